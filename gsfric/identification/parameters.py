"""The parameters an identification estimates, and the platform they stand for.

A ``ParameterSet`` lists, for a prior platform, the parameters theta that act on the actuator
forces, each with its name, unit, bounds and place in the compiled model's inputs (P, Q, the
load cells' gains):

* the moving body (platform and payload together: the motion sees only their sum), as its ten
  standard inertial parameters, on which the forces depend linearly: ``platform.mass`` (kg),
  ``platform.first_moment.x|y|z`` (mass times centre of mass, platform frame, kg m) and
  ``platform.inertia_origin.xx|xy|xz|yy|yz|zz`` (inertia about the platform frame origin,
  platform frame, kg m^2);
* the legs' part masses ``legs.lower_mass``, ``legs.upper_mass`` (kg) and, for the rigid leg
  model, their first moments ``legs.lower_first_moment`` (mass times the centre's distance from
  C_i) and ``legs.upper_first_moment`` (from E_i), kg m; the legs' inertias stay at the prior's;
* the friction coefficients ``friction.*`` (>= 0; ``joint_radius`` only scales
  ``joint_coulomb``, so it stays fixed, as do the bushings' places);
* the parameters of the platform's generated effects, ``effects.NAME.PARAM``, and when asked the
  load cells' offsets ``effects.sensor_bias.b1..b6`` (N) and gains
  ``effects.force_scale.g1..g6`` (1).

Physical consistency of the body is built in: the fit moves the log-Cholesky factor of its
4x4 pseudo-inertia ``[[0.5 tr(I) 1 - I, h], [h^T, m]]``, which is positive definite exactly when
the mass is positive and the inertia positive definite with the triangle inequalities
(``body_from_factor``); every other parameter has bounds.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from gsfric.evaluation.parameters import (effect_vector, jacobian_parameters, pack_parameters,
                                          parameter_values)
from gsfric.platform import catalog
from gsfric.platform.description import Platform

BODY = ("platform.mass", "platform.first_moment.x", "platform.first_moment.y",
        "platform.first_moment.z", "platform.inertia_origin.xx", "platform.inertia_origin.xy",
        "platform.inertia_origin.xz", "platform.inertia_origin.yy", "platform.inertia_origin.yz",
        "platform.inertia_origin.zz")
"""Names of the body's standard inertial parameters, in theta's order."""

BODY_UNITS = ("kg",) + ("kg m",) * 3 + ("kg m^2",) * 6

FRICTION = ("joint_viscous", "joint_coulomb", "prismatic_viscous", "prismatic_coulomb",
            "prismatic_seal")
"""The platform's friction coefficients the fit estimates."""

SIGNED = ("payload_offset.", "sensor_bias.", "force_scale.", "stroke_friction.slope")
"""Effect parameters that may be negative (every other one is >= 0)."""

_UPPER = [(0, 0), (0, 1), (0, 2), (1, 1), (1, 2), (2, 2)]


@dataclass(frozen=True)
class Parameter:
    """One estimated parameter.

    Attributes
    ----------
    name : str
        Dotted name (a platform-file key, or a documented one for the body's and legs'
        standard parameters).
    unit : str
    lower, upper : float
        Bounds of the fit.
    kind : {"body", "leg", "P", "Q", "gain"}
        Where it acts: the body's standard parameters, a leg part, a block of P, an entry of Q,
        a load cell's gain.
    key : str or int
        The P block's name, the Q index, the body or leg index, or the gain's leg.
    jacobian : int or None
        Column of the compiled ``jacobian`` function giving dF/dparameter, if it has one.
    """

    name: str
    unit: str
    lower: float
    upper: float
    kind: str
    key: object
    jacobian: int | None = None


@dataclass
class ParameterSet:
    """The parameters of an identification around a prior platform.

    Attributes
    ----------
    platform : Platform
        The prior (its values are the starting point and hold what the data cannot reach).
    parameters : list of Parameter
    prior : ndarray, shape (p,)
        theta of the prior platform, in the parameters' units.
    """

    platform: Platform
    parameters: list[Parameter]
    prior: np.ndarray
    _values: dict = field(repr=False, default_factory=dict)
    _Q: np.ndarray = field(repr=False, default=None)

    @property
    def names(self) -> list[str]:
        return [p.name for p in self.parameters]

    @property
    def units(self) -> list[str]:
        return [p.unit for p in self.parameters]

    def bounds(self) -> tuple[np.ndarray, np.ndarray]:
        """Lower and upper bounds of theta, (p,) each."""
        return (np.array([p.lower for p in self.parameters]),
                np.array([p.upper for p in self.parameters]))

    def inputs(self, theta: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The compiled model's P (118,) and Q (20,) and the load cells' gains (6,) for theta
        (no checks: a finite-difference step may leave the physical set)."""
        values = dict(self._values)
        Q = self._Q.copy()
        gains, _ = catalog.sensor_parameters(self.platform.effects)
        body = np.array([theta[i] for i, p in enumerate(self.parameters) if p.kind == "body"])
        if body.size:
            mass, com, inertia = body_blocks(body)
            values.update(platform_mass=mass, platform_com=com, platform_inertia=inertia,
                          payload_mass=0.0, payload_com=np.zeros(3),
                          payload_inertia=np.zeros((3, 3)))
        legs = {p.key: theta[i] for i, p in enumerate(self.parameters) if p.kind == "leg"}
        for part in ("lower", "upper"):
            if f"{part}_mass" in legs:
                values[f"{part}_mass"] = legs[f"{part}_mass"]
            if f"{part}_first_moment" in legs:
                mass = legs[f"{part}_mass"]
                values[f"{part}_com"] = legs[f"{part}_first_moment"] / mass if mass > 0 else 0.0
        for value, p in zip(theta, self.parameters):
            if p.kind == "P":
                values[p.key] = value
            elif p.kind == "Q":
                Q[p.key] = value
            elif p.kind == "gain":
                gains = gains.copy()
                gains[p.key] = value
        return pack_parameters(values), Q, gains

    def platform_of(self, theta: np.ndarray) -> Platform:
        """The platform with theta's values (the checks of a ``Platform`` apply)."""
        t = dict(zip(self.names, np.asarray(theta, float)))
        out = self.platform
        if BODY[0] in t:
            mass, com, inertia = body_blocks(np.array([t[n] for n in BODY]))
            out = out.with_body(mass=mass, com=com, inertia=inertia, payload_mass=0.0,
                                payload_com=np.zeros(3), payload_inertia=np.zeros((3, 3)))
        legs = {}
        for part in ("lower", "upper"):
            mass = t.get(f"legs.{part}_mass")
            if mass is not None:
                legs[f"{part}_mass"] = mass
                moment = t.get(f"legs.{part}_first_moment")
                if moment is not None:
                    legs[f"{part}_com"] = moment / mass if mass > 0 else 0.0
        friction = {n: t[f"friction.{n}"] for n in FRICTION if f"friction.{n}" in t}
        effects = {k: dict(v) for k, v in out.effects.items()}
        for name, value in t.items():
            if name.startswith("effects."):
                effect, param = name.split(".")[1:]
                effects.setdefault(effect, dict(catalog.EFFECTS[effect]))[param] = value
        return out.with_legs(**legs).with_friction(**friction).with_effects(effects)


def parameter_set(platform: Platform, *, sensors: bool = False) -> ParameterSet:
    """The parameters to estimate for ``platform`` (see the module docstring); ``sensors`` adds
    the load cells' offsets and gains."""
    jac = {name: k for k, name in enumerate(jacobian_parameters())}
    params = [Parameter(n, u, 0.0 if n == BODY[0] else -np.inf, np.inf, "body", k)
              for k, (n, u) in enumerate(zip(BODY, BODY_UNITS))]
    parts = ("lower", "upper")
    for part in parts:
        params.append(Parameter(f"legs.{part}_mass", "kg", 0.0, np.inf, "leg", f"{part}_mass"))
        if platform.legs.model == "rigid":
            params.append(Parameter(f"legs.{part}_first_moment", "kg m", 0.0, np.inf, "leg",
                                    f"{part}_first_moment"))
    for name in FRICTION:
        params.append(Parameter(f"friction.{name}", catalog.PLATFORM_UNITS[f"friction.{name}"],
                                0.0, np.inf, "P", name, jac.get(name)))
    effects = [e for e in platform.effects if e in catalog.GENERATED_EFFECTS]
    if sensors and "sensor_bias" not in effects:
        effects.append("sensor_bias")
    names = catalog.parameter_names()
    for effect in effects:
        for param in catalog.GENERATED_EFFECTS[effect]:
            flat = f"{effect}.{param}"
            lower = -np.inf if flat.startswith(SIGNED) else 0.0
            params.append(Parameter(f"effects.{flat}", catalog.unit(flat), lower, np.inf, "Q",
                                    names.index(flat), jac.get(flat)))
    if sensors:
        params += [Parameter(f"effects.force_scale.g{i + 1}", "1", -1.0, np.inf, "gain", i)
                   for i in range(6)]
    out = ParameterSet(platform, params, np.zeros(len(params)), parameter_values(platform),
                       effect_vector(platform))
    out.prior = _prior(out)
    return out


def _prior(ps: ParameterSet) -> np.ndarray:
    """theta of the prior platform."""
    p = ps.platform
    legs = p.legs
    gains, _ = catalog.sensor_parameters(p.effects)
    known = dict(zip(BODY, body_standard(p)))
    known.update({"legs.lower_mass": legs.lower_mass, "legs.upper_mass": legs.upper_mass,
                  "legs.lower_first_moment": legs.lower_mass * legs.lower_com,
                  "legs.upper_first_moment": legs.upper_mass * legs.upper_com})
    out = []
    for q in ps.parameters:
        if q.kind in ("body", "leg"):
            out.append(known[q.name])
        elif q.kind == "P":
            out.append(float(getattr(p.friction, q.key)))
        elif q.kind == "Q":
            out.append(float(ps._Q[q.key]))
        else:
            out.append(float(gains[q.key]))
    return np.array(out, float)


def _skew_square(c: np.ndarray) -> np.ndarray:
    """|c|^2 1 - c c^T: the inertia of a unit point mass at c about the origin."""
    return float(c @ c) * np.eye(3) - np.outer(c, c)


def body_standard(platform: Platform) -> np.ndarray:
    """The moving body's (platform and payload) ten standard parameters: m, m c (3) and the
    inertia about the platform frame origin (xx, xy, xz, yy, yz, zz), platform frame."""
    b = platform.platform
    mass = b.mass + b.payload_mass
    moment = b.mass * b.com + b.payload_mass * b.payload_com
    inertia = (b.inertia + b.mass * _skew_square(b.com) + b.payload_inertia
               + b.payload_mass * _skew_square(b.payload_com))
    return np.array([mass, *moment, *(inertia[i, j] for i, j in _UPPER)])


def body_blocks(pi: np.ndarray) -> tuple[float, np.ndarray, np.ndarray]:
    """Mass (kg), centre of mass (3,) m and inertia about it (3, 3) kg m^2, platform frame, of
    the standard parameters ``pi`` (10,); a zero mass gives a centre at the origin."""
    mass = float(pi[0])
    com = np.asarray(pi[1:4], float) / mass if mass > 0 else np.zeros(3)
    inertia = np.empty((3, 3))
    for value, (i, j) in zip(pi[4:], _UPPER):
        inertia[i, j] = inertia[j, i] = value
    return mass, com, inertia - mass * _skew_square(com)


def pseudo_inertia(pi: np.ndarray) -> np.ndarray:
    """The 4x4 pseudo-inertia ``[[0.5 tr(I) 1 - I, h], [h^T, m]]`` of standard parameters
    (positive definite exactly for a physically consistent body)."""
    inertia = body_blocks(np.r_[1.0, 0.0, 0.0, 0.0, pi[4:]])[2]
    J = np.empty((4, 4))
    J[:3, :3] = 0.5 * np.trace(inertia) * np.eye(3) - inertia
    J[:3, 3] = J[3, :3] = pi[1:4]
    J[3, 3] = pi[0]
    return J


def factor_of_body(pi: np.ndarray) -> np.ndarray:
    """The log-Cholesky coordinates (10,) of a consistent body's standard parameters: the
    upper-triangular U with ``U U^T`` its pseudo-inertia, diagonal as logarithms."""
    flip = np.eye(4)[::-1]
    U = flip @ np.linalg.cholesky(flip @ pseudo_inertia(pi) @ flip) @ flip
    rows, cols = np.triu_indices(4)
    values = U[rows, cols]
    diagonal = rows == cols
    values[diagonal] = np.log(np.abs(values[diagonal]))
    return values


def body_from_factor(u: np.ndarray) -> np.ndarray:
    """Standard parameters (10,) of log-Cholesky coordinates ``u`` (10,): always a physically
    consistent body (positive mass, positive-definite inertia obeying the triangle
    inequalities)."""
    rows, cols = np.triu_indices(4)
    values = np.array(u, float)
    diagonal = rows == cols
    values[diagonal] = np.exp(values[diagonal])
    U = np.zeros((4, 4))
    U[rows, cols] = values
    return body_of_pseudo_inertia(U @ U.T)


def body_of_pseudo_inertia(J: np.ndarray) -> np.ndarray:
    """Standard parameters (10,) of a 4x4 pseudo-inertia (the inverse of ``pseudo_inertia``)."""
    inertia = np.trace(J[:3, :3]) * np.eye(3) - J[:3, :3]
    return np.array([J[3, 3], *J[:3, 3], *(inertia[i, j] for i, j in _UPPER)])


def nearest_consistent(pi: np.ndarray, floor: float = 1e-6) -> np.ndarray:
    """A consistent body near ``pi``: its pseudo-inertia's eigenvalues raised to ``floor``
    times the largest (a start for the fit when the prior is not consistent, or barely)."""
    w, v = np.linalg.eigh(pseudo_inertia(pi))
    return body_of_pseudo_inertia((v * np.maximum(w, floor * max(w.max(), 1e-3))) @ v.T)


FACTOR_BOUNDS = (-25.0, 10.0)
"""Bounds of the log-Cholesky factor's logarithmic diagonal: a factor of e^-25 to e^10
(masses and inertias from 1e-22 to 5e8 in SI units) spans every rig and keeps the fit's steps
finite."""


def factor_bounds() -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper bounds (10,) of the log-Cholesky coordinates."""
    rows, cols = np.triu_indices(4)
    diagonal = rows == cols
    return (np.where(diagonal, FACTOR_BOUNDS[0], -np.inf),
            np.where(diagonal, FACTOR_BOUNDS[1], np.inf))


def consistent(pi: np.ndarray) -> bool:
    """Whether standard parameters describe a physical body (positive-definite pseudo-inertia)."""
    return bool(np.linalg.eigvalsh(pseudo_inertia(pi)).min() > 0)
