"""Liquids that level in the pose an object rests in (objects.liquid, sim.liquids): the levelled
centre of mass against closed-form values, the round trip through a built object's record, and
the simulation moving a lying bottle's centre of mass where its liquid runs."""

from __future__ import annotations

import math

import mujoco
import numpy as np
import pytest
import trimesh

from suctionbench.objects.liquid import UPRIGHT, Liquid, com_at_rest
from suctionbench.objects.mass import MATERIALS, contents_properties
from suctionbench.objects.registry import load_object
from suctionbench.sim.liquids import principal_axes

R, L = 0.04, 0.2
"""A closed cylinder 8 cm across and 20 cm long, axis along z (the object frame's up)."""


@pytest.fixture(scope="module")
def cylinder():
    return trimesh.creation.cylinder(radius=R, height=L, sections=256)


def test_half_full_cylinder_upright_and_lying(cylinder):
    half = cylinder.volume / 2.0
    # Upright, half the volume fills the lower half of the length: a solid cylinder of length L/2
    # whose centroid is L/4 below the middle.
    upright = contents_properties(cylinder, 0.25, half)
    np.testing.assert_allclose(upright.com, [0.0, 0.0, -L / 4.0], atol=1e-5)
    # Lying with gravity along +x, the liquid fills the half of every cross-section on the +x side:
    # a half-disc's centroid lies 4 R / (3 pi) from its diameter, and along the axis the liquid is
    # spread evenly, so its centre is at the middle of the length.
    lying = contents_properties(cylinder, 0.25, half, down=np.array([1.0, 0.0, 0.0]))
    np.testing.assert_allclose(lying.com, [4.0 * R / (3.0 * math.pi), 0.0, 0.0], atol=2e-5)
    assert lying.mass == pytest.approx(0.25)


def test_a_quarter_full_cylinder_tilted_holds_its_volume_below_a_level_surface(cylinder):
    quarter = cylinder.volume / 4.0
    down = np.array([1.0, 0.0, -1.0]) / math.sqrt(2.0)
    props = contents_properties(cylinder, 0.1, quarter, down=down)
    # The liquid's centre lies on the down side of the middle along gravity (the lower quarter of
    # the volume), and the mesh's mirror symmetry in y keeps it at y = 0.
    assert props.com @ down > 0.03 and abs(props.com[1]) < 1e-6


def test_liquids_flow_and_pastes_do_not():
    assert all(MATERIALS[m].flows for m in ("water", "milk", "shampoo", "soft_drink"))
    assert not MATERIALS["peanut_butter"].flows


@pytest.mark.parametrize("key", ["typical/bottle_shampoo", "typical/spray_bottle_cleaner", "typical/jug_milk",
                                 "typical/can_soda", "basic/cylinder_can"])
def test_levelled_upright_is_the_object_as_built(key):
    # Liquid.of takes the upright fill out of the record's mass properties; levelling it upright
    # again must give the record's own mass, centre of mass and inertia back.
    record = load_object(key)
    liquid = Liquid.of(record)
    assert liquid is not None
    props = liquid.properties(UPRIGHT)
    assert props.mass == pytest.approx(record.mass, rel=1e-9)
    np.testing.assert_allclose(props.com, record.com, atol=1e-6)
    np.testing.assert_allclose(props.inertia, record.inertia, atol=1e-8)
    np.testing.assert_allclose(com_at_rest(record, np.eye(3), liquid), record.com, atol=1e-6)


def test_paste_and_solid_objects_have_no_liquid():
    assert Liquid.of(load_object("typical/jar_wide")) is None  # peanut butter stays where it was filled
    assert Liquid.of(load_object("basic/box_brick")) is None


def test_lying_bottle_holds_its_liquid_along_its_length():
    # The shampoo bottle's 250 ml fill its lower end upright (centre of mass ~43 mm up its axis);
    # lying on its side the liquid runs along the whole body, so the centre of mass moves towards
    # the middle of the length and down towards the side it lies on.
    record = load_object("typical/bottle_shampoo")
    liquid = Liquid.of(record)
    lying = np.array([[1.0, 0.0, 0.0], [0.0, 0.0, -1.0], [0.0, 1.0, 0.0]])  # object +z -> world +y
    com = com_at_rest(record, lying, liquid)
    assert com[2] - record.com[2] > 0.02
    down = lying.T @ np.array([0.0, 0.0, -1.0])
    assert (com - record.com) @ down > 0.005


def test_principal_axes_rebuild_the_inertia_tensor():
    rng = np.random.default_rng(0)
    a = rng.normal(size=(3, 3))
    inertia = a @ a.T + np.eye(3)
    moments, quat = principal_axes(inertia)
    axes = np.zeros(9)
    mujoco.mju_quat2Mat(axes, quat)
    axes = axes.reshape(3, 3)
    np.testing.assert_allclose(axes @ np.diag(moments) @ axes.T, inertia, atol=1e-9)


def test_simulation_levels_the_liquid_of_a_bottle_that_lands_on_its_side():
    from suctionbench.sim.pick import PickRequest, PickRunner

    runner = PickRunner(PickRequest(object_key="typical/spray_bottle_cleaner", seed=0))
    runner.reset()
    ep = runner.episode
    body = ep.object
    rotation = ep.data.xmat[body].reshape(3, 3)
    assert abs(rotation[2, 2]) < 0.5, "seed 0 drops the bottle onto its side (its axis near horizontal)"
    built = np.asarray(runner.record.com)
    expected = Liquid.of(runner.record).properties(rotation.T @ UPRIGHT).com
    np.testing.assert_allclose(ep.model.body_ipos[body], expected, atol=LEVEL_TOLERANCE)
    assert np.linalg.norm(ep.model.body_ipos[body] - built) > 0.02
    # the analytic labels judge the same centre of mass as the simulated body
    _, com_world = runner.posed_object()
    np.testing.assert_allclose(com_world, rotation @ expected + ep.data.xpos[body], atol=LEVEL_TOLERANCE)
    # a reset restores the object as built before placing it again: the same seed, the same state
    qpos, ipos = ep.data.qpos.copy(), ep.model.body_ipos[body].copy()
    runner.reset()
    np.testing.assert_array_equal(ep.data.qpos, qpos)
    np.testing.assert_array_equal(ep.model.body_ipos[body], ipos)


LEVEL_TOLERANCE = 1e-3
"""The simulation levels when the object is at rest; it may still creep by up to the rest test's
0.2 mm and 0.23 deg afterwards, which moves the levelled centre of mass by well under 1 mm."""


def test_levelling_keeps_the_collision_bits_a_bin_episode_set():
    # mj_setConst derives each body's collision bits from its geoms': run on the episode's model it
    # cleared a parked object's, so that object fell through the bin once unparked (the bin
    # exploded while filling). Levelling must change only what derives from mass properties.
    from suctionbench.clutter.episode import BinEpisode
    from suctionbench.clutter.scene import build_bin_scene
    from suctionbench.config import CUP_DEFAULT
    from suctionbench.sensing.camera import resolve_camera

    records = [load_object("basic/cylinder_can"), load_object("basic/box_brick")]
    episode = BinEpisode(build_bin_scene(records, CUP_DEFAULT, resolve_camera("primesense"), np.eye(4)))
    can, brick = episode.bodies
    m = episode.model
    bits = m.body_contype[brick], m.body_conaffinity[brick]
    episode._park(brick)
    mujoco.mj_forward(m, episode.data)
    episode.liquids.level(episode.data, [can])
    episode._unpark(brick)
    assert (m.body_contype[brick], m.body_conaffinity[brick]) == bits
    assert m.body_subtreemass[can] == pytest.approx(records[0].mass)  # the mass stays; only where it sits moves


def test_a_levelled_body_collides_with_all_its_parts():
    # MuJoCo's mid-phase keeps a body's geom bounding boxes in its inertial frame. When levelling
    # moved the frame and the boxes stayed, the spray bottle (seed 1851474727: it lands on its
    # flat side) rested with its nozzle part 7 mm inside the table, uncollided. At rest on a
    # rigid table (5 ms contacts) no part may sink more than a millimetre, and the body's root box
    # must bound every part in the new frame.
    from suctionbench.sim.liquids import rotation_matrix
    from suctionbench.sim.pick import PickRequest, PickRunner

    runner = PickRunner(PickRequest(object_key="typical/spray_bottle_cleaner", seed=1851474727))
    runner.reset()
    ep = runner.episode
    m, d, body = ep.model, ep.data, ep.object
    assert np.linalg.norm(m.body_ipos[body] - runner.record.com) > 0.02  # levelled
    table = m.geom("table").id
    parts = [g for g in range(m.ngeom) if m.geom_bodyid[g] == body and m.geom(g).name.startswith("object_collision")]
    assert min(mujoco.mj_geomDistance(m, d, g, table, 0.05, None) for g in parts) > -1e-3
    root = m.bvh_aabb[m.body_bvhadr[body]]
    frame = rotation_matrix(m.body_iquat[body])
    for part in runner.record.part_meshes():
        local = (np.asarray(part.vertices) - m.body_ipos[body]) @ frame
        assert np.all(np.abs(local - root[:3]) <= root[3:] + 1e-6)


def test_levelling_a_body_built_with_an_unrotated_inertial_frame_rotates_it_in_the_kinematics():
    # A can built upright has its principal axes along its own: the compiler marks its inertial
    # frame as unrotated (body_sameframe) and MuJoCo's kinematics then takes the body's rotation
    # for the inertial frame's. Lying, the levelled liquid turns the principal axes; left marked,
    # the inertia acted about the wrong axes and the bounding boxes (kept in the inertial frame)
    # sat turned about the can's axis: parts up to 17 mm outside them, missed contacts, and bins
    # that ended in a deep interpenetration while filling. After levelling, the kinematics' inertial
    # frame must be the body's rotation times the levelled iquat, and it must bound every part.
    from suctionbench.clutter.episode import BinEpisode
    from suctionbench.clutter.scene import build_bin_scene
    from suctionbench.config import CUP_DEFAULT
    from suctionbench.sensing.camera import resolve_camera
    from suctionbench.sim.liquids import CORNERS, rotation_matrix

    record = load_object("basic/cylinder_can")
    episode = BinEpisode(build_bin_scene([record], CUP_DEFAULT, resolve_camera("primesense"), np.eye(4)))
    m, d = episode.model, episode.data
    (can,) = episode.bodies
    built = int(m.body_sameframe[can])
    assert built != mujoco.mjtSameFrame.mjSAMEFRAME_NONE  # as built: the case this test is about
    qpos = m.jnt_qposadr[m.body_jntadr[can]]
    d.qpos[qpos + 3: qpos + 7] = [np.cos(np.pi / 4), np.sin(np.pi / 4), 0.0, 0.0]  # lying: axis along y
    mujoco.mj_forward(m, d)
    assert episode.liquids.level(d, [can]) > 0.005  # the liquid moved towards the side below
    assert abs(abs(m.body_iquat[can][0]) - 1.0) > 1e-3  # and turned the principal axes
    mujoco.mj_kinematics(m, d)
    body_turn = d.xmat[can].reshape(3, 3)
    np.testing.assert_allclose(d.ximat[can].reshape(3, 3), body_turn @ rotation_matrix(m.body_iquat[can]), atol=1e-9)
    root = m.bvh_aabb[m.body_bvhadr[can]]
    frame, origin = d.ximat[can].reshape(3, 3), d.xipos[can]
    for g in range(m.body_geomadr[can], m.body_geomadr[can] + m.body_geomnum[can]):
        box = m.geom_aabb[g]
        world = d.geom_xpos[g] + (box[:3] + box[3:] * CORNERS) @ d.geom_xmat[g].reshape(3, 3).T
        local = (world - origin) @ frame
        assert np.all(np.abs(local - root[:3]) <= root[3:] + 1e-9), g
    episode.liquids.restore()
    assert m.body_sameframe[can] == built
