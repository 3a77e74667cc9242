"""The catalog of optional effects: the one list of their names, parameters, defaults and units.

Every generated effect is a symbolic term always present in the generated functions, with its
parameters as inputs; the parameters switch it on (all defaults leave the model unchanged). The
names are a contract of the platform files and the command line; the parameters are documented here and in
docs/reference/effects.md.

Prismatic-joint friction effects add to the friction force on the upper part ``F_fr`` (along u,
opposing the sliding speed v, with the regularised sign of friction.py):

* ``stribeck``: ``-sgn(v) static exp(-(v / velocity)^2)``: a friction peak at low speed.
* ``seal_friction``: ``-sgn(v) force``: load-independent Coulomb friction of the seals.
* ``quadratic_drag``: ``-coefficient v |v|``.
* ``stroke_friction``: ``-sgn(v) slope (D - reference)``: friction varying along the stroke.

The Coulomb parts of these effects are summed and the sum is kept non-negative (friction never
pushes), so ``stroke_friction`` alone is clamped at zero where ``slope (D - reference) < 0``.
* ``bushing_friction``: ``-sgn(v) coefficient 2 |u x M_3| / spacing``: the bending moment M_3 of the
  prismatic joint presses its two bushings, ``spacing`` apart, with forces ``|M_3,perp| / spacing``
  each; ``coefficient`` is their friction coefficient.

Effects on the loads:

* ``payload_offset``: the payload's centre of mass moves by (x, y, z) in the platform frame.
* ``leg_weight``: gravity on the leg parts with masses (lower_mass, upper_mass), for a model with
  ``[legs] weight = false``.
* ``joint_friction_coupling``: the friction moments of the spherical and universal joints enter
  the equilibrium of legs and platform (scaled by ``scale``; 1 = fully), so the actuators carry
  them.

And on the reading: ``sensor_bias``: a constant offset b_i in each force reading F_i.

``CATALOG`` is the one list of every effect, of two kinds (``Effect.kind``):

* ``"generated"``: the terms above, inputs ``Q`` of the generated functions (``Q`` holds their
  parameters in catalog order, ``parameter_names``);
* ``"sensor"``: errors of the measuring chain that the runtime applies to the model's actuator
  forces F (gsfric/platform/catalog.py, ``apply_sensor``); they are not inputs ``Q``:

  - ``force_scale``: a gain error g_i of each load cell, ``F_i -> (1 + g_i) F_i``;
  - ``time_offset``: the force channels lag the pose channels by ``delay``,
    ``F(t) -> F(t - delay)``.

derive/build.py writes the whole catalog into generated/manifest.json, from which the runtime
reads every effect's name, parameters, defaults, units and descriptions.
"""

from dataclasses import dataclass

import sympy as sp

from .vectors import cross, norm

GENERATED = "generated"
"""Kind of an effect that is a term of the mechanics: its parameters are inputs Q."""

SENSOR = "sensor"
"""Kind of an effect of the measuring chain, applied by the runtime to F: not an input Q."""


@dataclass(frozen=True)
class Parameter:
    """One parameter of an effect.

    Attributes
    ----------
    name : str
        Short name, unique within its effect (``static``); the flat name is ``effect.name``.
    default : float
        Value that leaves the model unchanged (or a neutral dimension), in ``unit``.
    unit : str
        SI unit ("1" for a ratio).
    description : str
        What the number is, for ``gsfric effects`` and the docs.
    """

    name: str
    default: float
    unit: str
    description: str


@dataclass(frozen=True)
class Effect:
    """One optional effect.

    Attributes
    ----------
    name : str
        Effect name (``stribeck``), a contract of the platform files and the command line.
    description : str
        One line on what it is.
    term : str
        The term it adds, in plain text (``F_fr`` the prismatic friction force on the upper
        part along the leg, ``v`` the sliding speed, ``F_i`` leg i's actuator force).
    parameters : tuple of Parameter
        Its parameters, in the order they take in Q (generated effects).
    kind : str
        ``GENERATED`` (a term of the mechanics, parameters in Q) or ``SENSOR`` (applied by the
        runtime to F, not in Q).
    """

    name: str
    description: str
    term: str
    parameters: tuple[Parameter, ...]
    kind: str = GENERATED


CATALOG: tuple[Effect, ...] = (
    Effect("stribeck", "low-speed friction peak in the prismatic joints",
           "F_fr += -sgn(v) static exp(-(v/velocity)^2)", (
        Parameter("static", 0.0, "N", "height of the friction peak at zero speed"),
        Parameter("velocity", 0.01, "m/s", "Stribeck velocity: speed at which the peak decays by 1/e"),
    )),
    Effect("seal_friction", "load-independent Coulomb friction in the prismatic joints",
           "F_fr += -sgn(v) force", (
        Parameter("force", 0.0, "N", "Coulomb force of the seals"),
    )),
    Effect("quadratic_drag", "prismatic friction growing with v abs(v)",
           "F_fr += -coefficient v abs(v)", (
        Parameter("coefficient", 0.0, "N s^2/m^2", "drag coefficient"),
    )),
    Effect("stroke_friction", "prismatic friction varying along the stroke",
           "F_fr += -sgn(v) slope (D - reference)", (
        Parameter("slope", 0.0, "N/m", "change of Coulomb force per metre of leg length"),
        Parameter("reference", 0.0, "m", "leg length at which the change is zero"),
    )),
    Effect("payload_offset", "payload centre of mass away from its nominal position",
           "payload centre of mass += (x, y, z) (platform frame)", (
        Parameter("x", 0.0, "m", "offset along the platform's x axis"),
        Parameter("y", 0.0, "m", "offset along the platform's y axis"),
        Parameter("z", 0.0, "m", "offset along the platform's z axis"),
    )),
    Effect("sensor_bias", "constant offset in each force reading",
           "F_i += b_i", tuple(
        Parameter(f"b{i}", 0.0, "N", f"offset of F{i}") for i in range(1, 7)
    )),
    Effect("joint_friction_coupling",
           "friction moments of the spherical and universal joints carried by the actuators",
           "joint friction moments (33)-(34) enter the equilibrium, times scale", (
               Parameter("scale", 0.0, "1", "fraction of the joint friction moments included"),
           )),
    Effect("leg_weight", "weight of the leg parts, for a model without it",
           "gravity on mass lower_mass at the lower part's centre, upper_mass at the upper "
           "part's", (
        Parameter("lower_mass", 0.0, "kg", "mass whose weight acts at the lower part's centre"),
        Parameter("upper_mass", 0.0, "kg", "mass whose weight acts at the upper part's centre"),
    )),
    Effect("bushing_friction", "prismatic friction from the bushing forces of the moment M_3",
           "F_fr += -sgn(v) coefficient 2 norm(u x M_3) / spacing", (
        Parameter("coefficient", 0.0, "1", "friction coefficient of the bushings"),
        Parameter("spacing", 0.1, "m", "distance between the two bushings"),
    )),
    Effect("force_scale", "gain error of each load cell",
           "F_i -> (1 + g_i) F_i", tuple(
        Parameter(f"g{i}", 0.0, "1", f"relative gain error of load cell {i}")
        for i in range(1, 7)
    ), kind=SENSOR),
    Effect("time_offset", "delay of the force channels behind the pose channels",
           "F(t) -> F(t - delay)", (
               Parameter("delay", 0.0, "s", "delay of the force readings behind the poses"),
           ), kind=SENSOR),
)
"""Every effect, generated ones first (in the order of Q), then the sensor effects."""


def generated() -> tuple[Effect, ...]:
    """The effects whose parameters are the input Q, in Q's order."""
    return tuple(e for e in CATALOG if e.kind == GENERATED)


def parameter_names() -> list[str]:
    """Flat names ``effect.parameter`` in the order of the effect-parameter input Q.

    Returns
    -------
    list of str
        One name per entry of Q (``len(Q)`` names), e.g. ``"stribeck.static"``.
    """
    return [f"{e.name}.{p.name}" for e in generated() for p in e.parameters]


def prismatic_effects_force(q: dict, v, sgn_v, D, u, M_3):
    """Sum of the catalog's friction forces on the upper part along u (the terms above).

    Parameters
    ----------
    q : dict
        Effect parameter name (``parameter_names``) -> symbol, in the catalog's units.
    v : sympy.Expr
        Sliding speed, m/s.
    sgn_v : sympy.Expr
        Regularised sign of v, 1.
    D : sympy.Expr
        Leg length, m.
    u : sympy.Matrix, shape (3, 1)
        Unit leg direction, base frame, 1.
    M_3 : sympy.Matrix, shape (3, 1)
        Moment of the prismatic joint on the upper part, base frame, N m.

    Returns
    -------
    sympy.Expr
        Force along u on the upper part, N (opposing v).
    """
    level = (q["stribeck.static"] * sp.exp(-(v / q["stribeck.velocity"]) ** 2)
             + q["seal_friction.force"]
             + q["stroke_friction.slope"] * (D - q["stroke_friction.reference"])
             + q["bushing_friction.coefficient"] * 2 * norm(cross(u, M_3))
             / q["bushing_friction.spacing"])
    # max(0, level), with the derivative of level where level is 0: the parameters, zero by
    # default, grow the force from there (a max's derivative at the tie would be half of it,
    # and whether a level such as a Stribeck term far above its speed is 0 or a subnormal
    # number depends on the exp of the build)
    coulomb = sp.Piecewise((level, level >= 0), (0, True))
    return -sgn_v * coulomb - q["quadratic_drag.coefficient"] * v * sp.Abs(v)
