"""Dataset generation in clutter (`generate --scene bin`): the datapoints of one bin per unit.

A unit fills the pick bin (`suctionbench.clutter`) with objects drawn from the generation's
objects, settled in MuJoCo, and shows it to a camera over the bin (`clutter.scene.BIN_CAMERA`)
at `GenerationConfig.bin_images` stages of its clearing (a random object taken out between
images). On each image, grasps sampled on every object's surface that the camera sees at their
pixel are labelled with their own object's robust label in its true pose (its mesh, mass and
centre of mass, plus the load its neighbours press onto it: `BinEpisode.loaded`; gravity straight
down), and a grasp whose gripper path meets a neighbour or a
wall (`clutter.planning.path_is_clear`: the cup's rim and the wrist) gets the label 0: it would
fail, and a network that never saw such grasps would propose them. The object context reads the
object's own pixels (the renderer's instance mask), as a policy planning per region does.
"""

from __future__ import annotations

import math
from pathlib import Path
from typing import Any

import numpy as np

from suctionbench.clutter.episode import BinEpisode
from suctionbench.clutter.planning import path_is_clear
from suctionbench.clutter.scene import BIN_CAMERA, PickBinConfig, build_bin_scene
from suctionbench.contact import SuctionLabeller
from suctionbench.dataset.generate import MAX_IMAGES_PER_UNIT, UNIT_FIELDS, _empty, image_object_context
from suctionbench.geometry.sampling import sample_surface_grasps, smoothed_approaches
from suctionbench.objects.build import ObjectRecord
from suctionbench.sensing.camera import DepthRenderer, body_image, resolve_camera
from suctionbench.sensing.camera_pose import sample_camera_pose
from suctionbench.sensing.noise import noisy_image
from suctionbench.sensing.thumbnails import (
    extract_context_thumbnails,
    pose_vector,
    project_grasps,
    sample_thumbnails,
    visible_mask,
)

CUP_PATH_LENGTH = 0.08
"""How far back from a grasp (m) the cup's rim rays of the path check reach (the cup and its
bellows; the wrist ring reaches further, `clutter.planning.WRIST_RING`)."""


def bin_objects(unit_index: int, num_objects: int, config: Any) -> np.ndarray:
    """Indices of the objects that fill bin `unit_index` (drop order)."""
    rng = np.random.default_rng((config.seed, unit_index, 7))
    low, high = config.bin_objects
    count = int(rng.integers(low, high + 1))
    return rng.choice(num_objects, size=count, replace=count > num_objects)


def generate_bin_unit(unit: Any, object_dirs: list[str], camera: str, config: Any) -> dict[str, np.ndarray]:
    """One bin's datapoints (runs in a worker process or a Ray task); see the module docstring."""
    return _BinUnit(unit, object_dirs, camera, config).run()


class _BinUnit:
    """The state of one bin unit's generation: the filled bin, its objects' candidates, the output."""

    def __init__(self, unit: Any, object_dirs: list[str], camera: str, config: Any):
        self.unit, self.config = unit, config
        self.rng = np.random.default_rng((config.seed, unit.index))
        self.chosen = bin_objects(unit.index, len(object_dirs), config)
        self.records = [ObjectRecord.load(Path(object_dirs[i])) for i in self.chosen]
        self.intrinsics = resolve_camera(camera)
        bin_config = PickBinConfig()
        self.camera_pose = sample_camera_pose(self.rng, np.array([*bin_config.centre, 0.0]),
                                              BIN_CAMERA.for_camera(self.intrinsics))
        self.scene = build_bin_scene(self.records, config.label.cup, self.intrinsics, self.camera_pose,
                                     bin_config=bin_config)
        self.episode = BinEpisode(self.scene, bin_config)
        self.episode.reset(self.rng)
        self.meshes, self.candidates = [], []
        for record in self.records:  # candidates in each object's own frame, as the table generator samples
            mesh = record.mesh()
            points, approaches = sample_surface_grasps(mesh, config.grasps_per_object, self.rng)
            if config.smoothed_approach_fraction > 0.0:
                smoothed = smoothed_approaches(mesh, points, approaches, config.approach_smoothing_radius, self.rng)
                use = self.rng.random(len(points)) < config.smoothed_approach_fraction
                approaches = np.where(use[:, None], smoothed, approaches)
            self.meshes.append(mesh)
            self.candidates.append((points, approaches))
        self.slot = {body: i for i, body in enumerate(self.episode.bodies)}
        self.out: dict[str, list[np.ndarray]] = {name: [] for name in UNIT_FIELDS}

    def run(self) -> dict[str, np.ndarray]:
        c, ep, count = self.config, self.episode, 0
        with DepthRenderer(self.scene.model, self.intrinsics) as renderer:
            for image in range(c.bin_images):
                if count >= self.unit.quota or not ep.present or ep.placement_error:
                    break
                depth = renderer.render(ep.data, self.scene.camera)
                segmentation = renderer.segment(ep.data, self.scene.camera)
                noisy = noisy_image(depth, self.rng, c.noise_model, c.noise)
                seen = body_image(self.scene.model, segmentation)
                pool = self._visible(depth)
                if pool:
                    budget = math.ceil((self.unit.quota - count) / (c.bin_images - image))
                    picks = np.sort(self.rng.choice(len(pool), size=min(budget, len(pool)), replace=False))
                    self._append([pool[k] for k in picks], image, depth, noisy, seen)
                    count += len(picks)
                if image + 1 < c.bin_images and len(ep.present) > 1:
                    ep.remove(ep.present[int(self.rng.integers(len(ep.present)))])
        return {name: np.concatenate(parts) if parts else _empty(name) for name, parts in self.out.items()}

    def _visible(self, depth: np.ndarray) -> list[tuple]:
        """(body, candidate index, pixel, depth, image angle, world point, world approach) of every
        candidate the camera sees at its pixel, approached from above within the generator's limit."""
        rot, origin = self.camera_pose[:3, :3], self.camera_pose[:3, 3]
        pool = []
        for body in self.episode.present:
            points, approaches = self.candidates[self.slot[body]]
            d = self.episode.data
            turn = d.xmat[body].reshape(3, 3)
            p_world, v_world = points @ turn.T + d.xpos[body], approaches @ turn.T
            pixels, depths, angles = project_grasps((p_world - origin) @ rot, v_world @ rot, self.intrinsics)
            upright = -v_world[:, 2] >= math.cos(self.config.max_approach_angle)
            for k in np.flatnonzero(visible_mask(pixels, depths, depth) & upright):
                pool.append((body, k, pixels[k], depths[k], angles[k], p_world[k], v_world[k]))
        return pool

    def _append(self, rows: list[tuple], image: int, depth: np.ndarray, noisy: np.ndarray, seen: np.ndarray) -> None:
        """Label the picked grasps (grouped by object) and append their datapoints."""
        c, ep, out = self.config, self.episode, self.out
        for body in sorted({r[0] for r in rows}):
            group = [r for r in rows if r[0] == body]
            i = self.slot[body]
            record = self.records[i]
            _, index, pixels, depths, angles, p_world, v_world = (np.array(col) for col in zip(*group, strict=True))
            mesh, com = ep.posed_mesh(body, self.meshes[i])
            mass, com = ep.loaded(body, record.mass, com)  # with what its neighbours press onto it
            labeller = SuctionLabeller(mesh, c.label, mass=mass, com=com)
            seed = int(np.random.SeedSequence((c.seed, self.unit.index, image, int(body))).generate_state(1)[0])
            labels = labeller.label(p_world, v_world, seed, metrics=("wr", "rwr"))
            clear = np.array([path_is_clear(ep.model, ep.data, p, v, body, c.label.cup.radius, CUP_PATH_LENGTH)
                              for p, v in zip(p_world, v_world, strict=True)])
            n = len(group)
            out["depth_ims_tf_table"].append(sample_thumbnails(noisy, pixels, angles, c.thumbnail)[..., None]
                                             .astype(np.float32))
            out["context_ims_tf_table"].append(
                extract_context_thumbnails(noisy, pixels, angles)[..., None].astype(np.float32))
            out["object_context"].append(image_object_context(self.intrinsics, depth, noisy, self.camera_pose, pixels,
                                                              p_world, v_world, object_mask=seen == body))
            v_cam = v_world @ self.camera_pose[:3, :3]
            out["hand_poses"].append(np.column_stack([pixels[:, 1], pixels[:, 0], pose_vector(depths, v_world),
                                                      v_cam]).astype(np.float32))
            out["robust_suction_wrench_resistance"].append(np.where(clear, labels.rwr, 0.0).astype(np.float32))
            out["object_labels"].append(np.full(n, int(self.chosen[i]), np.int32))
            out["pose_labels"].append(np.zeros(n, np.int32))
            out["image_labels"].append(np.full(n, self.unit.index * MAX_IMAGES_PER_UNIT + image, np.int32))
            out["grasp_labels"].append(index.astype(np.int32))
            out["seal_flags"].append((labels.seal.seal & clear).astype(np.uint8))
            out["wrench_resistance"].append((labels.wr & clear).astype(np.uint8))
