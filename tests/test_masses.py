"""Object masses: real items and named materials, the cup's mass cap, centres of mass of filled
containers and head-heavy tools, composite inertia, and known-state pickability."""

from __future__ import annotations

import math

import numpy as np
import pytest
import trimesh

from suctionbench.config import CUP_DEFAULT, STANDARD_GRAVITY, CupConfig
from suctionbench.errors import InputError
from suctionbench.objects.build import ObjectRecord, build_object
from suctionbench.objects.importer import import_mesh
from suctionbench.objects.mass import (
    MATERIALS,
    MassModel,
    mass_cap,
    mass_properties,
    printed,
    shell_properties,
    solid,
)
from suctionbench.objects.registry import list_objects, load_object
from suctionbench.objects.spec import SETS, ObjectSpec

ALL = [r for s in SETS for r in list_objects(s)]


def test_mass_cap_follows_from_the_cup():
    # V = 60 kPa x pi (6.5 mm)^2 = 7.96 N; cap = V / (1.5 (9.81 + 3.1)) = 0.411 kg
    cup = CupConfig()
    v = 60e3 * math.pi * 0.0065**2
    assert cup.mass_cap_kg == pytest.approx(v / (1.5 * (STANDARD_GRAVITY + 3.1)), rel=1e-9)
    cap = mass_cap(cup)
    assert cap["mass_cap_kg"] == pytest.approx(0.411, abs=5e-4)
    assert "0.411 kg" in cap["derivation"] and "7.96 N" in cap["derivation"]
    assert mass_cap(CupConfig(safety_factor=2.0))["mass_cap_kg"] < cap["mass_cap_kg"]


@pytest.mark.parametrize("record", ALL, ids=[r.key for r in ALL])
def test_committed_masses_are_real_and_under_the_cap(record):
    assert 0.005 <= record.mass <= CUP_DEFAULT.mass_cap_kg
    assert len(record.mass_source) > 20 and record.mass_model  # a stated source and its components
    inertia = np.asarray(record.inertia)
    eig = np.linalg.eigvalsh(inertia)
    assert np.allclose(inertia, inertia.T) and eig.min() > 0
    assert eig.max() <= eig.sum() - eig.max() + 1e-12  # triangle inequality of principal moments (MuJoCo)


FILLED = ["basic/cylinder_can", "typical/can_soda", "typical/bottle_shampoo", "typical/jar_wide",
          "typical/spray_bottle_cleaner", "typical/jug_milk"]


@pytest.mark.parametrize("key", FILLED)
def test_part_filled_container_has_its_centre_of_mass_below_the_centroid(key):
    record = load_object(key)
    assert record.mass_model.get("contents_volume"), "a part-filled container"
    centroid = record.mesh().center_mass
    assert record.com[2] < centroid[2] - 0.005  # liquid below the headspace pulls it > 5 mm down


def test_can_centre_of_mass_matches_the_fill_level():
    # A straight 66 x 120 mm can with 330 ml of drink: the liquid stands h_f = V_f / A tall from the
    # bottom, its centre at h_f / 2; the thin aluminium wall's centre is the can's centre (z = 0).
    record = load_object("basic/cylinder_can")
    mesh = record.mesh()
    height = mesh.extents[2]
    area = mesh.volume / height  # the 64-gon's cross-section
    liquid = record.mass_model["contents"]
    level = record.mass_model["contents_volume"] / area
    shell = record.mass - liquid
    expected = liquid * (-height / 2 + level / 2) / record.mass
    assert record.com[2] == pytest.approx(expected, abs=2e-4)
    assert shell == pytest.approx(record.mass_model["shell"] * mesh.area, rel=1e-6)
    assert record.mass == pytest.approx(0.356, abs=0.005)  # a full 330 ml can weighs ~0.35 kg


def test_hammer_is_head_heavy():
    record = load_object("typical/hammer_claw")
    mesh = record.mesh()
    # the steel head sits at the top of the handle (z = 0.2 m): the centre of mass is far above the
    # centroid of the volume, towards the head
    assert record.com[2] > mesh.center_mass[2] + 0.03
    assert record.mass > 7850.0 * 20e-6  # at least 20 cm^3 of steel


def test_real_items_weigh_what_they_weigh():
    assert load_object("basic/cylinder_battery").mass == pytest.approx(0.140, abs=1e-6)
    assert load_object("basic/cylinder_puck").mass == pytest.approx(0.163, abs=1e-6)
    assert 0.156 <= load_object("basic/cylinder_puck").mass <= 0.170


def test_shell_inertia_matches_a_closed_box_shell():
    # Thin closed box shell a x b x c of areal density s: I_xx = s [2 b c (b^2 + c^2) / 12
    # + 2 a c (b^2 / 4 + c^2 / 12) + 2 a b (b^2 / 12 + c^2 / 4)] (faces normal to x, y, z)
    a, b, c, s = 0.3, 0.2, 0.1, 2.0
    props = shell_properties(trimesh.creation.box(extents=(a, b, c)), s)
    ixx = s * (2 * b * c * (b**2 + c**2) / 12 + 2 * a * c * (b**2 / 4 + c**2 / 12) + 2 * a * b * (b**2 / 12 + c**2 / 4))
    assert props.mass == pytest.approx(s * 2 * (a * b + b * c + a * c))
    assert props.inertia[0, 0] == pytest.approx(ixx, rel=1e-9)
    assert np.allclose(props.com, 0.0, atol=1e-12)


def test_composite_of_components_is_consistent():
    # contents filling a box half-way: centre a quarter height below the middle; a part of another
    # density replaces the solid's inside it
    box = trimesh.creation.box(extents=(0.1, 0.1, 0.2))
    half = mass_properties(box, MassModel("test", contents=1.0, contents_volume=0.001))
    assert half.mass == pytest.approx(1.0) and half.com[2] == pytest.approx(-0.05, abs=1e-6)
    # a 1 kg/m^3 body with an upper half of 3 kg/m^3 weighs (1 + 3) / 2 x V and leans up
    upper = trimesh.creation.box(extents=(0.1, 0.1, 0.1)).apply_translation([0, 0, 0.05])
    from suctionbench.objects.mass import PARTS

    PARTS["test.upper"] = lambda: upper
    try:
        props = mass_properties(box, MassModel("test", density=1.0, part="test.upper", part_density=3.0))
    finally:
        del PARTS["test.upper"]
    assert props.mass == pytest.approx(0.002 * 2.0)
    assert props.com[2] == pytest.approx((3 * 0.05 - 1 * 0.05) / 4, abs=1e-9)


def test_materials_have_sources():
    for name, mat in MATERIALS.items():
        assert 100.0 < mat.density < 20000.0 and len(mat.source) > 10, name
    assert solid("beech").density == pytest.approx(0.64 * 1120, abs=1)  # Wood Handbook SG at 12 % x 1.12


def test_object_above_the_cap_is_rejected(tmp_path):
    cube = trimesh.creation.box(extents=(0.05, 0.05, 0.05))  # 125 cm^3 of steel: 0.98 kg
    steel = ObjectSpec(name="steel_cube", set="custom", generator="import", mass=solid("steel"))
    with pytest.raises(InputError, match=r"above the mass cap of 0\.411 kg"):
        build_object(cube, steel, tmp_path / "steel_cube")
    assert not (tmp_path / "steel_cube").exists()
    path = tmp_path / "cube.stl"
    cube.export(path)
    ok = import_mesh(path, set_name="custom", name="light", mass=0.3, root=tmp_path / "objs")
    assert ok.mass == pytest.approx(0.3) and "given" in ok.mass_source and "warnings" not in ok.params


def test_an_import_above_the_cap_is_kept_with_a_warning_naming_the_cups_that_carry_it(tmp_path):
    # The sets must be carried by the default cup (0.411 kg); an imported object need not be: the
    # paper's cup carries 12.9 kg, and an object no cup holds is a fair test of a policy. A 40 cm
    # PLA cube: at 20 % infill 1240 (0.2 x 0.064 + 0.8 x 0.96 x 0.0008) = 16.6 kg, above every cup;
    # its lightest variant, the bare 0.8 mm skin, 1240 x 0.96 m^2 x 0.0008 m = 0.952 kg, is kept.
    path = tmp_path / "big.stl"
    trimesh.creation.box(extents=(0.4, 0.4, 0.4)).export(path)
    record = import_mesh(path, set_name="custom", name="big", root=tmp_path / "objs")
    assert record.mass == pytest.approx(1240 * 0.96 * 0.0008, rel=1e-3)
    (warning,) = record.params["warnings"]
    assert "0.952 kg is above the default cup's mass cap of 0.411 kg" in warning and "paper (12.9 kg)" in warning
    assert ObjectRecord.load(record.directory).params["warnings"] == [warning]
    given = import_mesh(path, set_name="custom", name="given", mass=20.0, root=tmp_path / "objs")
    assert given.mass == pytest.approx(20.0) and "no cup preset carries it" in given.params["warnings"][0]


def test_large_print_falls_back_to_a_lower_infill(tmp_path):
    # A 14 cm PLA cube at 20 % infill weighs 1240 (0.2 V + 0.8 A 0.8 mm) = 0.84 kg: the build takes
    # the first lower infill (5 % steps) under the cap and says so.
    cube = trimesh.creation.box(extents=(0.14, 0.14, 0.14))
    spec = ObjectSpec(name="big_print", set="custom", generator="import", mass=printed())
    record = build_object(cube, spec, tmp_path / "big_print", decompose=False)
    rho, v, a = 1240.0, 0.14**3, 6 * 0.14**2
    expected = {f: rho * (f * v + (1 - f) * a * 0.0008) for f in (0.2, 0.15, 0.1, 0.05, 0.0)}
    chosen = next(f for f, m in expected.items() if m <= CUP_DEFAULT.mass_cap_kg)
    assert record.mass == pytest.approx(expected[chosen], rel=1e-6)
    assert f"{chosen * 100:g} % infill" in record.mass_source


def test_corpus_specs_carry_material_masses():
    from suctionbench.objects.corpus import corpus_specs

    specs = corpus_specs(40, seed=1)
    assert all(s.mass is not None and s.mass.source for s in specs)
    household = [s for s in specs if s.name.endswith("household")]
    assert household and all("PLA" not in s.mass.source for s in household)
    assert all(s.mass.lighter for s in specs)  # every corpus model can fall back under the cap


def test_the_training_mass_prior_changes_masses_only():
    # --masses prior draws each shape's make from its own stream (seed, index, 1): shapes and
    # parameters are the material corpus's, household kinds keep their kind's material, and every
    # other shape is one of the six makes, each able to fall back to a print under the cap.
    from suctionbench.objects.corpus import corpus_specs
    from suctionbench.objects.corpus_priors import TRAINING_MAKES

    material, prior = corpus_specs(120, seed=1), corpus_specs(120, seed=1, masses="prior")
    assert [(s.name, s.generator, s.params) for s in material] == [(s.name, s.generator, s.params) for s in prior]
    for a, b in zip(material, prior, strict=True):
        if a.name.endswith("household"):
            assert b.mass == a.mass
        else:
            assert b.mass.source.startswith("training mass prior: ") and b.mass.lighter
    makes = {s.mass.source for s in prior if not s.name.endswith("household")}
    assert makes == {make().source for make in TRAINING_MAKES}
    with pytest.raises(InputError, match="--masses 'lead'"):
        corpus_specs(1, seed=1, masses="lead")


def test_filled_containers_change_masses_only_and_hold_their_contents():
    # --masses filled draws each container's contents from its own stream (seed, index, 3): shapes,
    # parameters and every other object's mass are the material corpus's. A filled container weighs
    # its shell plus rho x (share of the enclosed volume V) of its contents, and the contents sit
    # at its bottom: the part of a body below a horizontal level has its centroid below the level,
    # the rest above it, and the whole's centroid is their volume-weighted mean, so for a share < 1
    # the contents' centre of mass lies strictly below the enclosed volume's centroid.
    from suctionbench.objects.corpus import corpus_specs
    from suctionbench.objects.corpus_priors import CONTAINER_KINDS, FILL_FRACTION
    from suctionbench.objects.mass import contents_properties, resolve_mass
    from suctionbench.objects.shapes import make_shape

    material, filled = corpus_specs(150, seed=1), corpus_specs(150, seed=1, masses="filled")
    assert [(s.name, s.generator, s.params) for s in material] == [(s.name, s.generator, s.params) for s in filled]
    changed = [(a, b) for a, b in zip(material, filled, strict=True) if a.mass != b.mass]
    assert changed and all(b.generator in CONTAINER_KINDS for _, b in changed)
    _, spec = changed[0]
    mesh = make_shape(spec.generator, spec.params)
    model = spec.mass
    share = model.contents_volume / mesh.volume
    assert FILL_FRACTION[0] <= share <= FILL_FRACTION[1]
    density = model.contents / model.contents_volume
    assert 1000.0 <= density <= 1080.0  # the contents: water to peanut butter
    props = mass_properties(mesh, model)
    assert props.mass == pytest.approx(shell_properties(mesh, model.shell).mass + density * share * mesh.volume,
                                       rel=1e-6)
    contents = contents_properties(mesh, model.contents, model.contents_volume)
    assert contents.com[2] < mesh.center_mass[2]
    # under the cap it holds the drawn share, or a half, a quarter, or nothing of it
    chosen, chosen_props = resolve_mass(mesh, model, spec.name)
    assert chosen_props.mass <= CUP_DEFAULT.mass_cap_kg
    assert chosen.contents_volume in (None, model.contents_volume, model.contents_volume / 2, model.contents_volume / 4)


def test_a_corpus_folder_rebuilds_a_container_built_with_another_mass_mode(tmp_path):
    # Corpus objects are cached by folder; an empty bottle built by `--masses material` must not
    # stand in for the same bottle part-filled by `--masses filled` (its empty shell is one of the
    # filled model's lighter variants, but not the one the cap chooses for it), and the reverse.
    from suctionbench.objects.corpus import corpus_spec
    from suctionbench.objects.corpus_build import _cached, build_specs
    from suctionbench.objects.shapes import register_all

    register_all()  # as corpus_specs does: a spec's category depends on the household kinds being known
    empty, filled = corpus_spec(1, 29, "material"), corpus_spec(1, 29, "filled")  # a bottle (index 29, seed 1)
    assert filled.generator == "household_bottle" and filled.mass.contents > 0
    folder = tmp_path / empty.set / empty.name
    (built_empty,) = build_specs([empty], tmp_path, workers=1, decompose=False)
    assert _cached(folder, empty) is not None and _cached(folder, filled) is None
    (built_filled,) = build_specs([filled], tmp_path, workers=1, decompose=False)
    assert built_filled.mass_model.get("contents", 0) > 0 and built_filled.mass > built_empty.mass
    assert _cached(folder, filled) is not None and _cached(folder, empty) is None


def test_pickability_flags_a_lying_triangular_prism():
    # Lying on a rectangular face, a triangular prism's other faces are tilted 60 deg from the
    # horizontal and its ends are vertical: under gqcnn's 30 deg cone no surface normal lies within
    # the cone and the prism is flagged; the image policies' 60 deg cone (the edge counts) takes
    # in both tilted faces, and every grasp it admits in a lying pose lies on them.
    from suctionbench.objects.stats import APPROACH_CONE, pickability

    assert math.degrees(APPROACH_CONE) == pytest.approx(60.0)
    record = load_object("basic/prism_tri_toblerone")
    narrow = pickability(record, grasps=64, seed=0, cone=math.radians(30.0))
    wide = pickability(record, grasps=64, seed=0)
    lying = 0
    for slim, broad, data in zip(narrow["poses"], wide["poses"], record.stable_poses, strict=True):
        up = np.asarray(data["transform"])[:3, :3] @ [0.0, 0.0, 1.0]  # the prism's axis in the world
        if abs(up[2]) < 0.1:  # lying
            lying += 1
            assert not slim["pickable"] and slim["in_cone"] == 0
            assert broad["in_cone"] == 64
    assert lying == 3
    cube = pickability(load_object("basic/box_cube_small"), grasps=64, seed=0)  # 46 g, flat faces
    assert cube["pickability"] == pytest.approx(1.0) and not cube["unpickable"]
    assert cube["pose_coverage"] == pytest.approx(1.0, abs=1e-5)
