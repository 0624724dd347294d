"""Unit quaternions, scalar first (w, x, y, z), rotating body vectors into the inertial frame.

Other libraries' orders (scipy and rerun use scalar last) are converted only at their
boundary, with `to_xyzw` / `from_xyzw`.
"""
from __future__ import annotations

import numpy as np


def multiply(p, q):
    """Hamilton product p ⊗ q for arrays of shape (..., 4)."""
    p = np.asarray(p, float)
    q = np.asarray(q, float)
    pw, px, py, pz = np.moveaxis(p, -1, 0)
    qw, qx, qy, qz = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            pw * qw - px * qx - py * qy - pz * qz,
            pw * qx + px * qw + py * qz - pz * qy,
            pw * qy - px * qz + py * qw + pz * qx,
            pw * qz + px * qy - py * qx + pz * qw,
        ],
        axis=-1,
    )


def conjugate(q):
    q = np.asarray(q, float)
    return q * np.array([1.0, -1.0, -1.0, -1.0])


def normalize(q):
    q = np.asarray(q, float)
    return q / np.linalg.norm(q, axis=-1, keepdims=True)


def rotate(q, v):
    """Rotate body vectors v (..., 3) into the inertial frame: v' = q v q*."""
    q = np.asarray(q, float)
    v = np.asarray(v, float)
    w = q[..., :1]
    u = q[..., 1:]
    t = 2.0 * np.cross(u, v)
    return v + w * t + np.cross(u, t)


def rotate_inverse(q, v):
    """Inertial vectors v (..., 3) expressed in the body frame: v_body = q* v q."""
    return rotate(conjugate(q), v)


def to_matrix(q):
    """Rotation matrix (..., 3, 3) whose columns are the body axes in the inertial frame."""
    q = normalize(q)
    w, x, y, z = np.moveaxis(q, -1, 0)
    return np.stack(
        [
            np.stack([1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)], -1),
            np.stack([2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)], -1),
            np.stack([2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)], -1),
        ],
        axis=-2,
    )


def from_axis_angle(axis, angle):
    axis = np.asarray(axis, float)
    axis = axis / np.linalg.norm(axis, axis=-1, keepdims=True)
    half = 0.5 * np.asarray(angle, float)[..., None]
    return np.concatenate([np.cos(half), np.sin(half) * axis], axis=-1)


def angle_between(p, q):
    """Rotation angle (rad) of p* ⊗ q, the attitude error between two quaternions."""
    # 2·acos(w) loses precision near w = 1; the atan2 form does not.
    r = multiply(conjugate(normalize(p)), normalize(q))
    return 2.0 * np.arctan2(np.linalg.norm(r[..., 1:], axis=-1), np.abs(r[..., 0]))


def to_xyzw(q):
    """Scalar-last order (scipy.spatial.transform.Rotation, rerun)."""
    q = np.asarray(q, float)
    return np.concatenate([q[..., 1:], q[..., :1]], axis=-1)


def from_xyzw(q):
    q = np.asarray(q, float)
    return np.concatenate([q[..., 3:], q[..., :3]], axis=-1)


IDENTITY = np.array([1.0, 0.0, 0.0, 0.0])
