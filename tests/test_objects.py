"""Object sets: committed assets are complete, valid, reproducible and simulate; import and corpus."""

from __future__ import annotations

import filecmp
import json

import numpy as np
import pytest
import trimesh
from typer.testing import CliRunner

from suctionbench.cli import app
from suctionbench.errors import InputError
from suctionbench.objects.build import COVERAGE_MIN, EXCESS_MAX, MASS_CAP, MAX_FACES, MIN_MASS, ObjectRecord
from suctionbench.objects.importer import import_mesh
from suctionbench.objects.registry import eval_specs, list_objects, load_object
from suctionbench.objects.spec import SETS

SIZES = {"basic": 25, "typical": 25, "adversarial": 5}
ALL = [r for s in SETS for r in list_objects(s)]


def test_set_sizes_and_names_are_stable():
    specs = eval_specs()
    for set_name, size in SIZES.items():
        names = [s.name for s in specs[set_name]]
        assert len(names) == size and len(set(names)) == size, set_name
        assert [r.name for r in list_objects(set_name)] == sorted(names), "committed assets differ from specs"


@pytest.mark.parametrize("record", ALL, ids=[r.key for r in ALL])
def test_committed_object_is_valid(record: ObjectRecord):
    mesh = record.mesh()
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert mesh.volume > 0 and len(mesh.faces) <= MAX_FACES
    assert len(mesh.split(only_watertight=False)) == 1
    assert MIN_MASS <= record.mass <= MASS_CAP + 1e-9
    assert record.mass == pytest.approx(record.density * mesh.volume, rel=1e-4)
    probs = [p["probability"] for p in record.stable_poses]
    assert probs and all(0 < p <= 1 for p in probs) and sum(probs) <= 1 + 1e-5  # each rounded to 6 decimals
    assert probs == sorted(probs, reverse=True)
    # the most probable pose rests the mesh on z = 0
    rested = mesh.copy()
    rested.apply_transform(record.most_probable_pose())
    assert rested.bounds[0, 2] == pytest.approx(0.0, abs=1e-6)
    assert record.parts and record.decomposition["coverage"] >= COVERAGE_MIN
    assert record.decomposition["excess"] <= EXCESS_MAX
    for part in record.part_meshes():
        assert part.is_convex


def rebuild_matches(record: ObjectRecord, tmp_path) -> None:
    from suctionbench.objects.batch import build_specs

    spec = next(s for s in eval_specs()[record.set] if s.name == record.name)
    (rebuilt,) = build_specs([spec], tmp_path)
    assert rebuilt.to_toml() == record.to_toml()
    for rel in ["mesh.stl", *record.parts]:
        assert filecmp.cmp(rebuilt.directory / rel, record.directory / rel, shallow=False), rel


@pytest.mark.parametrize("key", ["basic/box_tea", "basic/tube_ring"])
def test_rebuild_reproduces_committed_assets(key, tmp_path):
    rebuild_matches(load_object(key), tmp_path)


@pytest.mark.slow
@pytest.mark.parametrize("record", ALL, ids=[r.key for r in ALL])
def test_rebuild_reproduces_every_committed_object(record, tmp_path):
    rebuild_matches(record, tmp_path)


@pytest.mark.parametrize("record", ALL, ids=[r.key for r in ALL])
def test_object_compiles_and_rests_in_mujoco(record):
    # In its most probable stable pose the object is in quasi-static equilibrium on the plane, so
    # 2 s of simulation must leave it (after the 0.5 mm settling drop) where it was.
    from suctionbench.objects.mjcf import rest_on_plane

    rest = rest_on_plane(record, seconds=2.0)
    assert rest["finite"]
    assert rest["displacement"] < 0.003, rest
    assert rest["rotation"] < np.radians(3.0), rest


def test_unknown_object_and_set_are_input_errors():
    with pytest.raises(InputError, match="unknown"):
        load_object("basic/no_such_thing")
    with pytest.raises(InputError, match="SET/NAME"):
        load_object("box_tea")
    with pytest.raises(InputError, match="unknown"):
        list_objects("nope")


# -- import ---------------------------------------------------------------------------------------


def write(mesh: trimesh.Trimesh, path):
    mesh.export(path)
    return path


def test_import_good_mesh_in_millimetres(tmp_path):
    path = write(trimesh.creation.box(extents=(60.0, 40.0, 20.0)), tmp_path / "part.stl")
    record = import_mesh(path, set_name="custom", name="part", units="mm", mass=0.1, root=tmp_path / "objs")
    assert record.extents == pytest.approx([0.06, 0.04, 0.02])
    assert record.mass == pytest.approx(0.1) and record.parts and record.stable_poses
    assert (tmp_path / "objs" / "custom" / "part" / "object.toml").is_file()
    # an open box (one face missing) is repaired: small holes get closed
    open_box = trimesh.creation.box(extents=(0.05, 0.05, 0.05))
    open_box.update_faces(np.arange(len(open_box.faces)) >= 2)
    path = write(open_box, tmp_path / "open.obj")
    repaired = import_mesh(path, set_name="custom", name="open", root=tmp_path / "objs")
    assert repaired.mesh().is_watertight and repaired.volume == pytest.approx(0.05**3, rel=1e-6)


def _bad_meshes(tmp_path):
    half_sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.04)
    half_sphere.update_faces(half_sphere.triangles_center[:, 2] > 0)
    flat = trimesh.Trimesh([[0, 0, 0], [0.05, 0, 0], [0, 0.05, 0], [0.05, 0.05, 0]], [[0, 1, 2], [1, 3, 2]])
    nan_obj = "v nan 0 0\nv 0.05 0 0\nv 0 0.05 0\nv 0 0 0.05\nf 1 2 3\nf 1 2 4\nf 1 3 4\nf 2 3 4\n"
    (tmp_path / "nan.obj").write_text(nan_obj)
    (tmp_path / "notes.txt").write_text("hello")
    return {
        "missing": (tmp_path / "missing.stl", "not found"),
        "unsupported": (tmp_path / "notes.txt", "unsupported"),
        "nan": (tmp_path / "nan.obj", "NaN"),
        "unrepairable": (write(half_sphere, tmp_path / "half.ply"), "watertight"),
        "flat": (write(flat, tmp_path / "flat.obj"), "degenerate"),
        "huge": (write(trimesh.creation.box(extents=(3.0, 1.0, 1.0)), tmp_path / "huge.stl"), "absurd scale"),
    }


def test_separate_pieces_import_as_one_rigid_body_with_the_assemblys_mass_properties(tmp_path):
    # Two 30 mm cubes, centres 0.1 m apart on x, 0.2 kg in all: a rigid assembly (a link's two
    # parts, fastened by what the mesh does not draw). Each cube m = 0.1 kg, side a = 0.03 m.
    # Centre of mass: midway, x = 0.05 m, by symmetry. Inertia about it: a cube's own m a^2 / 6
    # = 1.5e-5 kg m^2 about any axis through its centre; about y and z the parallel-axis term
    # m d^2 with d = 0.05 m adds 2.5e-4 per cube: Iyy = Izz = 2 (1.5e-5 + 2.5e-4) = 5.3e-4,
    # Ixx = 2 x 1.5e-5 = 3e-5 (the cubes' centres lie on x), no products.
    cube = trimesh.creation.box(extents=(0.03,) * 3)
    two = write(trimesh.util.concatenate([cube, cube.copy().apply_translation([0.1, 0, 0])]), tmp_path / "two.stl")
    record = import_mesh(two, set_name="custom", name="two", mass=0.2, root=tmp_path / "objs")
    assert record.params["warnings"][0].startswith("2 separate pieces (the nearest 70 mm from the largest")
    assert record.mass == pytest.approx(0.2) and record.volume == pytest.approx(2 * 0.03**3, rel=1e-6)
    assert record.com == pytest.approx([0.05, 0.0, 0.0], abs=1e-7)  # STL stores float32
    assert np.asarray(record.inertia) == pytest.approx(np.diag([3e-5, 5.3e-4, 5.3e-4]), rel=1e-5, abs=1e-10)
    assert len(record.mesh().split(only_watertight=False)) == 2
    # the convex parts cover both pieces and bridge no gap: no part spans the 40 mm between them
    sides = {bool(part.centroid[0] > 0.05) for part in record.part_meshes()}
    assert sides == {False, True}
    assert all(np.ptp(part.vertices[:, 0]) <= 0.03 + 1e-6 for part in record.part_meshes())
    # one MuJoCo body: it rests in its most probable stable pose like any object
    from suctionbench.objects.mjcf import rest_on_plane

    rest = rest_on_plane(record, seconds=1.0)
    assert rest["finite"] and rest["displacement"] < 0.003 and rest["rotation"] < np.radians(3.0), rest


def test_import_bad_meshes_fail_cleanly(tmp_path):
    root = tmp_path / "objs"
    for label, (path, message) in _bad_meshes(tmp_path).items():
        with pytest.raises(InputError, match=message):
            import_mesh(path, set_name="custom", name=label, root=root)
        assert not (root / "custom" / label).exists(), label
    good = write(trimesh.creation.box(extents=(0.05, 0.04, 0.03)), tmp_path / "good.stl")
    import_mesh(good, set_name="custom", name="dup", root=root)
    with pytest.raises(InputError, match="already exists"):
        import_mesh(good, set_name="custom", name="dup", root=root)
    with pytest.raises(InputError, match="evaluation sets"):
        import_mesh(good, set_name="basic", name="x", root=root)


def test_import_cli_exit_codes(tmp_path):
    runner = CliRunner()
    good = write(trimesh.creation.box(extents=(0.05, 0.04, 0.03)), tmp_path / "good.stl")
    args = ["objects", "import", str(good), "--name", "good", "--root", str(tmp_path / "objs"), "--json"]
    ok = runner.invoke(app, args)
    assert ok.exit_code == 0, ok.output
    assert json.loads(ok.stdout.strip().splitlines()[-1])["ok"]
    dup = runner.invoke(app, args)
    assert dup.exit_code == 2 and "already exists" in json.loads(dup.stdout.strip().splitlines()[-1])["error"]


# -- corpus ---------------------------------------------------------------------------------------


def test_corpus_specs_are_deterministic_and_prefix_stable():
    from suctionbench.objects.corpus import corpus_specs

    a, b = corpus_specs(30, seed=7), corpus_specs(30, seed=7)
    assert a == b
    assert corpus_specs(10, seed=7) == a[:10]  # spec i depends on (seed, i) only
    assert corpus_specs(10, seed=8) != a[:10]
    assert len({s.name for s in a}) == 30 and all(s.set == "train" for s in a)


def test_the_items_size_prior_rescales_generic_shapes_only():
    # --sizes items draws each generic shape's largest extent from its own stream (seed, index, 2)
    # and scales the "family" corpus's shape to it: same shapes, household kinds untouched, every
    # largest extent inside ITEM_SIZES (log-uniform there, so the median lies near the geometric
    # mean sqrt(0.04 * 0.245) = 9.9 cm, above the family ranges' 8-9 cm).
    from suctionbench.objects.corpus import corpus_specs
    from suctionbench.objects.corpus_priors import ITEM_SIZES
    from suctionbench.objects.shapes import make_shape

    family, items = corpus_specs(40, seed=2), corpus_specs(40, seed=2, sizes="items")
    generic = 0
    for a, b in zip(family, items, strict=True):
        assert a.name == b.name and a.mass.source == b.mass.source
        if a.name.endswith("household"):
            assert (b.generator, b.params) == (a.generator, a.params)
            continue
        generic += 1
        assert b.generator == "scaled" and (b.params["generator"], b.params["params"]) == (a.generator, a.params)
        largest = make_shape(b.generator, b.params).extents.max()
        assert ITEM_SIZES[0] * (1 - 1e-5) <= largest <= ITEM_SIZES[1] * (1 + 1e-5)
        ratio = largest / make_shape(a.generator, a.params).extents.max()
        assert ratio == pytest.approx(b.params["factor"], rel=1e-6)
    assert generic >= 25
    with pytest.raises(InputError, match="--sizes 'huge'"):
        corpus_specs(1, seed=2, sizes="huge")


def test_corpus_is_disjoint_from_the_evaluation_sets(tmp_path):
    from suctionbench.objects.corpus_build import evaluation_fingerprints, generate_corpus

    first = generate_corpus(24, seed=3, out=tmp_path)
    assert first["built"] == 24
    eval_hashes, _ = evaluation_fingerprints()
    manifest = json.loads((tmp_path / "corpus.json").read_text())
    corpus_hashes = {o["geometry_hash"] for o in manifest["objects"]}
    assert len(eval_hashes) == sum(SIZES.values()) and not corpus_hashes & eval_hashes
    from suctionbench.objects.registry import resolve_objects

    for record in resolve_objects(str(tmp_path)):  # named materials, under the cup's mass cap
        assert MIN_MASS <= record.mass <= MASS_CAP and record.mass_source, record.name
    again = generate_corpus(24, seed=3, out=tmp_path)  # cached: nothing rebuilt, same manifest
    assert again["cached"] == 24 and json.loads((tmp_path / "corpus.json").read_text()) == manifest


def test_adversarial_set_is_clearly_harder_but_still_sealable():
    # The adversarial shapes are made of surfaces curved differently in different directions,
    # ridges and thin features, so few 15 mm seals exist - but each object keeps some.
    from suctionbench.objects.stats import set_stats

    typical = set_stats(list_objects("typical")[::5], grasps=100, seed=0)
    adversarial = set_stats(list_objects("adversarial"), grasps=300, seed=0)
    assert adversarial["seal_share"] < 0.5 * typical["seal_share"]
    for obj in adversarial["per_object"]:
        assert obj["seal_share"] * 300 >= 3, obj
