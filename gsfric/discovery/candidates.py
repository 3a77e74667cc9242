"""What the workflow may change: the model's own parameters and the catalog's candidate effects.

The model's own parameters (``REFIT``) are refitted first, each within a *plausible* range: a
wrong friction coefficient or payload mass is a wrong number, not a missing effect. Where the
refit can only explain the data with a value outside its range (a Coulomb coefficient of 1.5 in
a lubricated joint), the refit is held at the range's edge and the remaining gap is left to the
candidate effects.

There is one candidate per effect of the catalog (``CANDIDATES``, in the catalog's order): its
name, parameters, defaults and units are the catalog's (``gsfric.platform.catalog``, read from
the manifest). What is discovery's own is ``FITTING``, by effect: the physical bounds of the
fitted parameters, the parameters held fixed (set from the platform: the bushing spacing is the
platform's or the catalog's), and, for the parameters on which the model is strongly nonlinear,
a grid of starting values: ``stribeck.velocity`` (then fitted), the stroke reference (9 leg
lengths along the data's stroke; refined once the effect is named, ``Candidate.refined``).
Every other parameter of an effect is fitted; the first fitted one, in the catalog's order, is
the effect's amplitude.
"""

from __future__ import annotations

from collections.abc import Callable, Mapping
from dataclasses import dataclass, field, fields

import numpy as np

from gsfric.errors import GsfricError
from gsfric.platform import catalog
from gsfric.platform.description import Platform

INF = np.inf


@dataclass(frozen=True)
class Refit:
    """One of the model's own parameters and its plausible range.

    Attributes
    ----------
    name : str
        Jacobian parameter name (``prismatic_coulomb``, ``payload_mass``, ...).
    lower, upper : float
        Plausible range, in the parameter's unit; ``relative`` ranges are multiples of the
        model's value.
    relative : bool
        Whether ``lower`` and ``upper`` multiply the model's value.
    reason : str
        For the report.
    """

    name: str
    lower: float
    upper: float
    relative: bool = False
    reason: str = ""

    @property
    def unit(self) -> str:
        """The parameter's unit (``gsfric.platform.catalog.unit``)."""
        return catalog.unit(self.name)

    def bounds(self, value: float) -> tuple[float, float]:
        """The plausible range for a model whose value is ``value``."""
        if self.relative:
            return (self.lower * value, self.upper * value)
        return (self.lower, self.upper)


REFIT: tuple[Refit, ...] = (
    Refit("prismatic_viscous", 0.0, 50.0,
          reason="viscous friction of a lubricated actuator of this size"),
    Refit("prismatic_coulomb", 0.0, 0.3,
          reason="Coulomb coefficient of a lubricated sliding joint"),
    Refit("payload_mass", 0.5, 1.5, relative=True,
          reason="payload known to within 50%"),
)
"""Default plausible ranges of the refitted model parameters (override with ``plausible=``)."""


@dataclass(frozen=True)
class Fitting:
    """How discovery fits one catalog effect: everything of a candidate but what the catalog
    gives (its name, parameters, defaults and units).

    Attributes
    ----------
    signature : str
        Where the effect shows in the residuals (for the report).
    bounds : tuple of float
        Physical bounds (lower, upper) of every fitted parameter not in ``bounds_of``, in the
        parameter's unit.
    bounds_of : Mapping[str, tuple[float, float]]
        Physical bounds of single fitted parameters.
    held : tuple[str, ...]
        Parameters not fitted, set by ``fixed``.
    grid : Mapping[str, tuple[float, ...]]
        Starting values tried for parameters on which F is strongly nonlinear.
    coulomb : bool
        Whether the amplitude (the first fitted parameter) enters the non-negative Coulomb sum
        of the prismatic friction effects (columns by one-sided steps).
    signs : tuple of float
        Signs the amplitude may take (stroke_friction: both).
    fixed : Callable[[Platform, dict], dict]
        Values of the ``held`` parameters, from the platform and the data context
        (``{"mean_length": float}``).
    applies : Callable[[Platform], str | None]
        None if the candidate applies to the platform, else the reason why not.
    """

    signature: str
    bounds: tuple[float, float] = (0.0, INF)
    bounds_of: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    held: tuple[str, ...] = ()
    grid: Mapping[str, tuple[float, ...]] = field(default_factory=dict)
    coulomb: bool = False
    signs: tuple[float, ...] = (1.0,)
    fixed: Callable[[Platform, dict], dict] = lambda platform, context: {}
    applies: Callable[[Platform], str | None] = lambda platform: None
    grid_from: Callable[[dict], dict] = lambda context: {}
    simpler: int = 0
    """Rank in parsimony among indistinguishable candidates (lower: simpler, preferred)."""
    refined: tuple[str, ...] = ()
    """Grid parameters refined by Gauss-Newton once the effect is in the model (from the best
    grid value, within the grid's range): where the truth lies between two grid values, the
    grid's misfit would otherwise be left to another candidate."""
    secants: tuple[float, ...] = (1.0,)
    """Steps of the amplitude at which its one-sided (secant) columns are taken, for an
    amplitude on which F is nonlinear (``time_offset``: a delay of several samples shifts a
    friction step, which the derivative at zero delay does not describe)."""


@dataclass(frozen=True, kw_only=True)
class Candidate(Fitting):
    """A catalog effect as a candidate explanation of the gap: the catalog's effect with
    discovery's ``Fitting`` of it.

    Attributes
    ----------
    name : str
        Catalog (SPEC) effect name.
    parameters : Mapping[str, float]
        The catalog's parameters of the effect (short names, the catalog's order) and their
        defaults, in their units.
    units : Mapping[str, str]
        The catalog's unit of each parameter.
    """

    name: str
    parameters: Mapping[str, float]
    units: Mapping[str, str]

    def __post_init__(self) -> None:
        named = set(self.bounds_of) | set(self.held) | set(self.grid) | set(self.refined)
        unknown = sorted(named - set(self.parameters))
        if unknown:
            raise GsfricError(f"candidate {self.name}: {', '.join(unknown)} is not a parameter "
                              f"of the catalog's {self.name} ({', '.join(self.parameters)})")
        if not self.fitted:
            raise GsfricError(f"candidate {self.name}: every parameter is held or refined; "
                              "nothing is fitted")

    @property
    def fitted(self) -> tuple[str, ...]:
        """Parameters fitted, short names, in the catalog's order (the amplitude first)."""
        return tuple(p for p in self.parameters if p not in self.held + self.refined)

    @property
    def lower(self) -> tuple[float, ...]:
        """Physical lower bounds of the fitted parameters."""
        return tuple(self.bounds_of.get(p, self.bounds)[0] for p in self.fitted)

    @property
    def upper(self) -> tuple[float, ...]:
        """Physical upper bounds of the fitted parameters."""
        return tuple(self.bounds_of.get(p, self.bounds)[1] for p in self.fitted)

    def grids(self, context: dict) -> dict[str, tuple[float, ...]]:
        """Starting values of the grid parameters, the data-dependent ones included."""
        return {**self.grid, **self.grid_from(context)}

    @property
    def columns(self) -> list[str]:
        """Jacobian names of the fitted parameters."""
        return [f"{self.name}.{p}" for p in self.fitted]

    @property
    def refined_columns(self) -> list[str]:
        """Jacobian names of the fitted and the refined parameters."""
        return self.columns + [f"{self.name}.{p}" for p in self.refined]

    @property
    def stepped(self) -> bool:
        """Whether the screening column comes from one-sided steps (see the module docstring)."""
        return (self.coulomb or bool(self.grid) or self.grid_from({}) is None
                or self.secants != (1.0,))

    @property
    def amplitude(self) -> str:
        """The fitted parameter that scales the effect."""
        return self.fitted[0]


STROKE_REFERENCES = 9
"""Number of references of stroke friction tried, evenly spaced from the shortest to the
longest leg length of the data (ends included: steps of an eighth of the stroke)."""


def _stroke_ends(context: dict) -> dict | None:
    """References of stroke friction along the legs' stroke in the data, the ends included.

    At an end, a friction ``k (D - D_ref) sgn(v)`` growing from that end over the whole stroke
    is one effect (k >= 0 from the short end, k <= 0 from the long end). Inside the stroke the
    catalog's clamp of the Coulomb sum at zero makes the term a hinge: no friction on one side
    of the reference, friction growing with the distance from it on the other (the catalog's
    default reference, the mean leg length, is such a one). An end-only grid cannot describe a
    hinge inside the stroke; the grid's step of an eighth of the stroke leaves a hinge between
    two grid points a small misfit. None without data (marks a data-dependent grid)."""
    if "min_length" not in context:
        return None
    lo, hi = float(context["min_length"]), float(context["max_length"])
    return {"reference": tuple(float(v) for v in np.linspace(lo, hi, STROKE_REFERENCES))}


def _bushing_spacing(platform: Platform, context: dict) -> dict:
    """The spacing the effect is fitted at: its own where the platform's [effects] give one,
    else the rig's bushings' (``[friction] bushing_spacing``); the coefficient alone is fitted
    (only their ratio acts on the forces)."""
    own = platform.effects.get("bushing_friction", {})
    return {"spacing": float(own.get("spacing", platform.friction.bushing_spacing))}


def _coupled_applies(platform: Platform) -> str | None:
    """Joint friction carried by the actuators and bushing friction are part of the coupled
    friction model itself: there, a change of them is a refit of the model's own coefficients
    (``prismatic_coulomb`` is the bushings' coefficient), not a missing effect."""
    if platform.friction.model == "coupled":
        return ("part of the coupled friction model ([friction] model = \"coupled\"); its "
                "coefficients are refitted instead")
    return None


def _leg_weight_applies(platform: Platform) -> str | None:
    if platform.legs.weight:
        return "the model already has the legs' weight ([legs] weight = true)"
    return None


STRIBECK_VELOCITIES = tuple(float(v) for v in np.geomspace(0.002, 0.1, 6))
"""Starting values of the Stribeck velocity, m/s (those the data resolves, see below)."""

def stribeck_velocity_bound(upper: float, context: dict) -> float:
    """Largest Stribeck velocity (m/s) fitted on data with this context: ``upper``, lowered to
    the ``Settings.stribeck_quantile`` quantile of the sliding leg speeds
    (``context["sliding_speed"]``), never below the smallest starting value."""
    resolved = float(context.get("sliding_speed", np.inf))
    return float(max(min(upper, resolved), STRIBECK_VELOCITIES[0]))


def _stribeck_velocities(context: dict) -> dict | None:
    """The starting Stribeck velocities the data resolves (see ``Settings.stribeck_quantile``),
    the bound itself included when it cuts the list. None without data (a data-dependent
    grid)."""
    if "sliding_speed" not in context:
        return None
    bound = stribeck_velocity_bound(np.inf, context)
    values = [v for v in STRIBECK_VELOCITIES if v <= bound]
    if len(values) < len(STRIBECK_VELOCITIES) and bound not in values:
        values.append(bound)
    return {"velocity": tuple(values)}

TIME_OFFSET_STEPS = (0.002, 0.006, 0.018, 0.054, 0.162)
"""Delays (s) at which the secant columns of ``time_offset`` are taken, either sign (factors
of 3, from less than a sample at 200 Hz to about the shortest motion features); the best
secant starts the Gauss-Newton refinement."""

FITTING: dict[str, Fitting] = {
    "stribeck": Fitting(
        "friction-like (opposing the leg speed), concentrated at speed reversals",
        bounds_of={"velocity": (5e-4, 0.5)}, grid_from=_stribeck_velocities, coulomb=True,
        simpler=2),
    "seal_friction": Fitting(
        "friction-like, the same at every speed and load", coulomb=True, simpler=0),
    "quadratic_drag": Fitting(
        "friction-like, growing with the square of the leg speed"),
    "stroke_friction": Fitting(
        "friction-like, growing along the stroke from one end", bounds=(-INF, INF),
        grid_from=_stroke_ends, coulomb=True, signs=(1.0, -1.0), simpler=2,
        refined=("reference",)),
    "payload_offset": Fitting(
        "load-like, varying with the pose (moment of the payload's weight)",
        bounds=(-0.5, 0.5)),
    "sensor_bias": Fitting(
        "a constant offset per leg, in every regime", bounds=(-INF, INF)),
    "joint_friction_coupling": Fitting(
        "friction-like, from the joints' friction moments, largest at high load",
        applies=_coupled_applies),
    "leg_weight": Fitting(
        "load-like, varying with the legs' inclination", applies=_leg_weight_applies),
    "bushing_friction": Fitting(
        "friction-like, growing with the bending moment in the prismatic joint",
        held=("spacing",), fixed=_bushing_spacing, coulomb=True, simpler=1,
        applies=_coupled_applies),
    "force_scale": Fitting(
        "proportional to the measured force on each leg (a load cell's gain error)",
        bounds=(-0.5, 0.5), simpler=3),
    "time_offset": Fitting(
        "proportional to the rate of change of the force (a delay between the pose and force "
        "channels), largest where the force changes fastest",
        bounds=(-0.5, 0.5), simpler=1, signs=(1.0, -1.0), secants=TIME_OFFSET_STEPS),
}
"""How discovery fits each catalog effect, by effect name (the rest of a candidate is the
catalog's)."""


def _candidates() -> tuple[Candidate, ...]:
    """One candidate per catalog effect, in the catalog's order, with ``FITTING``'s settings."""
    entries = catalog.describe()
    missing = [e["name"] for e in entries if e["name"] not in FITTING]
    extra = sorted(set(FITTING) - {e["name"] for e in entries})
    if missing or extra:
        raise GsfricError("discovery's FITTING does not match the effect catalog: "
                          f"no settings for {missing}, settings for unknown effects {extra}")
    return tuple(_candidate(e, FITTING[e["name"]]) for e in entries)


def _candidate(entry: dict, fitting: Fitting) -> Candidate:
    """The candidate of one catalog entry (``catalog.describe()``) fitted by ``fitting``."""
    own = {f.name: getattr(fitting, f.name) for f in fields(Fitting)}
    return Candidate(name=entry["name"],
                     parameters={p["name"]: float(p["default"]) for p in entry["parameters"]},
                     units={p["name"]: p["unit"] for p in entry["parameters"]}, **own)


CANDIDATES: tuple[Candidate, ...] = _candidates()

SEPARATING_MOTION = {
    frozenset({"stribeck", "seal_friction"}):
        "slow moves (below the Stribeck velocity, a few mm/s) separate stribeck from "
        "seal_friction",
    frozenset({"seal_friction", "bushing_friction"}):
        "moves with large and small bending loads on the legs (tilted poses, payload off "
        "centre) separate bushing_friction from seal_friction",
    frozenset({"seal_friction", "stroke_friction"}):
        "moves over the whole stroke of each leg separate stroke_friction from seal_friction",
    frozenset({"force_scale", "payload_offset"}):
        "moves with large accelerations at one pose separate force_scale (scales inertial "
        "forces too) from payload_offset (weight only)",
    frozenset({"force_scale", "sensor_bias"}):
        "moves that change each leg's force over a wide range (fast vertical moves, tilts that "
        "shift the weight between the legs) separate force_scale (proportional to the force) "
        "from sensor_bias (constant)",
    frozenset({"time_offset", "quadratic_drag"}):
        "faster and slower repetitions of the same path separate a delay (time_offset) from a "
        "speed law (quadratic_drag)",
}
"""What motion separates two candidates the data could not tell apart (for the report)."""


def separating_motion(a: str, b: str) -> str:
    """A sentence on the motion that would separate candidates a and b."""
    return SEPARATING_MOTION.get(frozenset({a, b}),
                                 f"a motion that changes the ratio of the {a} and {b} "
                                 "signatures (see docs/reference/effects.md) separates them")

CANDIDATE_NAMES = tuple(c.name for c in CANDIDATES)
