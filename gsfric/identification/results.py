"""Results of an identification: each parameter's estimate, the identifiable combinations, the
fit's residual against the noise, and what the motion cannot reach."""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gsfric.identification.settings import MOVED_RTOL, TYPICAL
from gsfric.platform.description import Platform


def moved(value: float, prior: float, unit: str) -> bool:
    """Whether a parameter's value differs from its prior by more than the fit's rounding
    (``MOVED_RTOL`` of its size, ``max(|prior|, TYPICAL[unit])``)."""
    return abs(value - prior) > MOVED_RTOL * max(abs(prior), TYPICAL.get(unit, 1.0))


@dataclass
class Estimate:
    """One parameter's estimate.

    Attributes
    ----------
    value : float
        Estimate, in ``unit`` (the prior's value when not identifiable).
    std : float or None
        Standard deviation, in ``unit``; None when the data do not identify it.
    unit : str
    identifiable : bool
        Whether the data determine it on its own.
    prior : float
        The starting platform's value.
    """

    value: float
    std: float | None
    unit: str
    identifiable: bool
    prior: float

    @property
    def moved(self) -> bool:
        """Whether the fit moved it from the prior (``moved``)."""
        return moved(self.value, self.prior, self.unit)

    @property
    def rel_std(self) -> float | None:
        """std divided by the absolute value (None without a std; inf at a zero value)."""
        if self.std is None:
            return None
        return self.std / abs(self.value) if self.value != 0 else float("inf")

    def summary(self) -> dict:
        return {"value": self.value, "std": self.std, "rel_std": _finite(self.rel_std),
                "unit": self.unit, "identifiable": self.identifiable, "prior": self.prior}


@dataclass
class Combination:
    """An identifiable combination of parameters that are not identifiable alone (a base
    parameter), named by its expression, e.g. ``legs.upper_mass + 0.93 legs.lower_mass``.

    Attributes
    ----------
    value, std : float
        In ``unit`` (the leading parameter's).
    unit : str
    coefficients : dict[str, float]
        Parameter name -> coefficient (the leading one's is 1).
    """

    value: float
    std: float
    unit: str
    coefficients: dict[str, float]

    def summary(self) -> dict:
        return {"value": self.value, "std": self.std, "unit": self.unit,
                "identifiable": True, "coefficients": self.coefficients}


@dataclass
class Validation:
    """Prediction error on a second record.

    Attributes
    ----------
    before, after : ndarray, shape (6,)
        RMS of measured minus predicted actuator force per leg, N, with the prior platform and
        with the identified one.
    noise : ndarray, shape (6,)
        The identification's noise level per leg, N: "within the noise" is ``after`` near it.
    source : str
    flagged : int
        Steps of the record the prior's model flags, left out (as the fit leaves them out).
    """

    before: np.ndarray
    after: np.ndarray
    noise: np.ndarray
    source: str = ""
    flagged: int = 0

    def summary(self) -> dict:
        return {"source": self.source, "rms_before_N": self.before.tolist(),
                "rms_after_N": self.after.tolist(), "noise_N": self.noise.tolist(),
                "flagged_left_out": self.flagged}


@dataclass
class Identification:
    """What ``gsfric.identify`` found.

    Attributes
    ----------
    parameters : dict[str, Estimate]
        Every parameter of the fit by name (``gsfric.identification.parameters``).
    combinations : dict[str, Combination]
        Identifiable combinations of parameters not identifiable alone, by expression.
    correlation : ndarray, shape (q, q)
        Correlations of the identifiable parameters, in ``correlation_names``' order.
    correlation_names : list of str
    platform : Platform
        The identified platform (payload folded into ``[platform]``: the data see the sum).
    prior : Platform
    unreachable : list of str
        One line per parameter the motion cannot identify: why, and what motion would.
    weak : list of str
        One line per identifiable parameter whose std exceeds ``WEAK_RELATIVE_STD`` of its
        prior value: how far it moves a force along the motion against the noise, and what
        motion would determine it better.
    implausible : list of str
        Results no rig can have (a mass the data want negative): a non-empty list keeps the
        platform file from being written.
    misfit : list of str
        A line when the residual exceeds ``MISFIT_RATIO`` times the noise (given, or the
        forces' own high-frequency noise): the model does not reproduce the forces.
    residual : ndarray, shape (6,)
        RMS residual per leg after the fit, N.
    residual_prior : ndarray, shape (6,)
        RMS residual per leg of the prior platform, N.
    noise : ndarray, shape (6,)
        Force noise per leg, N: given, or estimated from the residual.
    noise_given : bool
    rank : int
        Number of identifiable directions (base parameters) out of ``len(parameters)``.
    condition : float
        Condition number of the column-normalised base regressor.
    samples : int
        Steps fitted.
    evaluations : int
        Residual evaluations of the nonlinear least squares.
    flagged : int
        Steps of the record that the prior's model flags (a leg outside the stroke, a pose near
        a singularity, the coupled friction solve not converged), left out of the fit: their
        forces are not the model's to reproduce.
    source, source_sha256 : str
        The measured file and its SHA-256 (empty for arrays).
    validation : Validation or None

    Examples
    --------
    >>> import gsfric
    >>> from gsfric.synth import synthesize
    >>> data = synthesize(samples=1000, rate=200.0, noise=0.5, seed=1)
    >>> result = gsfric.identify(data.motion, data.frame.filter(regex="^F").to_numpy())
    >>> mass = result.parameters["platform.mass"]
    >>> mass.unit, mass.identifiable, abs(mass.value - 13.0) < 5 * mass.std
    ('kg', True, True)
    """

    parameters: dict[str, Estimate]
    combinations: dict[str, Combination]
    correlation: np.ndarray
    correlation_names: list[str]
    platform: Platform
    prior: Platform
    unreachable: list[str]
    weak: list[str]
    implausible: list[str]
    residual: np.ndarray
    residual_prior: np.ndarray
    noise: np.ndarray
    noise_given: bool
    rank: int
    condition: float
    samples: int
    evaluations: int
    misfit: list[str] = field(default_factory=list)
    flagged: int = 0
    source: str = ""
    source_sha256: str = ""
    validation: Validation | None = field(default=None)

    def summary(self) -> dict:
        """The JSON-ready content of identification.json (units in the keys or fields)."""
        return {
            "source": self.source, "source_sha256": self.source_sha256,
            "samples": self.samples, "flagged_left_out": self.flagged, "rank": self.rank,
            "n_parameters": len(self.parameters), "condition_number": self.condition,
            "parameters": {n: e.summary() for n, e in self.parameters.items()},
            "combinations": {n: c.summary() for n, c in self.combinations.items()},
            "correlation": {"names": self.correlation_names,
                            "matrix": np.round(self.correlation, 6).tolist()},
            "residual_rms_N": self.residual.tolist(),
            "residual_rms_prior_N": self.residual_prior.tolist(),
            "noise_N": self.noise.tolist(),
            "noise": "given" if self.noise_given else "estimated from the residual",
            "unreachable": self.unreachable, "weak": self.weak,
            "implausible": self.implausible, "misfit": self.misfit,
            "validation": None if self.validation is None else self.validation.summary(),
            "evaluations": self.evaluations,
        }

    def statement(self) -> str:
        """A few lines for a reader: rank, residual against noise, what cannot be reached."""
        lines = [f"identified {self.rank} of {len(self.parameters)} directions "
                 f"(condition number {self.condition:.3g}); residual "
                 f"{np.sqrt(np.mean(self.residual ** 2)):.4g} N RMS (prior "
                 f"{np.sqrt(np.mean(self.residual_prior ** 2)):.4g} N) vs noise "
                 f"{np.sqrt(np.mean(self.noise ** 2)):.4g} N"]
        if self.flagged:
            lines.append(f"left out: {self.flagged} of {self.samples + self.flagged} steps the "
                         "prior's model flags (outside the stroke, near a singularity or an "
                         "unconverged friction solve; their flag in `gsfric simulate`)")
        lines += [f"not identifiable: {u}" for u in self.unreachable]
        lines += [f"weakly determined: {w}" for w in self.weak]
        lines += [f"implausible: {u}" for u in self.implausible]
        lines += [f"misfit: {u}" for u in self.misfit]
        return "\n".join(lines)


def _finite(value: float | None) -> float | None:
    """JSON has no infinity: None for it."""
    return None if value is None or not np.isfinite(value) else float(value)
