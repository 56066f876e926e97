"""The rendering scene for dataset generation: one object on the table, seen by a depth camera.

No robot: datasets only need depth images of the object resting in a stable pose. The object is
a mocap body (posed directly, no physics), the camera is moved per image.
"""

from __future__ import annotations

import mujoco
import numpy as np

from suctionbench.objects.build import ObjectRecord
from suctionbench.objects.mjcf import add_object_body
from suctionbench.sensing.camera import MUJOCO_FROM_OPENCV, CameraIntrinsics, DepthRenderer, add_camera

TABLE_HALF_SIZE = 1.0
"""Half side (m) of the table plane: wide enough to fill any preset's view."""


class TableScene:
    """Object on a table plane (z = 0) with a movable depth camera; render(object pose, camera pose)."""

    def __init__(self, record: ObjectRecord, intrinsics: CameraIntrinsics):
        spec = mujoco.MjSpec()
        spec.worldbody.add_geom(
            name="table", type=mujoco.mjtGeom.mjGEOM_PLANE, size=[TABLE_HALF_SIZE, TABLE_HALF_SIZE, 0.1]
        )
        body = add_object_body(spec, record, name="object", free=False)
        body.mocap = True
        add_camera(spec, "camera", np.eye(4), intrinsics)
        self.model = spec.compile()
        self.data = mujoco.MjData(self.model)
        self.intrinsics = intrinsics
        self.mocap = self.model.body("object").mocapid[0]
        self.camera = self.model.camera("camera").id
        self.renderer = DepthRenderer(self.model, intrinsics)

    def render(self, object_pose: np.ndarray, camera_pose: np.ndarray) -> np.ndarray:
        """Depth image (float32 metres, 0 = no return) for world poses of object and camera
        (camera pose in the OpenCV optical frame)."""
        quat = np.zeros(4)
        mujoco.mju_mat2Quat(quat, np.asarray(object_pose)[:3, :3].ravel())
        self.data.mocap_pos[self.mocap] = object_pose[:3, 3]
        self.data.mocap_quat[self.mocap] = quat
        cam_quat = np.zeros(4)
        mujoco.mju_mat2Quat(cam_quat, (np.asarray(camera_pose)[:3, :3] @ MUJOCO_FROM_OPENCV).ravel())
        self.model.cam_pos[self.camera] = camera_pose[:3, 3]
        self.model.cam_quat[self.camera] = cam_quat
        mujoco.mj_kinematics(self.model, self.data)
        mujoco.mj_camlight(self.model, self.data)
        return self.renderer.render(self.data, "camera")

    def close(self) -> None:
        self.renderer.close()

    def __enter__(self) -> TableScene:
        return self

    def __exit__(self, *exc) -> None:
        self.close()
