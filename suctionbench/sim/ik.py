"""Damped-least-squares (DLS) inverse kinematics for any site of a compiled MuJoCo model.

Why our own solver instead of mink or another IK package: the problem here is one site and at
most 7 joints, for which a DLS loop over `mj_jacSite` is short, needs no extra dependency (mink
brings a QP-solver stack), solves in about a millisecond, and is deterministic: no solver
tolerances, threads or hidden randomness, so the same model, inputs and `data` state give the
same joints bit for bit, which the pick episodes and their logs rely on.

Each iteration solves J dq = e in the damped least-squares sense (via the SVD of J), which stays
bounded near singularities; the step is scaled down to at most `max_step` rad per joint, a pull
toward an optional rest configuration is added in the exact null space of the task, and joints
that a step would push through their limits are frozen for that step (then everything is
clamped to the limits). A descent that stops improving ends early; optional restarts from
seeded random configurations handle the local minima of far-away targets. Two tasks:

* `solve_ik`: full 6-D pose; error = (position, rotation vector of R_target R^T, the log map
  computed with mju_mat2Quat + mju_quat2Vel).
* `solve_ik_position_axis` (or `solve_ik(..., axis_only=True)`): position and the direction of
  the site's z axis only, a 5-D task. A suction cup is symmetric about its axis, so rotation
  about the axis is free; leaving it free gives the arm one more redundant degree of freedom
  for reach and joint limits. The rotational error is the cross product of the current and
  target z axes (scaled to the angle between them), expressed along the site's x and y axes:
  the missing third component, rotation about the z axis itself, is exactly the one the task
  must not constrain.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace

import mujoco
import numpy as np

DEFAULT_DAMPING = 0.02
"""DLS damping (in units of the Jacobian: m and rad): keeps steps bounded near singularities while
barely slowing convergence where the arm is well conditioned (singular values ~0.1-1)."""

DEFAULT_MAX_STEP = 0.2
"""Largest change of any joint in one iteration (rad): far from the target the linearisation is
poor, so long steps overshoot and oscillate."""

DEFAULT_REST_WEIGHT = 0.1
"""Fraction of the distance to the rest configuration pulled back per iteration (null space only)."""

STALL_ITERS = 30
"""A descent stops early once its error (in units of the tolerances) has not dropped by
STALL_PROGRESS for this many iterations: it is stuck in a local minimum or against joint limits,
and the remaining iterations are better spent on a restart."""

STALL_PROGRESS = 0.01
"""Relative drop of the error that counts as progress for STALL_ITERS."""


@dataclass(frozen=True)
class IKResult:
    """Outcome of an IK solve."""

    q: np.ndarray
    """Joint values (rad) in the order of `joint_names`: the solution, or the closest configuration
    found when `success` is False."""
    success: bool
    """Whether both errors are within the tolerances."""
    pos_error: float
    """Distance (m) from the site to the target position at `q`."""
    rot_error: float
    """Angle (rad) between the site's and the target's orientation (full pose) or z axes (axis task)."""
    iterations: int
    """Number of DLS steps taken."""


# A rotational task maps the site's rotation matrix R (3x3, columns = site axes in the world) and
# its rotational Jacobian Jr (3 x n) to (error vector, its Jacobian, error angle in rad).
RotationTask = Callable[[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray, float]]


def _pose_task(target_rot: np.ndarray) -> RotationTask:
    """Full orientation: error = rotation vector of R_target R^T (world frame), via quaternions,
    which stay well defined up to and including a half turn."""
    quat = np.empty(4)
    rotvec = np.empty(3)

    def task(rot: np.ndarray, jac_rot: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        mujoco.mju_mat2Quat(quat, (target_rot @ rot.T).ravel())
        mujoco.mju_quat2Vel(rotvec, quat, 1.0)
        return rotvec.copy(), jac_rot, float(np.linalg.norm(rotvec))

    return task


def _axis_task(target_axis: np.ndarray) -> RotationTask:
    """Direction of the site's z axis only (5-D task together with the position)."""

    def task(rot: np.ndarray, jac_rot: np.ndarray) -> tuple[np.ndarray, np.ndarray, float]:
        axis = rot[:, 2]
        cross = np.cross(axis, target_axis)
        sin_angle = float(np.linalg.norm(cross))
        angle = float(np.arctan2(sin_angle, float(axis @ target_axis)))
        # Aligned (zero error) or opposite axes: turn about the site's x axis, any normal will do.
        omega = cross * (angle / sin_angle) if sin_angle > 1e-12 else rot[:, 0] * angle
        normals = rot[:, :2].T  # the site's x and y axes span the constrained rotations
        return normals @ omega, normals @ jac_rot, angle

    return task


def solve_ik(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    site_name: str,
    joint_names: Sequence[str],
    target_pos,
    target_rot,
    q_init,
    *,
    axis_only: bool = False,
    pos_tol: float = 1e-4,
    rot_tol: float = 1e-3,
    max_iters: int = 200,
    damping: float = DEFAULT_DAMPING,
    rest=None,
    rest_weight: float = DEFAULT_REST_WEIGHT,
    max_step: float = DEFAULT_MAX_STEP,
    restarts: int = 0,
    seed: int = 0,
) -> IKResult:
    """Joint values of `joint_names` that put site `site_name` at `target_pos` (3,) with
    orientation `target_rot` (3x3 rotation matrix, site axes as columns in the world frame).

    With `axis_only`, only the direction of the site's z axis is constrained (see
    `solve_ik_position_axis`); `target_rot` may then be that axis (3,) or a rotation matrix
    whose third column is used.

    Starts from `q_init` and never leaves the joint limits. `rest` (joint values), if given, is
    approached in the task's null space with gain `rest_weight` per iteration, which picks one
    solution among the redundant ones. If the descent from `q_init` fails, up to `restarts`
    further descents start from configurations drawn uniformly within the joint limits by
    `numpy.random.default_rng(seed)` (still deterministic); the default, no restarts, suits
    tracking a path, where a solution far from the previous waypoint would be a jump.
    `data` is used as scratch space: its qpos is restored, and its kinematics recomputed,
    before returning, so a running simulation is unaffected.
    """
    target_rot = np.asarray(target_rot, dtype=float)
    if axis_only:
        axis = target_rot[:, 2] if target_rot.shape == (3, 3) else target_rot
        norm = np.linalg.norm(axis)
        if axis.shape != (3,) or not norm > 0:
            raise ValueError(f"target axis must be a non-zero 3-vector, got {target_rot!r}")
        task = _axis_task(axis / norm)
    elif target_rot.shape == (3, 3):
        task = _pose_task(target_rot)
    else:
        raise ValueError(f"target_rot must be a 3x3 rotation matrix, got shape {target_rot.shape}")

    site_id = model.site(site_name).id
    qpos_adr, dof_adr = _joint_addresses(model, joint_names)
    lower, upper = _joint_limits(model, joint_names)
    n = len(joint_names)
    target_pos = np.asarray(target_pos, dtype=float)
    q_init = np.asarray(q_init, dtype=float)
    if target_pos.shape != (3,) or q_init.shape != (n,):
        raise ValueError(f"target_pos must have shape (3,) and q_init ({n},), "
                         f"got {target_pos.shape} and {q_init.shape}")
    rest_q = None if rest is None else np.asarray(rest, dtype=float)
    if rest_q is not None and rest_q.shape != (n,):
        raise ValueError(f"rest must have shape ({n},), got {rest_q.shape}")

    descend = _Descent(model, data, site_id, qpos_adr, dof_adr, lower, upper, target_pos, task,
                       pos_tol=pos_tol, rot_tol=rot_tol, max_iters=max_iters, damping=damping,
                       rest=rest_q, rest_weight=rest_weight, max_step=max_step)
    saved_qpos = data.qpos.copy()
    try:
        result = descend(q_init)
        rng = np.random.default_rng(seed)
        sample_lower, sample_upper = np.maximum(lower, -np.pi), np.minimum(upper, np.pi)
        for _ in range(restarts):
            if result.success:
                break
            retry = descend(rng.uniform(sample_lower, sample_upper))
            better = retry.success or _score(retry, pos_tol, rot_tol) < _score(result, pos_tol, rot_tol)
            result = replace(retry if better else result, iterations=result.iterations + retry.iterations)
    finally:
        data.qpos[:] = saved_qpos
        mujoco.mj_kinematics(model, data)
        mujoco.mj_comPos(model, data)
    return result


def solve_ik_position_axis(
    model: mujoco.MjModel,
    data: mujoco.MjData,
    site_name: str,
    joint_names: Sequence[str],
    target_pos,
    target_axis,
    q_init,
    **options,
) -> IKResult:
    """`solve_ik` constraining only the direction of the site's z axis to `target_axis` (3,),
    leaving the rotation about it free: the task for an axially symmetric tool such as a suction
    cup (for a grasp with approach direction v, target_axis = v when the site's z axis points
    out of the tool). `rot_tol` then bounds the angle between the two axes; `options` are the
    keyword arguments of `solve_ik`."""
    return solve_ik(model, data, site_name, joint_names, target_pos, target_axis, q_init,
                    axis_only=True, **options)


def _score(result: IKResult, pos_tol: float, rot_tol: float) -> float:
    """Error in units of the tolerances: <= 1 means success."""
    return max(result.pos_error / pos_tol, result.rot_error / rot_tol)


def _joint_addresses(model: mujoco.MjModel, joint_names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """qpos and dof addresses of single-dof (hinge or slide) joints, in the given order."""
    qpos_adr, dof_adr = [], []
    for name in joint_names:
        joint = model.joint(name)  # raises KeyError for an unknown name
        if model.jnt_type[joint.id] not in (mujoco.mjtJoint.mjJNT_HINGE.value, mujoco.mjtJoint.mjJNT_SLIDE.value):
            raise ValueError(f"joint {name!r} is not a hinge or slide joint")
        qpos_adr.append(joint.qposadr[0])
        dof_adr.append(joint.dofadr[0])
    return np.array(qpos_adr), np.array(dof_adr)


def _joint_limits(model: mujoco.MjModel, joint_names: Sequence[str]) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper limits; unlimited joints get infinite bounds."""
    lower, upper = [], []
    for name in joint_names:
        joint = model.joint(name)
        limited = bool(model.jnt_limited[joint.id])
        lower.append(model.jnt_range[joint.id, 0] if limited else -np.inf)
        upper.append(model.jnt_range[joint.id, 1] if limited else np.inf)
    return np.array(lower), np.array(upper)


@dataclass
class _Descent:
    """One DLS descent from a start configuration to a fixed target (see the module docstring)."""

    model: mujoco.MjModel
    data: mujoco.MjData
    site_id: int
    qpos_adr: np.ndarray
    dof_adr: np.ndarray
    lower: np.ndarray
    upper: np.ndarray
    target_pos: np.ndarray
    rotation_task: RotationTask
    pos_tol: float
    rot_tol: float
    max_iters: int
    damping: float
    rest: np.ndarray | None
    rest_weight: float
    max_step: float

    def __call__(self, q_start: np.ndarray) -> IKResult:
        """Iterate until within tolerance, stalled, or `max_iters` steps; returns the best iterate."""
        model, data, site_id, dofs = self.model, self.data, self.site_id, self.dof_adr
        jac_pos = np.zeros((3, model.nv))
        jac_rot = np.zeros((3, model.nv))
        q = np.clip(q_start, self.lower, self.upper)
        best, best_score, improved_at = None, np.inf, 0
        for iteration in range(self.max_iters + 1):
            data.qpos[self.qpos_adr] = q
            mujoco.mj_kinematics(model, data)
            mujoco.mj_comPos(model, data)  # mj_jacSite needs the subtree centres of mass
            mujoco.mj_jacSite(model, data, jac_pos, jac_rot, site_id)
            err_pos = self.target_pos - data.site_xpos[site_id]
            err_rot, task_jac_rot, rot_error = self.rotation_task(
                data.site_xmat[site_id].reshape(3, 3), jac_rot[:, dofs])
            current = IKResult(q=q, success=False, pos_error=float(np.linalg.norm(err_pos)),
                               rot_error=rot_error, iterations=iteration)
            score = _score(current, self.pos_tol, self.rot_tol)
            if score < best_score:
                if score < (1.0 - STALL_PROGRESS) * best_score:
                    improved_at = iteration
                best, best_score = current, score
            if best_score <= 1.0 or iteration == self.max_iters or iteration - improved_at >= STALL_ITERS:
                break
            jac = np.vstack([jac_pos[:, dofs], task_jac_rot])
            err = np.concatenate([err_pos, err_rot])
            pull = None if self.rest is None else self.rest_weight * (self.rest - q)
            step = _dls_step(jac, err, q, self.lower, self.upper, self.damping, self.max_step, pull)
            q = np.clip(q + step, self.lower, self.upper)
        return replace(best, success=best_score <= 1.0, iterations=iteration)


def _dls_step(
    jac: np.ndarray,
    err: np.ndarray,
    q: np.ndarray,
    lower: np.ndarray,
    upper: np.ndarray,
    damping: float,
    max_step: float,
    pull: np.ndarray | None,
) -> np.ndarray:
    """One damped-least-squares step, limited to `max_step`, that respects the joint limits.

    From the SVD J = U S V^T the DLS step is V diag(s / (s^2 + damping^2)) U^T err. `pull` (a
    joint-space velocity toward the rest configuration) is projected onto the exact null space
    of the task, the right singular vectors beyond the task dimension: a damped projector would
    leak part of the pull into the task and leave a steady position error of the order of the
    tolerance.

    Clamping alone stalls the solver: a joint resting on a limit keeps absorbing its share of
    the step, which is then lost. So a joint that sits on a limit and would be pushed through it
    is frozen for this step and the step is recomputed with the remaining joints, until no frozen
    joint is pushed outward (at most one pass per joint).
    """
    n = jac.shape[1]
    free = np.ones(n, dtype=bool)
    while True:
        u, s, vt = np.linalg.svd(jac[:, free])
        k = len(s)  # min(task dimension, free joints)
        step = np.zeros(n)
        step[free] = vt[:k].T @ ((s / (s**2 + damping**2)) * (u[:, :k].T @ err))
        if pull is not None and vt.shape[0] > k:
            null_basis = vt[k:]
            step[free] += null_basis.T @ (null_basis @ pull[free])
        largest = np.max(np.abs(step))
        if largest > max_step:
            step *= max_step / largest
        pushed = free & (((q <= lower) & (step < 0)) | ((q >= upper) & (step > 0)))
        if not pushed.any():
            return step
        free &= ~pushed
        if not free.any():
            return np.zeros(n)
