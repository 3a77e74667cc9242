"""Evaluation of a platform over a motion: the reaction map, the friction map, both combined.

``Evaluator`` holds an immutable platform packed into the generated functions' parameter
vectors and calls the compiled functions; ``evaluate`` is the one-call form. Results are named
arrays with the step as the leading axis.

Step flags (bits of ``Result.flag``; 0 = sound step):

* 1 ``FLAG_NONFINITE``: a non-finite input or output value (outputs set to NaN);
* 2 ``FLAG_STROKE``: a leg length outside ``geometry.stroke``;
* 4 ``FLAG_SINGULAR``: the platform's 6x6 force Jacobian (columns ``(u_i, (E_i - p) x u_i)``)
  has a condition number above ``COND_LIMIT``: the axial forces are ill-determined;
* 8 ``FLAG_UNIVERSAL``: a leg within ``UNIVERSAL_LIMIT`` of the direction of its universal
  joint's first axis (``1 - (u.a1)^2 < UNIVERSAL_LIMIT``), where the joint's torsion moment is
  undefined;
* 16 ``FLAG_COUPLING``: the coupled friction model's fixed point has not converged: the axial
  forces changed by more than ``COUPLING_TOLERANCE * (1 N + |F0|)`` over the last of its
  iterations (joint friction so large that it nearly locks the mechanism; docs/friction.md).
"""

from __future__ import annotations

import warnings
from dataclasses import dataclass, field

import numpy as np

from gsfric import native
from gsfric.errors import GsfricError, InputError, StepFlagError
from gsfric.manifest import layout
from gsfric.platform import Platform
from gsfric.trajectory import Motion

FLAG_NONFINITE = 1
FLAG_STROKE = 2
FLAG_SINGULAR = 4
FLAG_UNIVERSAL = 8
FLAG_COUPLING = 16
FLAG_NAMES = {FLAG_NONFINITE: "non-finite value", FLAG_STROKE: "leg length outside the stroke",
              FLAG_SINGULAR: "near-singular platform Jacobian",
              FLAG_UNIVERSAL: "leg near its universal joint's first axis",
              FLAG_COUPLING: "coupled friction solve not converged"}
COUPLING_TOLERANCE = 1e-6
COND_LIMIT = 1e6
UNIVERSAL_LIMIT = 1e-4

JOINT_EPS = 1e-4       # rad/s, regularisation of the joints' sign function
PRISMATIC_EPS = 1e-5   # m/s, regularisation of the prismatic sign function
PRISMATIC_POINT = 0.5  # prismatic joint point, fraction of D from C_i (the paper's zone 3)

MODES = ("kinematic", "paper")
CHUNK = 200_000


def state_array(motion: Motion) -> np.ndarray:
    """The generated functions' state input, (N, 24): p, T (row-major), v, omega, a, alpha.

    This is the one place where the step-leading arrays of a Motion are laid out for C.
    """
    n = len(motion)
    return np.concatenate([motion.position, motion.rotation.reshape(n, 9), motion.velocity,
                           motion.omega, motion.acceleration, motion.alpha], axis=1)


def _pack(blocks: list[dict], values: dict) -> np.ndarray:
    size = sum(int(np.prod(b["shape"])) for b in blocks)
    out = np.zeros(size)
    for b in blocks:
        n = int(np.prod(b["shape"]))
        out[b["offset"]:b["offset"] + n] = np.ravel(values[b["name"]])
    return out


def parameter_values(platform: Platform) -> dict[str, object]:
    """The platform as the named blocks of the parameter input P (see the manifest's layout)."""
    g, b, legs, fr = platform.geometry, platform.platform, platform.legs, platform.friction
    l4, k4, l2, k2 = legs.com_placement()
    return dict(
        gravity=platform.gravity, base_joints=g.base_joints, platform_joints=g.platform_joints,
        universal_axes=g.universal_axes, platform_mass=b.mass, platform_inertia=b.inertia,
        platform_com=b.com, payload_mass=b.payload_mass, payload_inertia=b.payload_inertia,
        payload_com=b.payload_com, lower_mass=legs.lower_mass, lower_com=l4, lower_frac=k4,
        lower_inertia=legs.lower_inertia, upper_mass=legs.upper_mass, upper_com=l2,
        upper_frac=k2, upper_inertia=legs.upper_inertia, leg_weight=float(legs.weight),
        prismatic_point=PRISMATIC_POINT, joint_viscous=fr.joint_viscous,
        joint_coulomb=fr.joint_coulomb, joint_radius=fr.joint_radius,
        prismatic_viscous=fr.prismatic_viscous, prismatic_coulomb=fr.prismatic_coulomb,
        joint_eps=JOINT_EPS, prismatic_eps=PRISMATIC_EPS,
        friction_model=float(fr.model == "coupled"), bushing_offset=fr.bushing_offset,
        bushing_spacing=fr.bushing_spacing, prismatic_seal=fr.prismatic_seal)


def parameter_vector(platform: Platform) -> np.ndarray:
    """The platform packed into the generated functions' parameter input P."""
    return _pack(layout("eval", "P"), parameter_values(platform))


def effect_vector(platform: Platform) -> np.ndarray:
    """The platform's effects packed into the effect-parameter input Q (defaults elsewhere)."""
    from gsfric.catalog import EFFECTS

    values = []
    for name, params in EFFECTS.items():
        given = platform.effects.get(name, {})
        values += [float(given.get(p, default)) for p, default in params.items()]
    return np.array(values)


@dataclass
class Result:
    """Named arrays of one evaluation, step as the leading axis.

    Attributes (shapes for N steps; units SI): ``t`` (N,), ``F``, ``F0`` (N, 6) N;
    ``R_E``, ``R_C``, ``R_3`` (N, 6, 3) N; ``M_C`` (N, 6) N m; ``M_3`` (N, 6, 3) N m;
    ``MfrE``, ``MfrC`` (N, 6, 3) N m; ``Ffr`` (N, 6) N; the paper's signed scalars ``MfrE_s``,
    ``MfrC_s`` (N, 6) N m and ``Ffr_s`` (N, 6) N; ``D``, ``D_dot`` (N, 6); ``u``, ``omega_leg``,
    ``omega_rel``, ``R_3_leg``, ``M_3_leg`` (N, 6, 3); ``s2`` (N, 6); ``flag`` (N,) int.
    See the manifest for every output's description.
    """

    t: np.ndarray
    arrays: dict[str, np.ndarray]
    flag: np.ndarray
    mode: str = "kinematic"
    notes: list[str] = field(default_factory=list)
    source: tuple | None = field(default=None, repr=False)   # (platform, motion) evaluated

    def breakdown(self) -> dict[str, np.ndarray]:
        """F per leg split into inertia, gravity, payload, joint friction carried, prismatic
        friction by kind and effects, (N, 6) N each (``gsfric.breakdown``; kinematic mode)."""
        from gsfric.breakdown import breakdown

        if self.source is None or self.mode != "kinematic":
            raise GsfricError("breakdown: needs a kinematic-mode result of Evaluator.evaluate")
        platform, motion = self.source
        return breakdown(platform, motion, self)

    def __getattr__(self, name):
        arrays = self.__dict__.get("arrays", {})
        if name in arrays:
            return arrays[name]
        raise AttributeError(name)

    def __len__(self) -> int:
        return len(self.t)

    def flagged(self) -> np.ndarray:
        """Indices of the steps with a non-zero flag."""
        return np.flatnonzero(self.flag)

    def to_frame(self):
        """A pandas DataFrame with the columns of ``gsfric simulate`` (SPEC) and more."""
        import pandas as pd

        cols = {"t": self.t}
        for i in range(6):
            cols[f"F{i + 1}"] = self.F[:, i]
        for name in ("MfrE", "MfrC"):
            for i in range(6):
                cols[f"{name}{i + 1}"] = self.arrays[f"{name}_s"][:, i]
        for i in range(6):
            cols[f"Ffr{i + 1}"] = self.Ffr_s[:, i]
        for name, key in (("RE", "R_E"), ("RC", "R_C")):
            for i in range(6):
                for j, ax in enumerate("xyz"):
                    cols[f"{name}{ax}{i + 1}"] = self.arrays[key][:, i, j]
        for i in range(6):
            cols[f"MC{i + 1}"] = self.M_C[:, i]
        for i in range(6):
            cols[f"F0_{i + 1}"] = self.F0[:, i]
            cols[f"D{i + 1}"] = self.D[:, i]
        # signed friction (docs/friction.md): the force on the rod along u (negative while the
        # leg extends), the joint moments' vectors (base frame), the joint friction carried
        for name, key in (("FfrS", "Ffr"), ("Fjoint", "F_joint")):
            if key in self.arrays:
                for i in range(6):
                    cols[f"{name}{i + 1}"] = self.arrays[key][:, i]
        for key in ("MfrE", "MfrC"):
            for i in range(6):
                for j, ax in enumerate("xyz"):
                    cols[f"{key}{ax}{i + 1}"] = self.arrays[key][:, i, j]
        cols["flag"] = self.flag
        return pd.DataFrame(cols)


class Evaluator:
    """A compiled evaluator of one platform; owns its packed parameters.

    Parameters
    ----------
    platform : Platform
    mode : {"kinematic", "paper"}
        "kinematic": every acceleration from the motion; "paper": the paper's constant
        accelerations and joint speed (``paper_constants``) instead.
    n_threads : int
        OpenMP threads for long evaluations.
    paper_constants : ndarray (13,), optional
        Paper mode's constants (default ``gsfric.models.paper_constants()``).
    """

    def __init__(self, platform: Platform, mode: str = "kinematic", n_threads: int = 1,
                 paper_constants=None) -> None:
        if mode not in MODES:
            raise InputError(f"mode: unknown mode {mode!r}; expected one of {', '.join(MODES)}")
        self.platform = platform
        self.mode = mode
        self.n_threads = int(n_threads)
        self.P = parameter_vector(platform)
        self.Q = effect_vector(platform)
        self.K = None
        if mode == "paper":
            from gsfric.models import paper_constants as pc

            self.K = np.asarray(pc() if paper_constants is None else paper_constants, float)
        self._full = native.get("eval_paper" if mode == "paper" else "eval")
        self._stroke = platform.geometry.stroke
        self._actuator = None

    # -- hot paths -------------------------------------------------------------
    def actuator_forces(self, x: np.ndarray, out: np.ndarray | None = None, P=None,
                        Q=None) -> np.ndarray:
        """Actuator forces with friction, (N, 6) N, for states x (N, 24) (``state_array``).

        ``P`` and ``Q`` may be given per step, (N, size), to vary parameters along the batch.
        No flags, no checks beyond shapes: the control loop's call.
        """
        if self.mode != "kinematic":
            raise GsfricError("actuator_forces is the kinematic mode's hot path")
        if P is None and Q is None and out is not None:
            if self._actuator is None:
                self._actuator = native.get("actuator").bound([self.P, self.Q], "F",
                                                              self.n_threads)
            return self._actuator(x, out)
        f = native.get("actuator")
        res = f([x, self.P if P is None else P, self.Q if Q is None else Q],
                None if out is None else {"F": out}, self.n_threads)
        return res["F"]

    def jacobian(self, x: np.ndarray, Q=None) -> tuple[np.ndarray, np.ndarray]:
        """F (N, 6) and dF/dtheta (N, 6, n_theta); theta names in ``jacobian_parameters()``."""
        res = native.get("jacobian")([x, self.P, self.Q if Q is None else Q], None,
                                     self.n_threads)
        n = x.shape[0]
        # CasADi stores the (6, n_theta) Jacobian column-major
        return res["F"], res["dF"].reshape(n, -1, 6).transpose(0, 2, 1)

    # -- full evaluation -------------------------------------------------------------
    def evaluate(self, motion: Motion, strict: bool = False, progress: bool = False,
                 chunk: int = CHUNK) -> Result:
        """Every output at every step of ``motion``, with step flags.

        Parameters
        ----------
        motion : Motion
        strict : bool
            Raise StepFlagError instead of warning when steps are flagged.
        progress : bool
            Show a progress bar (tqdm) over chunks.
        chunk : int
            Steps per call to the compiled code (bounds the temporary memory).
        """
        x = state_array(motion)
        n = x.shape[0]
        outs = {name: np.empty((n, size)) for name, size, _ in self._full.outputs}
        inputs = [self.P, self.Q] + ([self.K] if self.K is not None else [])
        starts = range(0, n, chunk)
        if progress and n > chunk:
            from tqdm import tqdm

            starts = tqdm(starts, total=(n + chunk - 1) // chunk, unit="chunk",
                          desc="evaluating")
        for s in starts:
            e = min(n, s + chunk)
            view = {k: v[s:e] for k, v in outs.items()}
            self._full([x[s:e]] + inputs, view, self.n_threads)
        shapes = {name: shape for name, _, shape in self._full.outputs}
        arrays = {k: v.reshape((n,) + tuple(shapes[k])) for k, v in outs.items()}
        flag = self._flags(x, motion, arrays)
        result = Result(t=np.asarray(motion.t, float), arrays=arrays, flag=flag, mode=self.mode,
                        source=(self.platform, motion))
        bad = result.flagged()
        if bad.size:
            kinds = sorted({FLAG_NAMES[b] for b in FLAG_NAMES if np.any(flag & b)})
            msg = (f"{bad.size} of {n} steps flagged ({'; '.join(kinds)}): steps "
                   f"{_index_list(bad)}")
            if strict:
                raise StepFlagError(msg)
            warnings.warn(msg, stacklevel=2)
        return result

    def _flags(self, x, motion, arrays) -> np.ndarray:
        n = x.shape[0]
        flag = np.zeros(n, dtype=np.int64)
        finite = np.isfinite(x).all(axis=1)
        for v in arrays.values():
            finite &= np.isfinite(v.reshape(n, -1)).all(axis=1)
        # the geometric causes first, on the values as computed (a NaN compares False), so
        # that a step made non-finite by one of them still names it
        D = arrays["D"]
        if self._stroke is not None:
            lo, hi = self._stroke
            out = ((D < lo) | (D > hi)).any(axis=1)
            flag[out] |= FLAG_STROKE
        flag[(arrays["s2"] < UNIVERSAL_LIMIT).any(axis=1)] |= FLAG_UNIVERSAL
        if "coupling_change" in arrays:
            limit = COUPLING_TOLERANCE * (1.0 + np.abs(arrays["F0"]))
            flag[(np.abs(arrays["coupling_change"]) > limit).any(axis=1)] |= FLAG_COUPLING
        u = arrays["u"]
        arm = np.einsum("nij,kj->nki", motion.rotation, self.platform.geometry.platform_joints)
        A = np.concatenate([u, np.cross(arm, u)], axis=2)  # (N, 6 legs, 6)
        known = np.isfinite(A).all(axis=(1, 2))  # otherwise FLAG_NONFINITE says it
        with np.errstate(invalid="ignore", divide="ignore"):
            cond = np.linalg.cond(np.where(known[:, None, None], A, np.eye(6)))
        flag[known & ~(cond < COND_LIMIT)] |= FLAG_SINGULAR
        flag[~finite] |= FLAG_NONFINITE
        if (~finite).any():
            for v in arrays.values():
                v[~finite] = np.nan
        return flag


def _index_list(idx: np.ndarray, limit: int = 10) -> str:
    shown = ", ".join(str(i) for i in idx[:limit])
    return shown + (f", ... ({idx.size - limit} more)" if idx.size > limit else "")


def jacobian_parameters() -> list[str]:
    """Names of the Jacobian's parameters: friction coefficients, masses, then every effect's."""
    from gsfric.manifest import manifest

    return list(manifest()["jacobian_parameters"])


def evaluate(platform: Platform, motion: Motion, mode: str = "kinematic", **kwargs) -> Result:
    """Evaluate ``platform`` over ``motion``; see ``Evaluator.evaluate``."""
    return Evaluator(platform, mode=mode).evaluate(motion, **kwargs)
