"""Batched rotations: the SO(3) exponential map and approach frames for suction grasps.

A grasp frame is a rotation whose columns are (x, y, z) with z = v, the approach direction
(pointing from the gripper into the object). x fixes the phase of the cup's perimeter ring and
the axes of the contact wrench basis.
"""

from __future__ import annotations

import numpy as np


def so3_exp(omega: np.ndarray) -> np.ndarray:
    """Rotation matrices exp([omega]x) for rotation vectors omega of shape (..., 3) (Rodrigues)."""
    omega = np.asarray(omega, dtype=float)
    theta = np.linalg.norm(omega, axis=-1)[..., None, None]
    k = skew(omega)
    small = theta < 1e-8
    safe = np.where(small, 1.0, theta)
    a = np.where(small, 1.0 - theta**2 / 6.0, np.sin(safe) / safe)
    b = np.where(small, 0.5 - theta**2 / 24.0, (1.0 - np.cos(safe)) / safe**2)
    eye = np.broadcast_to(np.eye(3), k.shape)
    return eye + a * k + b * (k @ k)


def skew(w: np.ndarray) -> np.ndarray:
    """Cross-product matrices [w]x of shape (..., 3, 3)."""
    w = np.asarray(w, dtype=float)
    out = np.zeros(w.shape[:-1] + (3, 3))
    out[..., 0, 1], out[..., 0, 2] = -w[..., 2], w[..., 1]
    out[..., 1, 0], out[..., 1, 2] = w[..., 2], -w[..., 0]
    out[..., 2, 0], out[..., 2, 1] = -w[..., 1], w[..., 0]
    return out


def normalize(v: np.ndarray) -> np.ndarray:
    """Unit vectors along the last axis."""
    v = np.asarray(v, dtype=float)
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def approach_frames(approach: np.ndarray, reference: np.ndarray | None = None) -> np.ndarray:
    """Frames (N, 3, 3) with z = approach and x = the reference projected onto the cup plane.

    Where the reference is (nearly) parallel to the approach or missing, x falls back to the
    world axis least aligned with the approach, so every frame is defined. A reference that moves
    with the object (e.g. the direction to its centre of mass) makes the frames, and so the
    labels, invariant to rigid motions of object and grasp together.
    """
    z = normalize(np.atleast_2d(approach))
    fallback = np.eye(3)[np.argmin(np.abs(z), axis=1)]
    ref = fallback if reference is None else np.broadcast_to(np.asarray(reference, float), z.shape)
    x = ref - np.einsum("ij,ij->i", ref, z)[:, None] * z
    norm = np.linalg.norm(x, axis=1)
    weak = norm < 1e-6 * np.maximum(np.linalg.norm(ref, axis=1), 1e-12)
    if np.any(weak):
        fb = fallback[weak] - np.einsum("ij,ij->i", fallback[weak], z[weak])[:, None] * z[weak]
        x[weak] = fb
        norm[weak] = np.linalg.norm(fb, axis=1)
    x = x / norm[:, None]
    y = np.cross(z, x)
    return np.stack([x, y, z], axis=-1)
