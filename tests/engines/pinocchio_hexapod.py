"""Independent inverse-dynamics reference for the 6-UPS hexapod, built with Pinocchio.

Only NumPy arrays come in and go out; nothing from ``gsfric`` is used.

Model
-----
A kinematic tree is built for the evaluated state (``build_model``):

* the base is Pinocchio's universe; gravity is ``(0, 0, -gravity)``;
* the platform is a free-flyer body whose joint frame is the platform frame (origin ``position``,
  orientation ``rotation``); its inertia has mass ``platform_mass``, centre of mass
  ``platform_com`` and rotational inertia ``platform_inertia`` about that centre (platform frame);
* each leg i is a chain hanging from the universe:

  - ``leg{i}_u1``: revolute about the base-fixed axis a1_i, joint frame at C_i with the orientation
    of the leg body frame at the evaluated pose (``leg_frame``: x = a2, y = u x a2, z = u, where
    u = (E_i - C_i)/d_i and a2 = normalize(a1 x u));
  - ``leg{i}_u2``: revolute about the local x axis (a2, carried by the first joint); the lower
    part rides on it: mass ``lower_mass``, centre at ``lower_com`` along z, inertia
    ``lower_inertia`` (leg body frame);
  - ``leg{i}_p``: prismatic along the local z axis (u); its joint frame sits at distance d_i along
    z, so it coincides with E_i at the evaluated pose; the upper part rides on it: mass
    ``upper_mass``, centre at ``-upper_com`` along z (distance d_i - upper_com from C_i), inertia
    ``upper_inertia`` (leg body frame).

  The frame ``leg{i}_end`` (origin of ``leg{i}_p``) and the platform frame ``platform_E{i}``
  (E_i in the platform frame) are tied by a 3-D point closure: the spherical joint.

All leg joint coordinates are zero at the evaluated pose, so the leg joint angles are exactly
the inverse kinematics of the given platform pose.

Velocities and accelerations
----------------------------
The free-flyer velocity is Pinocchio's local one: ``v_ff = (R^T velocity, R^T omega)``. Its
acceleration is the time derivative of those local components:
``a_ff = (R^T acceleration - omega_l x v_l, R^T alpha)`` with ``v_l, omega_l`` the local
velocity parts. ``acceleration`` is the second time derivative of ``position``, i.e. the
classical acceleration of the platform frame origin (not of the centre of mass).

With J_c = J_end - J_E (linear, LOCAL_WORLD_ALIGNED frame Jacobians; 18 x 24) the leg rates solve
``J_c[:, legs] v_legs = -J_c[:, ff] v_ff``; the leg accelerations solve
``J_c[:, legs] a_legs = -(J_c[:, ff] a_ff + drift)``, where the term in brackets is the difference
of the two frames' classical accelerations computed with zero leg accelerations.

Forces
------
``tau = rnea(q, v, a)`` (24 generalized forces). The equations of motion with actuation and
closure forces are ``tau = S^T F + J_c^T lambda``; S selects the six prismatic coordinates and
lambda_i (base frame) is the force applied on the upper part of leg i at its end point, with
-lambda_i applied on the platform at E_i. The 24 x 24 linear system gives

* ``F[i]``: the prismatic joint's generalized force, i.e. the actuator force on the upper part
  along +u_i (positive pushes the platform away from the base);
* ``R_E[i] = -lambda_i``: force that leg i exerts on the platform at E_i (base frame).

``rnea`` is then run again with the closure forces as external forces. ``data.f`` of
``leg{i}_u1`` is the wrench that the base transmits to the leg through the universal joint,
expressed in that joint's frame at C_i:

* ``R_C[i]``: its force part, rotated to the base frame;
* ``M_C_vector[i]``: its moment part about C_i, rotated to the base frame. Its components along
  a1 and a2 are the (zero) generalized forces of the two revolute joints, so it is parallel to
  n_i = normalize(u_i - (u_i . a1_i) a1_i);
* ``M_C[i] = M_C_vector[i] . n_i``: the universal joint's constraint moment (torsion).

Friction (``inverse_dynamics(geom, state, friction)``): given friction wrenches are applied as
loads, nothing else changes. ``friction["MfrC"][i]`` (base frame, on the leg) acts in the
universal joint: its components along a1 and a2 are the generalized forces of the two revolute
joints (the joint's friction torques); ``friction["MfrE"][i]`` acts on the platform and its
reaction ``-MfrE`` on the upper part (external forces of both bodies);
``friction["Ffr"][i]`` acts on the upper part along u, so the prismatic joint's generalized force
is the actuator force plus it: ``F = tau_p - Ffr``. With friction the universal joint's moment
``M_C_vector`` has the friction torques along a1 and a2 besides the torsion along n.

Residuals returned: ``closure_position``, ``closure_velocity``, ``closure_acceleration`` (largest
norm of the point gap and its rates), ``solve_residual`` (largest deviation of the second rnea
from ``S^T F``) and ``moment_offaxis`` (largest norm of the part of ``M_C_vector`` not along n).
"""

import numpy as np
import pinocchio as pin

GEOM_KEYS = (
    "gravity",
    "base_joints",
    "platform_joints",
    "universal_axes",
    "platform_mass",
    "platform_inertia",
    "platform_com",
    "lower_mass",
    "lower_com",
    "lower_inertia",
    "upper_mass",
    "upper_com",
    "upper_inertia",
)
STATE_KEYS = ("position", "rotation", "velocity", "omega", "acceleration", "alpha")


def _unit(x):
    return x / np.linalg.norm(x)


def rotation_about(axis, angle):
    """Rotation matrix of ``angle`` about the unit vector ``axis`` (Rodrigues)."""
    k = np.asarray(axis, dtype=float)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + np.sin(angle) * K + (1.0 - np.cos(angle)) * K @ K


def leg_frame(a1, u):
    """Leg body frame (columns x = a2, y = u x a2, z = u) for base axis a1 and leg direction u."""
    a2 = _unit(np.cross(a1, u))
    return np.column_stack([a2, np.cross(u, a2), u])


def leg_geometry(geom, state):
    """Joint centres C (6,3), E (6,3) in the base frame, leg directions u (6,3), lengths d (6,)."""
    C = np.asarray(geom["base_joints"], dtype=float)
    E = state["position"] + np.asarray(geom["platform_joints"], dtype=float) @ state["rotation"].T
    d = np.linalg.norm(E - C, axis=1)
    u = (E - C) / d[:, None]
    return C, E, u, d


def build_model(geom, state):
    """Pinocchio model whose leg joint coordinates are zero at ``state``'s pose.

    Returns ``(model, ids)``; ``ids`` holds the joint ids (``platform``, ``u1``, ``u2``, ``p``),
    frame ids (``end``, ``E``) and velocity indices (``idx_u1``, ``idx_u2``, ``idx_p``).
    """
    C, _, u, d = leg_geometry(geom, state)
    a1 = np.asarray(geom["universal_axes"], dtype=float)
    Ep = np.asarray(geom["platform_joints"], dtype=float)

    model = pin.Model()
    model.gravity = pin.Motion(np.array([0.0, 0.0, -geom["gravity"], 0.0, 0.0, 0.0]))
    ff = model.addJoint(0, pin.JointModelFreeFlyer(), pin.SE3.Identity(), "platform")
    model.appendBodyToJoint(
        ff,
        pin.Inertia(
            float(geom["platform_mass"]),
            np.asarray(geom["platform_com"], dtype=float),
            np.asarray(geom["platform_inertia"], dtype=float),
        ),
        pin.SE3.Identity(),
    )
    lower = pin.Inertia(
        float(geom["lower_mass"]),
        np.array([0.0, 0.0, float(geom["lower_com"])]),
        np.asarray(geom["lower_inertia"], dtype=float),
    )
    upper = pin.Inertia(
        float(geom["upper_mass"]),
        np.array([0.0, 0.0, -float(geom["upper_com"])]),
        np.asarray(geom["upper_inertia"], dtype=float),
    )

    ids = {"platform": ff, "u1": [], "u2": [], "p": [], "end": [], "E": []}
    for i in range(6):
        R0 = leg_frame(a1[i], u[i])
        j1 = model.addJoint(
            0,
            pin.JointModelRevoluteUnaligned(R0.T @ _unit(a1[i])),
            pin.SE3(R0, C[i]),
            f"leg{i}_u1",
        )
        j2 = model.addJoint(j1, pin.JointModelRX(), pin.SE3.Identity(), f"leg{i}_u2")
        model.appendBodyToJoint(j2, lower, pin.SE3.Identity())
        j3 = model.addJoint(
            j2, pin.JointModelPZ(), pin.SE3(np.eye(3), np.array([0.0, 0.0, d[i]])), f"leg{i}_p"
        )
        model.appendBodyToJoint(j3, upper, pin.SE3.Identity())
        f_end = model.addFrame(
            pin.Frame(f"leg{i}_end", j3, pin.SE3.Identity(), pin.FrameType.OP_FRAME)
        )
        f_E = model.addFrame(
            pin.Frame(f"platform_E{i}", ff, pin.SE3(np.eye(3), Ep[i]), pin.FrameType.OP_FRAME)
        )
        for key, value in (("u1", j1), ("u2", j2), ("p", j3), ("end", f_end), ("E", f_E)):
            ids[key].append(value)
    for key in ("u1", "u2", "p"):
        ids["idx_" + key] = np.array([model.joints[j].idx_v for j in ids[key]])
    ids["idx_legs"] = np.arange(6, model.nv)
    return model, ids


def _configuration(model, state, q_legs=None):
    q = pin.neutral(model)
    q[:7] = pin.SE3ToXYZQUAT(pin.SE3(np.asarray(state["rotation"]), np.asarray(state["position"])))
    if q_legs is not None:
        q[7:] = np.asarray(q_legs, dtype=float).reshape(-1)
    return q


def _closure_jacobian(model, data, ids):
    J = np.zeros((18, model.nv))
    for i in range(6):
        J_end = pin.getFrameJacobian(model, data, ids["end"][i], pin.LOCAL_WORLD_ALIGNED)
        J_E = pin.getFrameJacobian(model, data, ids["E"][i], pin.LOCAL_WORLD_ALIGNED)
        J[3 * i : 3 * i + 3] = J_end[:3] - J_E[:3]
    return J


def _closure_gaps(model, data, ids):
    """Point gap, velocity gap and classical-acceleration gap (6,3) from the last kinematics."""
    gap = np.zeros((6, 3))
    dgap = np.zeros((6, 3))
    ddgap = np.zeros((6, 3))
    frame = pin.LOCAL_WORLD_ALIGNED
    for i in range(6):
        fe, fp = ids["end"][i], ids["E"][i]
        gap[i] = data.oMf[fe].translation - data.oMf[fp].translation
        dgap[i] = (
            pin.getFrameVelocity(model, data, fe, frame).linear
            - pin.getFrameVelocity(model, data, fp, frame).linear
        )
        ddgap[i] = (
            pin.getFrameClassicalAcceleration(model, data, fe, frame).linear
            - pin.getFrameClassicalAcceleration(model, data, fp, frame).linear
        )
    return gap, dgap, ddgap


def platform_twist(state):
    """Free-flyer velocity and acceleration (local components, Pinocchio's convention)."""
    R = np.asarray(state["rotation"], dtype=float)
    v_l = R.T @ state["velocity"]
    w_l = R.T @ state["omega"]
    a_l = R.T @ state["acceleration"] - np.cross(w_l, v_l)
    dw_l = R.T @ state["alpha"]
    return np.concatenate([v_l, w_l]), np.concatenate([a_l, dw_l])


def inverse_dynamics(geom, state, friction=None):
    """Actuator forces and joint reactions of the hexapod at one state (see module docstring).

    ``friction``: optional dict of friction loads, ``MfrE`` (6, 3) N m (on the platform),
    ``MfrC`` (6, 3) N m (on the leg), ``Ffr`` (6,) N (on the upper part along u), base frame.
    """
    state = {k: np.asarray(state[k], dtype=float) for k in STATE_KEYS}
    model, ids = build_model(geom, state)
    data = model.createData()
    legs = ids["idx_legs"]
    q = _configuration(model, state)
    v_ff, a_ff = platform_twist(state)

    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    J = _closure_jacobian(model, data, ids)
    J_legs = J[:, legs]

    v = np.zeros(model.nv)
    v[:6] = v_ff
    v[legs] = np.linalg.solve(J_legs, -J[:, :6] @ v_ff)

    a = np.zeros(model.nv)
    a[:6] = a_ff
    pin.forwardKinematics(model, data, q, v, a)
    pin.updateFramePlacements(model, data)
    _, _, acc_gap = _closure_gaps(model, data, ids)
    a[legs] = np.linalg.solve(J_legs, -acc_gap.reshape(-1))

    pin.forwardKinematics(model, data, q, v, a)
    pin.updateFramePlacements(model, data)
    gap, dgap, ddgap = _closure_gaps(model, data, ids)

    C, E, u, d = leg_geometry(geom, state)
    a1 = np.asarray(geom["universal_axes"], dtype=float)
    R = state["rotation"]
    fr_ext = pin.StdVec_Force()
    for _ in range(model.njoints):
        fr_ext.append(pin.Force.Zero())
    tau_joint = np.zeros(model.nv)
    F_slide = np.zeros(6)
    if friction is not None:
        MfrE = np.asarray(friction["MfrE"], float)
        MfrC = np.asarray(friction["MfrC"], float)
        F_slide = np.asarray(friction["Ffr"], float)
        platform_moment = np.zeros(3)
        for i in range(6):
            R_end = data.oMi[ids["p"][i]].rotation
            fr_ext[ids["p"][i]] = pin.Force(np.zeros(3), R_end.T @ -MfrE[i])
            platform_moment += R.T @ MfrE[i]
            a2 = _unit(np.cross(a1[i], u[i]))
            tau_joint[ids["idx_u1"][i]] = MfrC[i] @ _unit(a1[i])
            tau_joint[ids["idx_u2"][i]] = MfrC[i] @ a2
            tau_joint[ids["idx_p"][i]] = F_slide[i]
        fr_ext[ids["platform"]] = pin.Force(np.zeros(3), platform_moment)
    tau = pin.rnea(model, data, q, v, a, fr_ext).copy() - tau_joint
    A = np.zeros((model.nv, 24))
    A[ids["idx_p"], np.arange(6)] = 1.0
    A[:, 6:] = J.T
    x = np.linalg.solve(A, tau)
    F = x[:6]
    lam = x[6:].reshape(6, 3)
    R_E = -lam

    fext = pin.StdVec_Force()
    for j in range(model.njoints):
        fext.append(pin.Force(fr_ext[j]))
    Ep = np.asarray(geom["platform_joints"], dtype=float)
    f_platform = np.zeros(6)
    for i in range(6):
        R_end = data.oMi[ids["p"][i]].rotation
        fext[ids["p"][i]] = fext[ids["p"][i]] + pin.Force(R_end.T @ lam[i], np.zeros(3))
        f_local = R.T @ R_E[i]
        f_platform += np.concatenate([f_local, np.cross(Ep[i], f_local)])
    fext[ids["platform"]] = fext[ids["platform"]] + pin.Force(f_platform[:3], f_platform[3:])
    tau_ext = pin.rnea(model, data, q, v, a, fext).copy()
    tau_expected = tau_joint.copy()
    tau_expected[ids["idx_p"]] += F

    n = u - np.sum(u * a1, axis=1)[:, None] * a1
    n /= np.linalg.norm(n, axis=1)[:, None]
    R_C = np.zeros((6, 3))
    M_vec = np.zeros((6, 3))
    omega_leg = np.zeros((6, 3))
    alpha_leg = np.zeros((6, 3))
    for i in range(6):
        j1, j2 = ids["u1"][i], ids["u2"][i]
        R1 = data.oMi[j1].rotation
        R_C[i] = R1 @ data.f[j1].linear
        M_vec[i] = R1 @ data.f[j1].angular
        R2 = data.oMi[j2].rotation
        omega_leg[i] = R2 @ data.v[j2].angular
        alpha_leg[i] = R2 @ data.a[j2].angular
    M_C = np.sum(M_vec * n, axis=1)

    return {
        "F": F,
        "F_axial": F + F_slide,
        "R_E": R_E,
        "R_C": R_C,
        "M_C": M_C,
        "M_C_vector": M_vec,
        "C": C,
        "E": E,
        "u": u,
        "n": n,
        "d": d,
        "d_dot": v[ids["idx_p"]],
        "d_ddot": a[ids["idx_p"]],
        "q": q,
        "v": v,
        "a": a,
        "tau": tau,
        "v_legs": v[legs].reshape(6, 3),
        "a_legs": a[legs].reshape(6, 3),
        "omega_leg": omega_leg,
        "alpha_leg": alpha_leg,
        "closure_position": float(np.max(np.linalg.norm(gap, axis=1))),
        "closure_velocity": float(np.max(np.linalg.norm(dgap, axis=1))),
        "closure_acceleration": float(np.max(np.linalg.norm(ddgap, axis=1))),
        "solve_residual": float(np.max(np.abs(tau_ext - tau_expected))),
        "moment_offaxis": float(
            np.max(np.linalg.norm(M_vec - M_C[:, None] * n
                                  - (0.0 if friction is None else
                                     np.asarray(friction["MfrC"], float)), axis=1))
        ),
    }


def leg_coordinates(geom, ref_state, state):
    """Leg joint coordinates (6,3) of the model built at ``ref_state`` that match ``state``'s pose.

    Columns: angle about a1, angle about a2, length change d - d_ref.
    """
    a1 = np.asarray(geom["universal_axes"], dtype=float)
    _, _, u0, d0 = leg_geometry(geom, ref_state)
    _, _, u, d = leg_geometry(geom, state)
    out = np.zeros((6, 3))
    for i in range(6):
        k = _unit(a1[i])
        b0 = _unit(np.cross(k, u0[i]))
        b = _unit(np.cross(k, u[i]))
        q1 = np.arctan2(k @ np.cross(b0, b), b0 @ b)
        u1 = rotation_about(k, q1) @ u0[i]
        q2 = np.arctan2(b @ np.cross(u1, u[i]), u1 @ u[i])
        out[i] = (q1, q2, d[i] - d0[i])
    return out


def closure_gap(geom, ref_state, state, q_legs):
    """Largest closure gap of the model built at ``ref_state``, platform at ``state``'s pose."""
    model, ids = build_model(geom, ref_state)
    data = model.createData()
    q = _configuration(model, state, q_legs)
    pin.framesForwardKinematics(model, data, q)
    gaps = [
        data.oMf[ids["end"][i]].translation - data.oMf[ids["E"][i]].translation for i in range(6)
    ]
    return float(np.max(np.linalg.norm(gaps, axis=1)))


def symmetric_geometry(leg_mass=True):
    """Three-fold symmetric hexapod (base radius 0.5 m, platform radius 0.3 m, home height 0.6 m).

    Leg i joins the base joint at angle 120 k +/- 12.5 deg to the platform joint at
    120 k +/- 52.5 deg (k = i // 2). The universal joints' first axes are horizontal and tangent to
    the base circle. The platform's centre of mass lies on its z axis. With ``leg_mass=False`` the
    legs are massless.
    """
    base_deg = np.array([-12.5, 12.5, 107.5, 132.5, 227.5, 252.5])
    plat_deg = np.array([-52.5, 52.5, 67.5, 172.5, 187.5, 292.5])
    tb = np.radians(base_deg)
    tp = np.radians(plat_deg)
    base = np.column_stack([0.5 * np.cos(tb), 0.5 * np.sin(tb), np.zeros(6)])
    plat = np.column_stack([0.3 * np.cos(tp), 0.3 * np.sin(tp), np.zeros(6)])
    axes = np.column_stack([-np.sin(tb), np.cos(tb), np.zeros(6)])
    scale = 1.0 if leg_mass else 0.0
    return {
        "gravity": 9.81,
        "base_joints": base,
        "platform_joints": plat,
        "universal_axes": axes,
        "platform_mass": 40.0,
        "platform_inertia": np.diag([1.1, 1.1, 1.9]),
        "platform_com": np.array([0.0, 0.0, 0.05]),
        "lower_mass": 3.0 * scale,
        "lower_com": 0.18,
        "lower_inertia": np.diag([0.06, 0.06, 0.004]) * scale,
        "upper_mass": 2.0 * scale,
        "upper_com": 0.22,
        "upper_inertia": np.diag([0.035, 0.035, 0.002]) * scale,
    }


def home_state(height=0.6):
    """Platform at rest, level, its frame origin ``height`` above the base origin."""
    return {
        "position": np.array([0.0, 0.0, height]),
        "rotation": np.eye(3),
        "velocity": np.zeros(3),
        "omega": np.zeros(3),
        "acceleration": np.zeros(3),
        "alpha": np.zeros(3),
    }


def _random_inertia(rng, scale):
    """Symmetric positive-definite inertia satisfying the triangle inequalities."""
    principal = scale * rng.uniform(0.5, 1.0, 3)
    Q = rotation_about(_unit(rng.normal(size=3)), rng.uniform(0.0, np.pi))
    return Q @ np.diag(principal) @ Q.T


def random_geometry(rng):
    """``symmetric_geometry`` with perturbed joints, tilted axes and full (non-diagonal) inertias."""
    g = symmetric_geometry()
    g["base_joints"] = g["base_joints"] + rng.uniform(-0.02, 0.02, (6, 3))
    g["platform_joints"] = g["platform_joints"] + rng.uniform(-0.02, 0.02, (6, 3))
    axes = g["universal_axes"] + rng.uniform(-0.2, 0.2, (6, 3))
    g["universal_axes"] = axes / np.linalg.norm(axes, axis=1)[:, None]
    g["platform_mass"] = rng.uniform(20.0, 60.0)
    g["platform_inertia"] = _random_inertia(rng, 1.5)
    g["platform_com"] = rng.uniform(-0.05, 0.05, 3) + np.array([0.0, 0.0, 0.05])
    g["lower_mass"] = rng.uniform(1.0, 4.0)
    g["lower_com"] = rng.uniform(0.1, 0.3)
    g["lower_inertia"] = _random_inertia(rng, 0.05)
    g["upper_mass"] = rng.uniform(1.0, 3.0)
    g["upper_com"] = rng.uniform(0.1, 0.3)
    g["upper_inertia"] = _random_inertia(rng, 0.03)
    return g


def random_state(rng, height=0.6):
    """Random pose near the home pose with random velocities and accelerations."""
    axis = _unit(rng.normal(size=3))
    return {
        "position": np.array([0.0, 0.0, height]) + rng.uniform(-0.06, 0.06, 3),
        "rotation": rotation_about(axis, rng.uniform(-0.2, 0.2)),
        "velocity": rng.normal(scale=0.3, size=3),
        "omega": rng.normal(scale=0.5, size=3),
        "acceleration": rng.normal(scale=2.0, size=3),
        "alpha": rng.normal(scale=3.0, size=3),
    }
