"""Importing meshes as users have them: a corpus of third-party-like meshes (textured OBJs whose seams
split vertices, pieces that touch or overlap, non-manifold edges, duplicated faces, stray open
bodies, a surface that passes through itself, garbage, truncated files, odd units) and real robot
meshes shipped by dm_control; each either imports as one closed solid or fails with the message of
its defect class."""

from __future__ import annotations

import json
import os
import re
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
import pytest
import trimesh

from suctionbench.errors import InputError
from suctionbench.objects.importer import import_mesh

# -- the corpus -----------------------------------------------------------------------------------


@dataclass
class Case:
    """One corpus mesh: its file, import options, and what should happen."""

    name: str
    path: Path
    options: dict = field(default_factory=dict)
    error: str | None = None
    """None: imports with `options`; else a regex the InputError must match."""
    warning: str | None = None
    """A regex one of the import's notes must match (what was repaired)."""
    volume: float | None = None
    """Expected volume (m^3) of the imported solid, where the defect would change it."""
    pieces: int = 1
    """Separate closed pieces the imported solid keeps (more than one: a rigid assembly)."""


def _obj_text(vertices: np.ndarray, faces: np.ndarray, groups: list[np.ndarray] | None = None) -> str:
    """An OBJ as exporters with textures write it: unique positions, but a UV and a normal per face
    corner (flat shading, UV islands per face), so a loader splits vertices at every seam."""
    lines = [f"v {x:.9g} {y:.9g} {z:.9g}" for x, y, z in vertices]
    rng = np.random.default_rng(len(faces))
    uv = rng.uniform(size=(3 * len(faces), 2))
    lines += [f"vt {u:.6f} {v:.6f}" for u, v in uv]
    tri = vertices[faces]
    normals = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    lines += [f"vn {x:.6f} {y:.6f} {z:.6f}" for x, y, z in normals]
    groups = groups if groups is not None else [np.arange(len(faces))]
    for g, members in enumerate(groups):
        lines.append(f"o piece_{g}")
        for i in members:
            corners = [f"{faces[i, k] + 1}/{3 * i + k + 1}/{i + 1}" for k in range(3)]
            lines.append("f " + " ".join(corners))
    return "\n".join(lines) + "\n"


def _tube(path_points: np.ndarray, radius: float, sides: int = 16) -> trimesh.Trimesh:
    """A closed tube (capped) swept along a polyline in the xy plane."""
    tangents = np.gradient(path_points, axis=0)
    tangents /= np.linalg.norm(tangents, axis=1, keepdims=True)
    side = np.cross([0.0, 0.0, 1.0], tangents)
    angles = np.linspace(0, 2 * np.pi, sides, endpoint=False)
    rings = (
        path_points[:, None, :]
        + radius * np.cos(angles)[None, :, None] * side[:, None, :]
        + radius * np.sin(angles)[None, :, None] * np.array([0.0, 0.0, 1.0])
    )
    vertices = [*rings.reshape(-1, 3), path_points[0], path_points[-1]]
    n = len(path_points)
    faces = []
    for i in range(n - 1):
        for j in range(sides):
            a, b = i * sides + j, i * sides + (j + 1) % sides
            c, d = a + sides, b + sides
            faces += [[a, b, d], [a, d, c]]
    start, end = n * sides, n * sides + 1
    for j in range(sides):
        faces.append([start, (j + 1) % sides, j])
        faces.append([end, (n - 1) * sides + j, (n - 1) * sides + (j + 1) % sides])
    mesh = trimesh.Trimesh(np.array(vertices), np.array(faces), process=False)
    if mesh.volume < 0:
        mesh.invert()
    return mesh


def _box(extents, offset=(0.0, 0.0, 0.0)) -> trimesh.Trimesh:
    return trimesh.creation.box(extents=extents).apply_translation(offset)


def build_corpus(directory: Path) -> list[Case]:
    """Write the corpus under `directory` and describe it."""
    directory.mkdir(parents=True, exist_ok=True)
    cases: list[Case] = []

    def save(name: str, mesh: trimesh.Trimesh, **kwargs) -> Case:
        path = directory / name
        mesh.export(path)
        cases.append(Case(name, path, **kwargs))
        return cases[-1]

    def text(name: str, content: str | bytes, **kwargs) -> Case:
        path = directory / name
        path.write_bytes(content if isinstance(content, bytes) else content.encode())
        cases.append(Case(name, path, **kwargs))
        return cases[-1]

    # Textured OBJs: closed, but every UV/normal seam splits the loader's vertices.
    box = _box((0.06, 0.04, 0.03))
    text("seams_box.obj", _obj_text(box.vertices, box.faces), volume=0.06 * 0.04 * 0.03)
    sphere = trimesh.creation.icosphere(subdivisions=3, radius=0.03)
    text("seams_sphere.obj", _obj_text(sphere.vertices, sphere.faces), volume=sphere.volume)
    cylinder = trimesh.creation.cylinder(radius=0.025, height=0.08, sections=40)
    text("seams_cylinder.obj", _obj_text(cylinder.vertices, cylinder.faces), volume=cylinder.volume)
    glb = sphere.copy()
    glb.unmerge_vertices()  # glTF stores a vertex per UV: every triangle its own island
    glb.visual = trimesh.visual.TextureVisuals(uv=np.random.default_rng(1).uniform(size=(len(glb.vertices), 2)))
    save("seams_sphere.glb", glb, volume=sphere.volume)
    # Pieces that touch face to face (a modeller's L-bracket, a CAD table) and pieces that overlap.
    piece_a, piece_b = _box((0.06, 0.02, 0.02)), _box((0.02, 0.02, 0.04), (0.02, 0.0, 0.03))
    both = trimesh.util.concatenate([piece_a, piece_b])
    text(
        "touching_bracket.obj",
        _obj_text(both.vertices, both.faces, [np.arange(12), np.arange(12, 24)]),
        warning="touch",
        volume=0.06 * 0.02 * 0.02 + 0.02 * 0.02 * 0.04,
    )
    legs = [_box((0.01, 0.01, 0.05), (x, y, 0.025)) for x in (-0.04, 0.04) for y in (-0.025, 0.025)]
    table = trimesh.util.concatenate([_box((0.1, 0.06, 0.01), (0.0, 0.0, 0.055)), *legs])
    save("touching_table.stl", table, warning="touch", volume=0.1 * 0.06 * 0.01 + 4 * 0.01 * 0.01 * 0.05)
    overlap = trimesh.util.concatenate([_box((0.05, 0.03, 0.03)), _box((0.05, 0.03, 0.03), (0.02, 0.0, 0.0))])
    save("overlapping_boxes.ply", overlap, warning="overlap", volume=0.07 * 0.03 * 0.03)
    # A closed box with a dangling fin on one edge and one with an inner wall: non-manifold edges.
    fin_box = _box((0.05, 0.05, 0.05))
    corner = fin_box.vertices[fin_box.edges_unique[0]]
    fin = trimesh.Trimesh(np.vstack([corner, corner.mean(0) + [0.0, 0.03, 0.03]]), [[0, 1, 2]])
    save("nonmanifold_fin.stl", trimesh.util.concatenate([fin_box, fin]), warning="non-manifold", volume=0.05**3)
    stack = trimesh.util.concatenate([_box((0.04, 0.04, 0.02), (0, 0, 0.01)), _box((0.04, 0.04, 0.02), (0, 0, 0.03))])
    stack.merge_vertices()
    middle = np.isclose(stack.triangles_center[:, 2], 0.02)
    wall = np.flatnonzero(middle)[:2]  # one of the two coincident middle squares
    keep = ~middle
    keep[wall] = True
    stack.update_faces(keep)
    save("nonmanifold_wall.stl", stack, warning="non-manifold", volume=0.04 * 0.04 * 0.04)
    # Duplicated faces (an exporter wrote part of the surface twice).
    dup = trimesh.creation.icosphere(subdivisions=2, radius=0.03)
    dup = trimesh.Trimesh(dup.vertices, np.vstack([dup.faces, dup.faces[:40]]), process=False)
    save("duplicated_faces.stl", dup, warning="duplicated", volume=trimesh.creation.icosphere(2, 0.03).volume)
    # A bottle with a separate open label sleeve around it.
    bottle = trimesh.creation.cylinder(radius=0.03, height=0.12, sections=32)
    sleeve = trimesh.creation.cylinder(radius=0.0302, height=0.05, sections=32)
    sleeve.update_faces(np.abs(sleeve.face_normals[:, 2]) < 0.5)
    save("open_second_body.obj", trimesh.util.concatenate([bottle, sleeve]), warning="open", volume=bottle.volume)
    # A box with a small hole (a scan's missing patch) that a fan closes.
    holed = trimesh.creation.icosphere(subdivisions=3, radius=0.03)
    holed.update_faces(np.linalg.norm(holed.triangles_center - [0, 0, 0.03], axis=1) > 0.008)
    save("small_hole.ply", holed, warning="hole")
    # Meshes in other units: millimetres and inches (URDF-style scale).
    save("part_mm.stl", _box((60.0, 40.0, 20.0)), options={"units": "mm"}, volume=0.06 * 0.04 * 0.02)
    save("part_in.stl", _box((2.0, 1.5, 1.0)), options={"units": "in"}, volume=3.0 * 0.0254**3)
    save("part_scaled.stl", _box((6.0, 4.0, 2.0)), options={"scale": 0.01}, volume=0.06 * 0.04 * 0.02)
    # Unfixable: the defect must be named.
    hemisphere = trimesh.creation.icosphere(subdivisions=3, radius=0.04)
    hemisphere.update_faces(hemisphere.triangles_center[:, 2] > 0)
    save("hemisphere.stl", hemisphere, error=r"not watertight: 1 hole up to 80 mm across")
    t = np.linspace(0.15, 2 * np.pi - 0.15, 80)
    curl = np.stack([0.04 * np.cos(t), 0.025 * np.sin(2 * t), np.zeros_like(t)], axis=1)
    save("self_intersecting.stl", _tube(curl, 0.008), error="self-intersecting")
    apart = trimesh.util.concatenate([_box((0.03,) * 3), _box((0.03,) * 3, (0.1, 0, 0))])
    # Two pieces 7 cm apart: one rigid body as the file is one object (a robot link's parts are
    # fastened by what the mesh does not draw), kept apart, with a warning.
    save("two_apart.stl", apart, warning=r"2 separate pieces \(the nearest 70 mm .*kept as one rigid body",
         volume=2 * 0.03**3, pieces=2)
    # Without --units an STL is read in metres or millimetres, whichever size is plausible (no size
    # is plausible both ways); an OBJ has no convention, so a size plausible only in other units is
    # rejected with the units that would fit (60 units: 60 cm or 60 mm, 1.5 m in inches).
    save("part_mm_auto.stl", _box((60.0, 40.0, 20.0)), volume=0.06 * 0.04 * 0.02)
    save("big_in_mm.obj", _box((60.0, 40.0, 20.0)), error=r"absurd scale.*it fits read in cm or mm.*--units")
    rng = np.random.default_rng(5)
    text("garbage.stl", rng.bytes(3000), error=r"not a readable mesh \(format stl")
    text("garbage.obj", b"\xff\xfe" + rng.bytes(2000), error=r"not a readable mesh \(format obj")
    text("garbage.ply", b"ply\nformat binary_little_endian 1.0\n" + rng.bytes(500), error=r"not a readable mesh")
    good = trimesh.creation.icosphere(subdivisions=2, radius=0.03)
    data = good.export(file_type="stl")
    text("truncated.stl", data[: len(data) // 2], error=r"not a readable mesh \(format stl")
    data = good.export(file_type="ply")
    text("truncated.ply", data[: len(data) // 2], error=r"not a readable mesh \(format ply")
    return cases


def third_party_meshes() -> list[Path]:
    """Robot meshes as public packages ship them: dm_control's Kinova arm and the dog's bones."""
    import dm_control

    root = Path(dm_control.__file__).parent
    kinova = sorted((root / "third_party" / "kinova" / "meshes_decimated").glob("*.stl"))
    bones = sorted((root / "suite" / "dog_assets").glob("BONE*.stl"))
    bones = [p for p in bones if max(trimesh.load(p, force="mesh").extents) >= 0.01][::12]
    return kinova + bones


def import_case(case: Case, root: Path):
    return import_mesh(
        case.path,
        set_name="corpus",
        name=case.path.stem.replace(".", "_").lower(),
        root=root,
        overwrite=True,
        **case.options,
    )


def third_party_cases() -> list[Case]:
    """`third_party_meshes` with their expected outcomes: the Kinova hand's insert is a shell open on
    one side (a 52 mm opening its winding number leaves undecided over more than the volume); the main
    shell, open where the insert closes it, bounds a solid with 6 % of its volume undecided and is
    rebuilt; everything else imports."""
    cases = []
    for path in third_party_meshes():
        insert = path.stem == "hand_3finger_insert"
        error = r"not watertight: 1 hole up to 51.6 mm across.*undecided" if insert else None
        warning = "rebuilt as the solid the surface bounds" if path.stem == "hand_3finger_main" else None
        cases.append(Case(f"{path.parent.name}/{path.name}", path, error=error, warning=warning))
    return cases


with tempfile.TemporaryDirectory() as _folder:
    CORPUS_NAMES = [case.name for case in build_corpus(Path(_folder))]


@pytest.fixture(scope="module")
def corpus(tmp_path_factory) -> dict[str, Case]:
    return {case.name: case for case in build_corpus(tmp_path_factory.mktemp("corpus"))}


def _leftovers(root: Path) -> list[Path]:
    return sorted(p for p in root.rglob("*") if p.name.startswith(".")) if root.exists() else []


def check_case(case: Case, root: Path) -> str:
    """Import `case` under `root` and check its outcome; returns 'ok' or the error message."""
    if case.error is not None:
        with pytest.raises(InputError, match=case.error) as info:
            import_case(case, root)
        message = str(info.value)
        assert "\n" not in message and str(case.path) in message, message
        assert not (root / "corpus" / case.path.stem.lower()).exists()
        assert not _leftovers(root), _leftovers(root)
        return message
    record = import_case(case, root)
    mesh = record.mesh()
    assert mesh.is_watertight and mesh.is_winding_consistent
    assert len(mesh.split(only_watertight=False)) == case.pieces, case.name
    assert record.parts and record.stable_poses and record.volume > 0
    if case.volume is not None:
        assert record.volume == pytest.approx(case.volume, rel=2e-3), case.name
    notes = record.params["repairs"] + record.params.get("warnings", [])
    if case.warning is not None:
        assert any(re.search(case.warning, note) for note in notes), notes
    assert not _leftovers(root), _leftovers(root)
    return "ok"


@pytest.mark.parametrize("name", CORPUS_NAMES)
def test_corpus_mesh_imports_or_names_its_defect(corpus, name, tmp_path):
    check_case(corpus[name], tmp_path / "objs")


def test_each_defect_class_has_its_own_message(corpus, tmp_path):
    messages = {}
    for name in ("hemisphere.stl", "self_intersecting.stl", "garbage.stl", "big_in_mm.obj"):
        messages[name] = check_case(corpus[name], tmp_path / "objs").split("': ", 1)[1]
    firsts = [m.split(" ")[0:2] for m in messages.values()]
    assert len({tuple(f) for f in firsts}) == len(firsts), messages


def test_repairs_are_recorded_and_can_be_refused(corpus, tmp_path):
    record = import_case(corpus["touching_table.stl"], tmp_path / "objs")
    assert record.params["repairs"] == ["5 pieces that touch face to face united into one body"]
    assert record.params["units"] == "m" and record.params["scale"] == 1.0
    millimetres = import_case(corpus["part_mm_auto.stl"], tmp_path / "objs")
    assert millimetres.units == "mm" and millimetres.params["units"] == "mm" and millimetres.scale == 0.001
    case = corpus["duplicated_faces.stl"]
    with pytest.raises(InputError, match=r"needs repair \(40 duplicated faces removed\).*--no-repair"):
        import_mesh(case.path, set_name="corpus", name="strict", root=tmp_path / "objs", try_repair=False)
    # merging seams is reading, not repairing: a textured OBJ imports even without repairs
    seams = import_mesh(
        corpus["seams_box.obj"].path, set_name="corpus", name="seams", root=tmp_path / "objs", try_repair=False
    )
    assert seams.params["repairs"] == [] and seams.faces == 12


def test_scale_and_units_combine(corpus, tmp_path):
    record = import_mesh(
        corpus["part_in.stl"].path, set_name="corpus", name="half", units="in", scale=0.5, root=tmp_path / "objs"
    )
    assert record.scale == pytest.approx(0.0127) and record.extents == pytest.approx([0.0254, 0.01905, 0.0127])
    for bad in (0.0, -1.0, float("nan"), float("inf")):
        with pytest.raises(InputError, match="scale"):
            import_mesh(corpus["part_in.stl"].path, set_name="corpus", name="bad", scale=bad, root=tmp_path / "objs")
    with pytest.raises(InputError, match="units 'ft' is unknown"):
        import_mesh(corpus["part_in.stl"].path, set_name="corpus", name="bad", units="ft", root=tmp_path / "objs")


# -- the repair pieces ----------------------------------------------------------------------------


def test_winding_numbers_are_one_inside_and_zero_outside():
    from suctionbench.objects.repair import doubled_share
    from suctionbench.objects.winding import winding_numbers

    box = _box((0.04, 0.02, 0.01))
    points = np.array([[0.0, 0.0, 0.0], [0.019, 0.009, 0.004], [0.03, 0.0, 0.0], [0.0, 0.0, -0.02]])
    assert winding_numbers(box, points) == pytest.approx([1.0, 1.0, 0.0, 0.0], abs=1e-9)
    assert doubled_share(box) == 0.0
    twice = trimesh.util.concatenate([box, box.copy()])
    assert winding_numbers(twice, points[:1]) == pytest.approx([2.0])
    assert doubled_share(twice) == pytest.approx(1.0, abs=0.05)


def test_touching_pieces_separate_into_closed_bodies():
    from suctionbench.objects.repair import bodies, merge_by_position

    # two cubes sharing a face (written with the same diagonal: opposite duplicate triangles) and a
    # third sharing only an edge with the second
    cubes = [_box((0.02,) * 3), _box((0.02,) * 3, (0.02, 0, 0)), _box((0.02,) * 3, (0.04, 0.02, 0))]
    mesh = merge_by_position(trimesh.util.concatenate(cubes))
    groups, nonmanifold, cut = bodies(mesh)
    assert [len(g) for g in groups] == [12, 12, 12] and nonmanifold > 0 and cut == 0
    for group in groups:
        body = trimesh.Trimesh(mesh.vertices, mesh.faces[group])
        assert body.is_watertight and body.volume == pytest.approx(0.02**3)


# -- CoACD in a child process ---------------------------------------------------------------------


def _aborting_child(job, result):
    return [sys.executable, "-c", "import os; os.abort()"]


def test_coacd_crash_is_a_clean_input_error_with_nothing_left(corpus, tmp_path, monkeypatch):
    from suctionbench.objects import decompose

    monkeypatch.setattr(decompose, "_child_command", _aborting_child)
    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    root = tmp_path / "objs"
    # concave (an L bracket): its hull would add phantom material, so no fallback
    with pytest.raises(InputError, match=r"convex decomposition failed .*CoACD crashed \(SIGABRT\)") as info:
        import_case(corpus["touching_bracket.obj"], root)
    assert str(corpus["touching_bracket.obj"].path) in str(info.value)
    assert not root.exists() or not any(root.rglob("*"))
    assert list((tmp_path / "tmp").iterdir()) == []
    # convex (a box): falls back to its hull and says so
    record = import_case(corpus["seams_box.obj"], root)
    assert record.decomposition["method"] == "hull" and len(record.parts) == 1
    assert "SIGABRT" in record.decomposition["failures"][0]
    assert [p.name for p in (root / "corpus").iterdir()] == ["seams_box"]


def test_coacd_tries_side_by_side_give_the_same_parts_and_leave_nothing(corpus, tmp_path, monkeypatch):
    """The schedule's tries run at once (`parallel`) and are judged in order: the same parts and
    record as one by one (every run is seeded), no temp folder and no child process left behind."""
    from suctionbench.objects.build import decompose_mesh
    from suctionbench.objects.decompose import IMPORT_OPTIONS

    monkeypatch.setattr(tempfile, "tempdir", str(tmp_path / "tmp"))
    (tmp_path / "tmp").mkdir()
    piece_a, piece_b = _box((0.06, 0.02, 0.02)), _box((0.02, 0.02, 0.04), (0.02, 0.0, 0.03))
    solid = trimesh.boolean.union([piece_a, piece_b], engine="manifold")  # an L bracket
    # a first try that cannot fit (one hull on an L), so the second, already running, is judged too
    schedule = ((1.0, 1), (0.05, 8), (0.03, 16))
    one, info_one = decompose_mesh(solid, schedule=schedule, options=IMPORT_OPTIONS, parallel=1)
    three, info_three = decompose_mesh(solid, schedule=schedule, options=IMPORT_OPTIONS, parallel=3)
    assert info_one == info_three and info_one["threshold"] == 0.05
    assert len(one) == len(three)
    assert all(np.array_equal(a.vertices, b.vertices) for a, b in zip(one, three, strict=True))
    assert list((tmp_path / "tmp").iterdir()) == []
    children = Path(f"/proc/{os.getpid()}/task/{os.getpid()}/children")
    if children.exists():  # no CoACD child left running (other tests may leave pool workers)
        commands = [Path(f"/proc/{pid}/cmdline").read_bytes() for pid in children.read_text().split()
                    if Path(f"/proc/{pid}/cmdline").exists()]
        assert not [c for c in commands if b"decompose.py" in c], commands


def test_bench_import_times_both_ways_and_gets_the_same_object(corpus):
    from typer.testing import CliRunner

    from suctionbench.cli import app

    result = CliRunner().invoke(app, ["bench", "import", str(corpus["touching_bracket.obj"].path), "--json"])
    assert result.exit_code == 0, result.output[-2000:]
    line = json.loads(result.stdout.strip().splitlines()[-1])
    assert line["ok"] and line["same_object"] is True and line["parts"] >= 2
    assert line["seconds_one_by_one"] > 0 and line["seconds_side_by_side"] > 0


def test_cli_import_crash_exits_2_with_a_json_line(corpus, tmp_path):
    """A real child that aborts (SIGABRT): the CLI process survives, prints its JSON line, exits 2."""
    import subprocess

    script = (
        "import sys; from suctionbench.objects import decompose; "
        "decompose._child_command = lambda job, result: [sys.executable, '-c', 'import os; os.abort()']; "
        "from suctionbench.cli import main; sys.argv = ['suctionbench'] + sys.argv[1:]; main()"
    )
    path = corpus["touching_bracket.obj"].path
    args = ["objects", "import", str(path), "--name", "bracket", "--root", str(tmp_path / "objs"), "--json"]
    done = subprocess.run([sys.executable, "-c", script, *args], capture_output=True, text=True, timeout=300)
    assert done.returncode == 2, done.stderr[-2000:]
    line = json.loads(done.stdout.strip().splitlines()[-1])
    assert not line["ok"] and "CoACD crashed (SIGABRT)" in line["error"] and str(path) in line["error"]
    assert not (tmp_path / "objs").exists() or not any((tmp_path / "objs").rglob("*"))


# -- real meshes from public packages -------------------------------------------------------------


@pytest.mark.slow
def test_third_party_robot_meshes_import(tmp_path):
    outcomes = {case.name: check_case(case, tmp_path / "objs") for case in third_party_cases()}
    expected_ok = [c for c in third_party_cases() if c.error is None]
    imported = [name for name, out in outcomes.items() if out == "ok"]
    assert len(imported) == len(expected_ok) >= 20


def test_hidden_folders_in_the_user_root_are_not_sets(corpus, tmp_path, monkeypatch):
    from suctionbench.objects.registry import list_objects

    monkeypatch.setenv("SUCTIONBENCH_HOME", str(tmp_path))
    (tmp_path / "objects" / ".mine.k2j4x9").mkdir(parents=True)  # a write killed half-way
    import_mesh(corpus["seams_box.obj"].path, set_name="mine", name="box")
    user = [r.key for r in list_objects() if r.set not in ("basic", "typical", "adversarial")]
    assert user == ["mine/box"]
    with pytest.raises(InputError, match="unknown"):
        list_objects(".mine.k2j4x9")


def test_cli_import_takes_units_and_scale_and_reports_repairs(corpus, tmp_path):
    from typer.testing import CliRunner

    from suctionbench.cli import app

    runner = CliRunner()
    root = ["--root", str(tmp_path / "objs"), "--json"]
    scaled = runner.invoke(
        app,
        [
            "objects",
            "import",
            str(corpus["part_in.stl"].path),
            "--units",
            "in",
            "--scale",
            "0.5",
            "--name",
            "half",
            *root,
        ],
    )
    assert scaled.exit_code == 0, scaled.output
    line = json.loads(scaled.stdout.strip().splitlines()[-1])
    assert line["ok"] and line["scale"] == pytest.approx(0.0127) and line["repairs"] == []
    table = runner.invoke(app, ["objects", "import", str(corpus["touching_table.stl"].path), "--name", "table", *root])
    assert json.loads(table.stdout.strip().splitlines()[-1])["repairs"] == [
        "5 pieces that touch face to face united into one body"
    ]
    for args, message in (
        (["--scale", "0"], "scale 0.0: must be a positive, finite factor"),
        (["--units", "ft"], "units 'ft' is unknown"),
    ):
        bad = runner.invoke(app, ["objects", "import", str(corpus["part_in.stl"].path), "--name", "bad", *args, *root])
        assert bad.exit_code == 2 and message in json.loads(bad.stdout.strip().splitlines()[-1])["error"]
    garbage = runner.invoke(app, ["objects", "import", str(corpus["garbage.obj"].path), *root])
    error = json.loads(garbage.stdout.strip().splitlines()[-1])["error"]
    assert garbage.exit_code == 2 and "not a readable mesh (format obj" in error and "charset" not in error


# -- pieces a few micrometres apart, crumbs, sealed voids, pinches ---------------------------------


def _solid(mesh: trimesh.Trimesh):
    from suctionbench.objects.repair import solidify

    return solidify(mesh, source="test")


def test_convex_pieces_a_few_micrometres_apart_are_joined(tmp_path):
    """A V-HACD-style decomposition written as one OBJ: convex pieces meant to touch, 5 um apart."""
    pieces = [_box((0.04, 0.03, 0.02)), _box((0.02, 0.03, 0.02), (0.03 + 5e-6, 0.0, 0.0))]
    pieces.append(_box((0.04, 0.03, 0.01), (0.01, 0.0, 0.015 + 3e-6)))
    both = trimesh.util.concatenate(pieces)
    path = tmp_path / "vhacd.obj"
    path.write_text(_obj_text(both.vertices, both.faces, [np.arange(12 * k, 12 * k + 12) for k in range(3)]))
    record = import_mesh(path, set_name="corpus", name="vhacd", root=tmp_path / "objs")
    assert any(re.search(r"3 gaps of up to 0.005 mm between pieces closed", n) for n in record.params["repairs"])
    expected = 0.04 * 0.03 * 0.02 + 0.02 * 0.03 * 0.02 + 0.04 * 0.03 * 0.01
    assert record.volume == pytest.approx(expected, rel=2e-3)
    mesh = record.mesh()
    assert mesh.is_watertight and len(mesh.split(only_watertight=False)) == 1


def _kept_apart(solid, pieces: int, volume: float, warning: str) -> None:
    """`solid` keeps `pieces` separate closed pieces of `volume` in all, with `warning` (a regex)."""
    assert solid.mesh.is_watertight and len(solid.mesh.split(only_watertight=False)) == pieces
    assert solid.mesh.volume == pytest.approx(volume, rel=1e-6)
    assert any(re.search(warning, w) for w in solid.warnings), solid.warnings


def test_a_gap_wider_than_an_assemblys_clearance_is_kept_apart():
    from suctionbench.objects.repair import assembly_clearance

    # A 60.9 mm object: ISO 2768-m permits +-0.3 mm on 30-120 mm, so two facing surfaces of a made
    # part may close a drawn gap of 0.6 mm between them; 0.9 mm is a real gap: two pieces, kept
    # apart as one rigid body (nothing bridged, so the volume is the two cubes').
    assert assembly_clearance(0.0609) == pytest.approx(0.0006)
    mesh = trimesh.util.concatenate([_box((0.03, 0.03, 0.03)), _box((0.03, 0.03, 0.03), (0.0309, 0, 0))])
    _kept_apart(_solid(mesh), 2, 2 * 0.03**3, r"^2 separate pieces \(the nearest 0.9 mm from the largest, beyond the "
                r"0.6 mm a made part this size closes\) kept as one rigid body")


def test_parts_of_an_assembly_drawn_with_clearance_are_joined():
    # A 0.5 m plate on a 0.2 m block, drawn 1.2 mm above it (as CAD assemblies leave clearances):
    # the object is 0.5 m, where ISO 2768-m permits +-0.8 mm, so a made part closes up to 1.6 mm:
    # one body. The bridge fills at most the gap over the block's top (0.2 x 0.2 m x 1.2 mm =
    # 48 cm^3) and removes nothing, so the volume lies between the pieces' sum and that plus 48 cm^3.
    from suctionbench.objects.repair import assembly_clearance

    assert assembly_clearance(0.5) == pytest.approx(0.0016) and assembly_clearance(0.005) == pytest.approx(0.0002)
    block = _box((0.2, 0.2, 0.1))
    plate = _box((0.5, 0.3, 0.01), (0.0, 0.0, 0.05 + 0.0012 + 0.005))
    solid = _solid(trimesh.util.concatenate([block, plate]))
    assert solid.mesh.is_watertight and len(solid.mesh.split(only_watertight=False)) == 1
    pieces = 0.2 * 0.2 * 0.1 + 0.5 * 0.3 * 0.01
    assert pieces <= solid.mesh.volume <= pieces + 0.2 * 0.2 * 0.0012 * 1.01
    assert any(re.search(r"1 gap of up to 1.2 mm between pieces closed \(up to 1.6 mm", n) for n in solid.notes)
    far = _solid(trimesh.util.concatenate([block, _box((0.5, 0.3, 0.01), (0.0, 0.0, 0.05 + 0.002 + 0.005))]))
    _kept_apart(far, 2, pieces, r"the nearest 2 mm from the largest, beyond the 1.6 mm")  # 2 mm: a real gap


def test_loose_crumbs_are_dropped_but_a_second_piece_is_kept():
    from suctionbench.objects.repair import LOOSE_MAX

    main = _box((0.05, 0.04, 0.03))
    crumb = _box((0.004,) * 3, (0.06, 0.0, 0.0))  # 0.1 % of the volume, 33 mm away
    solid = _solid(trimesh.util.concatenate([main, crumb]))
    assert solid.mesh.volume == pytest.approx(main.volume)
    assert any("1 loose piece dropped (0.11% of the volume" in note for note in solid.notes), solid.notes
    side = (LOOSE_MAX * 2 * main.volume) ** (1 / 3)  # twice the share that counts as crumbs
    second = _solid(trimesh.util.concatenate([main, _box((side,) * 3, (0.06, 0.0, 0.0))]))
    _kept_apart(second, 2, main.volume + side**3, r"^2 separate pieces \(the nearest 29.7 mm from the largest")
    assert not any("dropped" in note for note in second.notes), second.notes


def _walls(outer: float, wall: float) -> trimesh.Trimesh:
    """Six overlapping slabs making a closed box of side `outer` with walls `wall` thick: their union
    encloses a sealed cubic void of side outer - 2 wall."""
    slabs = []
    for axis in range(3):
        for sign in (-1, 1):
            extents = [outer] * 3
            extents[axis] = wall
            offset = [0.0] * 3
            offset[axis] = sign * (outer - wall) / 2
            slabs.append(_box(extents, offset))
    return trimesh.util.concatenate(slabs)


def test_a_small_void_between_united_pieces_is_filled_a_large_one_kept_hollow():
    # Six 5 mm slabs round a 40 mm void: the void is (40/50)^3 = 51.2 % of the volume within the
    # outer surface, no slab holds it, so the object is the 50 mm box with 64 cm^3 of air inside.
    solid = _solid(_walls(0.05, 0.023))  # a 4 mm void in a 50 mm block: 0.05 %
    assert solid.mesh.volume == pytest.approx(0.05**3, rel=1e-6)
    assert len(solid.mesh.split(only_watertight=False)) == 1 and solid.cavities is None
    assert any("1 sealed void between united pieces filled (0.05% of the volume)" in n for n in solid.notes)
    hollow = _solid(_walls(0.05, 0.005))
    assert hollow.mesh.volume == pytest.approx(0.05**3, rel=1e-6)
    assert len(hollow.mesh.split(only_watertight=False)) == 1
    assert hollow.cavities.volume == pytest.approx(-(0.04**3), rel=1e-6)
    assert any("1 sealed void between united pieces (51.2% of the volume" in n and "kept hollow" in n
               for n in hollow.notes), hollow.notes


def test_a_cavity_modelled_facing_inwards_stays_hollow_in_the_mass(tmp_path):
    """A 80 x 60 x 100 mm box with a 40 mm cubic cavity written as a second closed surface facing
    inwards (as CAD writes a sealed hollow), the cavity's centre 15 mm along +x.

    Derivation, uniform density (a given mass is spread uniformly over the material): the material
    is the box less the cavity, V = 480 - 64 = 416 cm^3, and its centre of mass is the box's (the
    origin) less the cavity's moment: x = -(64 cm^3 x 15 mm) / 416 cm^3 = -2.3077 mm, y = z = 0.
    Before, the inward surface was turned outwards and united with the box: the cavity was filled
    (480 cm^3, centre at the origin). The same cavity written facing outwards is a second solid
    inside the first (overlap), and stays united as before."""
    cavity = _box((0.04, 0.04, 0.04), (0.015, 0.0, 0.0))
    cavity.invert()
    path = tmp_path / "hollow.stl"
    trimesh.util.concatenate([_box((0.08, 0.06, 0.1)), cavity]).export(path)
    record = import_mesh(path, set_name="custom", name="hollow", mass=0.2, root=tmp_path / "objs")
    assert record.volume == pytest.approx(416e-6, rel=1e-6)  # float32 STL vertices
    assert record.com == pytest.approx([-0.96e-6 / 416e-6, 0.0, 0.0], abs=1e-7)
    assert record.density == pytest.approx(0.2 / 416e-6, rel=1e-6)
    assert any("1 sealed cavity modelled inside (13.33% of the volume" in n for n in record.params["repairs"])
    mesh = record.mesh()  # the object's surface is the outer one: what the cup and the camera meet
    assert mesh.volume == pytest.approx(480e-6, rel=1e-6) and len(mesh.split(only_watertight=False)) == 1
    cavity.invert()
    solid = _solid(trimesh.util.concatenate([_box((0.08, 0.06, 0.1)), cavity]))
    assert solid.cavities is None and solid.mesh.volume == pytest.approx(480e-6, rel=1e-6)


def test_pieces_touching_along_an_edge_stay_closed_when_vertices_are_merged():
    """Two boxes that share only an edge: united, the edge's vertices appear twice (one per box); every
    later reader merges vertices by position, which made the edge non-manifold (4 faces)."""
    from suctionbench.objects.repair import unpinch

    mesh = trimesh.util.concatenate([_box((0.02,) * 3), _box((0.02,) * 3, (0.02, 0.02, 0.0))])
    solid = _solid(mesh)
    merged = solid.mesh.copy()
    merged.merge_vertices()
    assert merged.is_watertight and merged.is_winding_consistent
    assert merged.volume == pytest.approx(2 * 0.02**3, rel=1e-3)
    # unpinch itself: a closed mesh with the shared edge's vertices doubled
    pinched = trimesh.util.concatenate([_box((0.02,) * 3), _box((0.02,) * 3, (0.02, 0.02, 0.0))])
    assert not _merged_watertight(pinched)
    assert _merged_watertight(unpinch(pinched))
    assert unpinch(_box((0.02,) * 3)).vertices.tolist() == _box((0.02,) * 3).vertices.tolist()


def _merged_watertight(mesh: trimesh.Trimesh) -> bool:
    merged = trimesh.Trimesh(mesh.vertices, mesh.faces, process=False)
    merged.merge_vertices()
    return bool(merged.is_watertight)


@pytest.mark.slow
def test_pybullet_random_objects_and_vhacd_meshes_import(tmp_path):
    """pybullet's random grasping objects and V-HACD collision meshes (convex pieces micrometres
    apart): every one is one closed solid after repair (before gaps were closed: 0 of 25)."""
    pybullet_data = pytest.importorskip("pybullet_data", reason="pip install pybullet (the mesh corpus extra)")
    from suctionbench.geometry.mesh import load_mesh
    from suctionbench.objects.repair import solidify

    root = Path(pybullet_data.getDataPath())
    meshes = [(root / "random_urdfs" / f"{i:03d}" / f"{i:03d}.obj", 0.015) for i in range(0, 1000, 50)]
    meshes += [(root / "duck_vhacd.obj", 0.05), (root / "laikago" / "upper_leg_left_vhacd.obj", 1.0)]
    meshes += [(p, 1.0) for p in sorted((root / "xarm").rglob("link[2-4]_vhacd*.obj"))]
    for path, scale in meshes:
        solid = solidify(load_mesh(path, scale=scale).mesh, source=str(path))
        merged = solid.mesh.copy()
        merged.merge_vertices()
        assert merged.is_watertight and len(merged.split(only_watertight=False)) == 1, path


def test_self_intersection_counts_by_the_share_of_the_object_it_doubles():
    """A CAD export's sliver body that passes through itself (a camera model had one of 0.4 mm) does not
    change the object's mass; the same surface as the whole object does."""
    t = np.linspace(0.15, 2 * np.pi - 0.15, 80)
    curl = _tube(np.stack([0.04 * np.cos(t), 0.025 * np.sin(2 * t), np.zeros_like(t)], axis=1), 0.008)
    with pytest.raises(InputError, match=r"self-intersecting surface: it encloses about \d+% of the object's volume"):
        _solid(curl)
    sliver = curl.copy().apply_scale(0.05)  # 4 mm across, inside a 50 mm box
    box = _box((0.05, 0.05, 0.05))
    solid = _solid(trimesh.util.concatenate([box, sliver]))
    assert solid.mesh.volume == pytest.approx(box.volume, rel=1e-6)


def test_a_flat_closed_pair_of_faces_is_not_a_body_to_unite():
    """Two back-to-back triangles are watertight with no volume; as a 'closed body' they made manifold3d's
    union of a robot chassis come out empty."""
    pieces = [_box((0.04, 0.03, 0.02)), _box((0.02, 0.02, 0.02), (0.03, 0.0, 0.0))]
    corners = [[0.26125, 0.09226, 0.006025], [0.26125, 0.092034, 0.006216], [0.26125, 0.091807, 0.006407]]
    flat = trimesh.Trimesh(corners, [[0, 1, 2], [0, 2, 1]], process=False)  # as in pybullet's laikago chassis
    solid = _solid(trimesh.util.concatenate([*pieces, flat]))
    assert solid.mesh.volume == pytest.approx(0.04 * 0.03 * 0.02 + 0.02**3, rel=1e-5)
    assert any("1 open body dropped" in note for note in solid.notes), solid.notes


def test_a_sliver_thinner_than_the_gap_it_is_snapped_across_does_not_stop_the_union():
    """A 2 um-thick closed slab 5 um above a box (as a1's thigh mesh has): snapped across, both its faces
    pass through each other and it turns inside out; it stays as it was instead and is dropped as a crumb."""
    box = _box((0.04, 0.04, 0.04))
    slab = _box((0.01, 0.01, 2e-6), (0.0, 0.0, 0.02 + 5e-6 + 1e-6))
    solid = _solid(trimesh.util.concatenate([box, slab]))
    assert solid.mesh.volume == pytest.approx(box.volume, rel=1e-6)
    assert any("loose piece dropped" in note for note in solid.notes), solid.notes


def _cracked_box(extents, crack: float) -> trimesh.Trimesh:
    """A box as a render mesh: each face its own patch with its own vertices, shrunk towards its
    centre so that neighbouring patches stay `crack` apart along every edge (no shared vertex, no
    shared edge: every edge is open)."""
    box = _box(extents)
    patches = []
    for facet in box.facets:  # the six faces, two triangles each
        faces = box.faces[facet]
        corners = np.unique(faces)
        centre = box.vertices[corners].mean(axis=0)
        vertices = box.vertices.copy()
        for c in corners:  # move each corner in along both of its face's edges by crack / 2
            offset = centre - vertices[c]
            vertices[c] += np.sign(offset) * np.where(np.abs(offset) > 1e-12, crack / 2, 0.0)
        patch = trimesh.Trimesh(vertices, faces, process=False)
        patch.remove_unreferenced_vertices()
        patches.append(patch)
    return trimesh.util.concatenate(patches)


def test_a_cracked_render_mesh_is_rebuilt_as_the_solid_it_bounds():
    from suctionbench.objects.repair import solidify

    extents, crack = np.array([0.06, 0.04, 0.03]), 0.0003
    cracked = _cracked_box(extents, crack)
    assert not cracked.is_watertight and len(cracked.split(only_watertight=False)) == 6
    solid = solidify(cracked, "cracked box")
    assert "rebuilt as the solid the surface bounds" in solid.notes[0]
    merged = solid.mesh.copy()
    merged.merge_vertices()
    assert merged.is_watertight and len(merged.split(only_watertight=False)) == 1
    # The level set of the winding number lies on the faces (1/2 on a closed surface; a 0.3 mm crack
    # only moves it within about a crack's width of the crack) and its vertices are snapped onto them,
    # so the solid is the box but along its edges, where marching cubes cuts each of the 12 edges by
    # at most a cell (0.06 / 96 m) in both directions: a lost volume of at most sum(edge) * cell^2 / 2
    # = 0.52 m * (0.625 mm)^2 / 2 = 1.0e-7 m^3, 0.14 % of the box.
    cell = extents.max() / 96
    lost = 4 * extents.sum() * cell**2 / 2
    assert abs(solid.mesh.volume - np.prod(extents)) <= lost
    assert solid.mesh.bounds == pytest.approx(np.array([-extents / 2, extents / 2]), abs=cell)
    # the faces come back flat: every vertex lies on the box's surface within float rounding
    distance = np.min(np.abs(np.abs(solid.mesh.vertices) - extents / 2), axis=1)
    assert np.quantile(distance, 0.95) < 1e-9


def test_a_cracked_surface_turned_inside_out_is_read_the_other_way_round():
    from suctionbench.objects.repair import solidify

    cracked = _cracked_box((0.05, 0.05, 0.05), 0.0002)
    cracked.invert()
    assert solidify(cracked, "inverted").mesh.volume == pytest.approx(0.05**3, rel=0.01)


def test_an_opening_is_not_rebuilt_and_says_how_undecided_the_inside_is():
    from suctionbench.objects.repair import solidify
    from suctionbench.objects.winding import AMBIGUOUS_MAX, rebuild_from_winding

    cup = trimesh.creation.cylinder(radius=0.03, height=0.06, sections=32)  # without its top: a cup,
    cup.update_faces(cup.face_normals[:, 2] < 0.5)  # whose inside no surface decides
    rebuilt, ambiguous = rebuild_from_winding(cup)
    assert rebuilt is None and ambiguous > AMBIGUOUS_MAX
    with pytest.raises(InputError, match=r"not watertight: 1 hole.*leaves \d+% of the volume undecided"):
        solidify(cup, "cup")


def test_a_convex_part_without_volume_is_left_out_not_a_crash():
    # CoACD can hand back a stray triangle (3 distinct points, the same point repeated): it bounds no
    # volume, so it has no convex hull (qhull needs 4 points off one plane). A 350-face random object
    # of pybullet's hit it and failed with an internal QhullError; it is left out, and a run that
    # returned only such parts counts as a failed run (the next threshold is tried).
    from suctionbench.objects.build import _hulls
    from suctionbench.objects.decompose import CoacdFailed

    box = trimesh.creation.box((0.02, 0.03, 0.04))
    triangle = (np.array([[0, 0, 0], [0.01, 0, 0], [0, 0.01, 0], [0, 0, 0]], float), np.array([[0, 1, 2], [3, 1, 2]]))
    parts = _hulls([(np.asarray(box.vertices), np.asarray(box.faces)), triangle])
    assert len(parts) == 1 and parts[0].volume == pytest.approx(0.02 * 0.03 * 0.04)
    with pytest.raises(CoacdFailed, match="none of its 2 parts bounds a volume"):
        _hulls([triangle, triangle])
