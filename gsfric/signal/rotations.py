"""Rotations: ZXZ angles, unit quaternions and rotation matrices, and the conversions between them.

Conventions: the orientation ``R`` maps platform-frame vectors to the base frame. In ZXZ angles,
``R = Rz(gamma) Rx(beta) Rz(alpha)``, whose entries are the paper's b_ij; this is
``scipy.spatial.transform.Rotation.from_euler("zxz", [alpha, beta, gamma])`` (extrinsic).
Quaternions are unit and scalar-first, ``(qw, qx, qy, qz)``, Hamilton product, mapping the
platform frame to the base frame. Angular velocity ``omega`` and acceleration ``alpha`` are
expressed in the base frame: ``dR/dt = [omega]x R``.
"""

from __future__ import annotations

import warnings

import numpy as np

from gsfric._optional import optional


def _scipy_rotation():
    """SciPy's ``Rotation`` class, loaded on first use (``gsfric._optional``)."""
    return optional("scipy.spatial.transform").Rotation

def rotation_defects(rotation: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """How far each of the (N, 3, 3) matrices is from a rotation: the largest entry of
    |R^T R - I| (N,) (the entries a NaN makes NaN left out) and the determinant (N,) (a
    rotation: 0 and 1). The test of ``gsfric.trajectory.first_non_rotation`` and of the
    compiled code's ``rotation_flag`` (gsfric/compiled/batch.c)."""
    e = np.ascontiguousarray(np.reshape(rotation, (-1, 9)).T)  # entry 3 i + j of every matrix
    col = [e[j::3] for j in range(3)]                          # column j: (3, N)
    error = np.zeros(e.shape[1])
    for j in range(3):                                         # the entries of R^T R - I
        for k in range(j, 3):
            gram = col[j][0] * col[k][0] + col[j][1] * col[k][1] + col[j][2] * col[k][2]
            error = np.fmax(error, np.abs(gram - (j == k)))
    a, b, c = col
    det = (a[0] * (b[1] * c[2] - b[2] * c[1]) - a[1] * (b[0] * c[2] - b[2] * c[0])
           + a[2] * (b[0] * c[1] - b[1] * c[0]))
    return error, det


def rotation_from_euler(alpha: np.ndarray | float, beta: np.ndarray | float,
                        gamma: np.ndarray | float) -> np.ndarray:
    """Rotation matrices ``Rz(gamma) Rx(beta) Rz(alpha)`` from ZXZ angles.

    Parameters
    ----------
    alpha, beta, gamma : array_like, shape (N,) (or broadcastable, or scalars)
        rad.

    Returns
    -------
    ndarray, shape (N, 3, 3)
        Entries are the paper's b_ij, e.g. ``b11 = cos(a)cos(g) - cos(b)sin(a)sin(g)``,
        ``b13 = sin(b)sin(g)``, ``b31 = sin(b)sin(a)``, ``b33 = cos(b)``.
    """
    a, b, g = np.broadcast_arrays(*(np.asarray(v, dtype=float) for v in (alpha, beta, gamma)))
    ca, sa, cb, sb, cg, sg = np.cos(a), np.sin(a), np.cos(b), np.sin(b), np.cos(g), np.sin(g)
    rows = [
        [ca * cg - cb * sa * sg, -sa * cg - cb * ca * sg, sb * sg],
        [ca * sg + cb * sa * cg, -sa * sg + cb * ca * cg, -sb * cg],
        [sb * sa, sb * ca, cb],
    ]
    return np.stack([np.stack(row, axis=-1) for row in rows], axis=-2)


def euler_from_rotation(rotation: np.ndarray) -> np.ndarray:
    """ZXZ angles ``(alpha, beta, gamma)`` of rotation matrices.

    Parameters
    ----------
    rotation : array_like, shape (N, 3, 3)

    Returns
    -------
    ndarray, shape (N, 3)
        alpha, gamma in (-pi, pi], beta in [0, pi], rad. Where sin(beta) vanishes (the level
        pose) only alpha + gamma (or alpha - gamma) is defined; there gamma = 0.
    """
    r = np.asarray(rotation, dtype=float)
    sin_beta = np.hypot(r[..., 0, 2], r[..., 1, 2])
    beta = np.arctan2(sin_beta, r[..., 2, 2])
    regular = sin_beta > 1e-12
    alpha = np.where(regular, np.arctan2(r[..., 2, 0], r[..., 2, 1]),
                     np.arctan2(np.sign(r[..., 2, 2]) * r[..., 1, 0], r[..., 0, 0]))
    gamma = np.where(regular, np.arctan2(r[..., 0, 2], -r[..., 1, 2]), 0.0)
    return np.stack([alpha, beta, gamma], axis=-1)


def quaternion_from_euler(alpha: np.ndarray | float, beta: np.ndarray | float,
                          gamma: np.ndarray | float) -> np.ndarray:
    """Unit quaternions ``(qw, qx, qy, qz)`` of ``Rz(gamma) Rx(beta) Rz(alpha)``, shape (N, 4)."""
    a, b, g = np.broadcast_arrays(*(np.asarray(v, dtype=float) / 2 for v in (alpha, beta, gamma)))
    zero = np.zeros_like(a)
    qa = np.stack([np.cos(a), zero, zero, np.sin(a)], axis=-1)
    qb = np.stack([np.cos(b), np.sin(b), zero, zero], axis=-1)
    qg = np.stack([np.cos(g), zero, zero, np.sin(g)], axis=-1)
    return quaternion_multiply(qg, quaternion_multiply(qb, qa))


def quaternion_from_rotation(rotation: np.ndarray) -> np.ndarray:
    """Unit quaternions ``(qw, qx, qy, qz)`` with qw >= 0 of rotation matrices.

    Parameters
    ----------
    rotation : array_like, shape (N, 3, 3)

    Returns
    -------
    ndarray, shape (N, 4)
    """

    r = np.asarray(rotation, dtype=float)
    xyzw = _scipy_rotation().from_matrix(r.reshape(-1, 3, 3)).as_quat()
    q = np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
    q *= np.where(q[:, :1] < 0, -1.0, 1.0)
    return q.reshape(r.shape[:-2] + (4,))


MIN_QUATERNION_LENGTH = 1e-12
"""A quaternion shorter than this is refused as of zero length: it gives no direction (an
empty or zeroed reading), whatever its scale."""


def unit_quaternions(quaternion: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Quaternions scaled to unit length, and their lengths, without overflow or underflow:
    each is divided by its largest component first, so a length of 1e200 (or 1e-200) is
    exact where the sum of squares would be infinite (or zero).

    Parameters
    ----------
    quaternion : array_like, shape (..., 4)

    Returns
    -------
    unit : ndarray, shape (..., 4)
        NaN for a zero or non-finite quaternion.
    length : ndarray, shape (...)
        0 for a zero quaternion; inf beyond the floating-point range.
    """
    q = np.asarray(quaternion, dtype=float)
    scale = np.max(np.abs(q), axis=-1, keepdims=True)
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        scaled = q / scale
        length = np.linalg.norm(scaled, axis=-1, keepdims=True)
        return scaled / length, np.where(scale[..., 0] == 0, 0.0, (length * scale)[..., 0])


def rotation_from_quaternion(quaternion: np.ndarray) -> np.ndarray:
    """Rotation matrices of quaternions ``(qw, qx, qy, qz)`` (normalized first).

    Parameters
    ----------
    quaternion : array_like, shape (N, 4)

    Returns
    -------
    ndarray, shape (N, 3, 3)
        Entries written one by one into the result (no intermediate stacks).
    """
    q = np.asarray(quaternion, dtype=float)
    w, x, y, z = np.moveaxis(unit_quaternions(q)[0], -1, 0)
    xx, yy, zz = x * x, y * y, z * z
    xy, xz, yz = x * y, x * z, y * z
    wx, wy, wz = w * x, w * y, w * z
    r = np.empty(q.shape[:-1] + (3, 3))
    r[..., 0, 0] = 1 - 2 * (yy + zz)
    r[..., 0, 1] = 2 * (xy - wz)
    r[..., 0, 2] = 2 * (xz + wy)
    r[..., 1, 0] = 2 * (xy + wz)
    r[..., 1, 1] = 1 - 2 * (xx + zz)
    r[..., 1, 2] = 2 * (yz - wx)
    r[..., 2, 0] = 2 * (xz - wy)
    r[..., 2, 1] = 2 * (yz + wx)
    r[..., 2, 2] = 1 - 2 * (xx + yy)
    return r


def quaternion_multiply(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    """Hamilton product ``p q`` of scalar-first quaternions, shape (N, 4)."""
    pw, pv = p[..., :1], p[..., 1:]
    qw, qv = q[..., :1], q[..., 1:]
    w = pw * qw - np.sum(pv * qv, axis=-1, keepdims=True)
    v = pw * qv + qw * pv + np.cross(pv, qv)
    return np.concatenate([w, v], axis=-1)


def continuous_quaternions(q: np.ndarray) -> np.ndarray:
    """Flip signs so that consecutive quaternions have a non-negative dot product."""
    dots = np.sum(q[1:] * q[:-1], axis=1)
    signs = np.concatenate([[1.0], np.cumprod(np.where(dots < 0, -1.0, 1.0))])
    return q * signs[:, None]


def angular_rates(q0: np.ndarray, q1: np.ndarray, q2: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray]:
    """Angular velocity and acceleration of a smoothed quaternion signal.

    With p = ``q0`` the (not exactly unit) quaternions and ``q1``, ``q2`` their first and
    second time derivatives, ``omega = 2 vec(q1 p*) / |p|^2`` and
    ``alpha = 2 vec(q2 p*) / |p|^2 - omega 2 (p . q1) / |p|^2``, which for a unit quaternion
    are ``omega = 2 vec(qdot q*)`` and ``alpha = 2 vec(qddot q*)``. The products are written
    out, ``vec(d p*) = w_p v_d - w_d v_p + v_p x v_d``, with the rounding of
    ``quaternion_multiply`` of d and the conjugate of p.

    Parameters
    ----------
    q0, q1, q2 : ndarray, shape (N, 4)
        Quaternions ``(qw, qx, qy, qz)`` and their derivatives, /s and /s^2.

    Returns
    -------
    omega, alpha : ndarray, shape (N, 3) each
        Base frame, rad/s and rad/s^2.
    """
    w0, v0 = q0[:, :1], q0[:, 1:]
    squared = np.sum(q0 * q0, axis=1, keepdims=True)
    dot01 = np.sum(q0 * q1, axis=1, keepdims=True)
    cross = np.empty((len(q0), 3))
    omega = _conjugate_product(w0, v0, q1, cross)
    omega *= 2
    omega /= squared
    alpha = _conjugate_product(w0, v0, q2, cross)
    alpha *= 2
    alpha /= squared
    damping = omega * 2
    damping *= dot01
    damping /= squared
    alpha -= damping
    return omega, alpha


def _conjugate_product(w0: np.ndarray, v0: np.ndarray, d: np.ndarray,
                       cross: np.ndarray) -> np.ndarray:
    """``vec(d p*)`` (N, 3) for p = (w0 (N, 1), v0 (N, 3)) and quaternions d (N, 4);
    ``cross`` (N, 3) is scratch."""
    out = w0 * d[:, 1:]
    out -= d[:, :1] * v0
    vd = d[:, 1:]
    for i, (j, k) in enumerate(((1, 2), (2, 0), (0, 1))):
        np.subtract(v0[:, j] * vd[:, k], v0[:, k] * vd[:, j], out=cross[:, i])
    out += cross
    return out


def rotation_from_rpy(angles: np.ndarray) -> np.ndarray:
    """Rotation matrices (N, 3, 3) ``R = Rz(yaw) Ry(pitch) Rx(roll)`` of angles (N, 3) rad,
    columns (roll, pitch, yaw): SciPy's ``Rotation.from_euler("ZYX", [yaw, pitch, roll])``
    (the convention "xyz" of ``LogFormat``), written out (six times faster at a million
    poses)."""
    c, s = np.cos(angles), np.sin(angles)
    (cr, cp, cy), (sr, sp, sy) = c.T, s.T
    out = np.empty((len(angles), 3, 3))
    out[:, 0, 0] = cy * cp
    out[:, 0, 1] = cy * sp * sr - sy * cr
    out[:, 0, 2] = cy * sp * cr + sy * sr
    out[:, 1, 0] = sy * cp
    out[:, 1, 1] = sy * sp * sr + cy * cr
    out[:, 1, 2] = sy * sp * cr - cy * sr
    out[:, 2, 0] = -sp
    out[:, 2, 1] = cp * sr
    out[:, 2, 2] = cp * cr
    return out


def rpy_from_rotation(rotation: np.ndarray) -> np.ndarray:
    """(roll, pitch, yaw) (N, 3) rad of rotations (N, 3, 3), ``R = Rz(yaw) Ry(pitch) Rx(roll)``;
    at gimbal lock (pitch = +-90 deg) roll is set to zero and yaw takes the whole angle."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", UserWarning)   # SciPy's gimbal-lock warning
        return _scipy_rotation().from_matrix(rotation).as_euler("ZYX")[:, ::-1]


def quaternion_from_rpy(angles: np.ndarray, convention: str = "xyz") -> np.ndarray:
    """Unit quaternions (w, x, y, z), (N, 4), of roll, pitch, yaw (N, 3) rad in SciPy's
    ``convention``: "xyz" extrinsic, ``R = Rz(yaw) Ry(pitch) Rx(roll)``; "XYZ" intrinsic,
    ``R = Rx(roll) Ry(pitch) Rz(yaw)``."""
    xyzw = _scipy_rotation().from_euler(convention, angles).as_quat()
    return np.concatenate([xyzw[:, 3:], xyzw[:, :3]], axis=1)
