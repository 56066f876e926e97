"""Share of a mixed corpus of third-party meshes that `suctionbench objects import` takes with its
default options, and how long each import takes.

Each mesh is imported by the CLI as a user would (`suctionbench objects import FILE --json`, a
fresh process per mesh, into a temporary root), with no option but the scale its package declares
for it (a URDF's `<mesh scale=...>` or an SDF's `<scale>`; units are a fact about the file, not a
repair option). A file declared at several uniform scales counts once per scale (each is an object
the package defines, e.g. a 5 cm and a 1 m cube); one declared at none, or only at non-uniform
scales (which import cannot take), counts once as written.

Groups (--groups, comma-separated):
  synthetic  the repairable meshes of tests/test_import.py's corpus that need no option (textured
             OBJ/GLB seams, touching and overlapping pieces, non-manifold edges, duplicated faces,
             a stray open sleeve, a small hole, two pieces apart kept as one rigid body, a millimetre
             STL without --units): 14 meshes
  dm_control dm_control's Kinova arm (10 STL) and every 12th dog bone of 1 cm or more (14 STL)
  pybullet   pybullet's pybullet_data (`pip install pybullet==3.2.7`): every OBJ/STL in it but
             the scenes (planes, terrain, a monastery, a stadium, a cloth sheet) and byte-identical
             copies, and of the 1000 random objects every 50th (20); 213 meshes
  ply        every PLY in two robotics packages' wheels (`pip download mani-skill==3.0.1
             rtb-data==2.0.0 --no-deps -d WHEELS`, then --wheels WHEELS): ManiSkill's SO-100 gripper
             collision links, assembly-task parts, an apple in convex pieces and a scanned bowl;
             the Robotics Toolbox's test mesh; 11 meshes

The earlier measurement (94.4 %, 34 of 36) was synthetic + dm_control. A run of all three groups
takes ~40 min on 2 cores (large CAD meshes decompose for minutes); eval/import/README.md has the
commands (two shards at once, then --merge) and the results.
"""

from __future__ import annotations

import argparse
import hashlib
import json
import re
import shutil
import subprocess
import sys
import tempfile
import time
import xml.etree.ElementTree as ET
import zipfile
from pathlib import Path

REPO = Path(__file__).resolve().parents[2]
SCENES = re.compile(r"^(plane\w*|terrain|samurai_monastry|cloth_z_up)\.obj$|roboschool/models_outdoor/stadium/")


def synthetic(folder: Path) -> list[tuple[str, Path, dict]]:
    sys.path.insert(0, str(REPO / "tests"))
    from test_import import build_corpus

    return [(f"synthetic/{c.name}", c.path, {}) for c in build_corpus(folder) if not c.options and c.error is None]


def dm_control_meshes() -> list[tuple[str, Path, dict]]:
    sys.path.insert(0, str(REPO / "tests"))
    from test_import import third_party_meshes

    return [(f"dm_control/{p.parent.name}/{p.name}", p, {}) for p in third_party_meshes()]


def declared_scales(root: Path) -> dict[Path, set[float]]:
    """Uniform scales the package's URDF and SDF files declare for each mesh file (paths relative to
    the model file or to the data root, as pybullet resolves them); non-uniform scales are left out
    (import takes one factor)."""
    scales: dict[Path, set[float]] = {}
    for model in sorted([*root.rglob("*.urdf"), *root.rglob("*.sdf")]):
        try:
            tree = ET.parse(model)
        except ET.ParseError:
            continue
        for mesh in tree.iter("mesh"):
            name, scale = mesh.get("filename"), mesh.get("scale")
            if name is None:  # SDF: <mesh><uri>..</uri><scale>..</scale></mesh>
                name, scale = mesh.findtext("uri"), mesh.findtext("scale")
            if not name or not scale:
                continue
            name = re.sub(r"^(package|model)://[^/]+/", "", name.strip())
            found = [p.resolve() for p in (model.parent / name, root / name) if p.is_file()]
            values = {float(v) for v in scale.split()}
            if found and len(values) == 1:
                scales.setdefault(found[0], set()).add(values.pop())
    return scales


def pybullet_meshes() -> list[tuple[str, Path, dict]]:
    import pybullet_data

    root = Path(pybullet_data.getDataPath()).resolve()
    scales = declared_scales(root)
    seen: set[str] = set()
    out = []
    for path in sorted(p for p in root.rglob("*") if p.suffix.lower() in (".obj", ".stl", ".ply")):
        rel = path.relative_to(root).as_posix()
        if SCENES.search(rel):
            continue
        if rel.startswith("random_urdfs/"):
            number = path.parent.name
            if path.stem != number or int(number) % 50:
                continue
        digest = hashlib.sha256(path.read_bytes()).hexdigest()
        if digest in seen:
            continue
        seen.add(digest)
        for scale in sorted(scales.get(path.resolve(), {1.0})):
            label = f"pybullet/{rel}" + ("" if scale == 1.0 else f"@{scale:g}")
            out.append((label, path, {} if scale == 1.0 else {"scale": scale}))
    return out


PLY_WHEELS = ("mani_skill-3.0.1-py3-none-any.whl", "rtb_data-2.0.0-py3-none-any.whl")
"""The wheels the "ply" group reads (`pip download mani-skill==3.0.1 rtb-data==2.0.0 --no-deps`)."""


def ply_meshes(folder: Path, wheels: Path | None) -> list[tuple[str, Path, dict]]:
    """Every PLY of the `PLY_WHEELS` in `wheels`, at the scales their URDF/SDF files declare."""
    out = []
    for wheel in PLY_WHEELS:
        path = (wheels or Path(".")) / wheel
        if not path.is_file():
            raise SystemExit(f"--wheels {wheels}: no {wheel} (pip download mani-skill==3.0.1 rtb-data==2.0.0 "
                             "--no-deps -d DIR)")
        root = folder / path.stem
        with zipfile.ZipFile(path) as archive:
            for member in archive.namelist():
                if member.lower().endswith((".ply", ".urdf", ".sdf")):
                    archive.extract(member, root)
        scales = declared_scales(root)
        package = wheel.split("-")[0]
        for mesh in sorted(p for p in root.rglob("*") if p.suffix.lower() == ".ply"):
            rel = mesh.relative_to(root).as_posix()
            for scale in sorted(scales.get(mesh.resolve(), {1.0})):
                label = f"ply/{package}/{rel}" + ("" if scale == 1.0 else f"@{scale:g}")
                out.append((label, mesh, {} if scale == 1.0 else {"scale": scale}))
    return out


def run_one(name: str, path: Path, options: dict, root: Path, timeout: float) -> dict:
    cli = Path(sys.executable).parent / "suctionbench"
    slug = re.sub(r"[^a-z0-9_\-]", "_", name.lower())[-60:].strip("_-") or "mesh"
    args = [str(cli), "objects", "import", str(path), "--name", slug, "--root", str(root), "--overwrite", "--json"]
    if "scale" in options:
        args += ["--scale", repr(options["scale"])]
    start = time.perf_counter()
    try:
        done = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
        line = json.loads(done.stdout.strip().splitlines()[-1]) if done.stdout.strip() else {}
        ok, error = bool(line.get("ok")), line.get("error") or (None if line else done.stderr.strip()[-300:])
        repairs, faces, warnings = line.get("repairs", []), line.get("faces"), line.get("warnings", [])
    except subprocess.TimeoutExpired:
        ok, error, repairs, faces, warnings = False, f"timed out after {timeout:g} s", [], None, []
    seconds = time.perf_counter() - start
    return {
        "name": name,
        "options": options,
        "ok": ok,
        "seconds": round(seconds, 2),
        "faces": faces,
        "error": error,
        "repairs": repairs,
        "warnings": warnings,
    }


CAUSES = (
    ("absurd scale", "size outside 5 mm - 1 m as written (units or scale not declared, or a >1 m object)"),
    ("above the mass cap", "heavier than the cup carries at the default density (--mass takes a lighter one)"),
    ("not watertight: ", "an opening wider than 30 % of the object (a shell, a link without its joint face)"),
    ("not watertight (has holes", "repaired, then opened again where merged vertices pinch an edge"),
    ("open bod", "open sheets beside the closed bodies (render meshes: patches that do not meet)"),
    ("disconnected bodies",
     "disconnected pieces (apart by more than a made part closes, twice ISO 2768-m, and > 1 % of the volume)"),
    ("hollow", "a sealed cavity over 1 % of the volume"),
    ("not manifold volumes", "closed pieces manifold3d refuses as volumes"),
    ("leave no closed body", "non-manifold edges leave no closed body"),
    ("self-intersecting", "a self-intersecting surface"),
    ("timed out", "timed out"),
)


def cause(error: str) -> str:
    return next((label for key, label in CAUSES if key in error), "other: " + error[:80])


def summarize(files: list[Path]) -> dict:
    """Merge result files (shards of one run) and count the failures by cause. A mesh in several
    files counts once, as the last file has it (a rerun of some meshes after a change replaces
    their entries)."""
    latest = {r["name"]: r for f in files for r in json.loads(f.read_text())["results"]}
    results = list(latest.values())
    by_group: dict[str, list[dict]] = {}
    for r in results:
        by_group.setdefault(r["name"].split("/")[0], []).append(r)
    causes: dict[str, list[str]] = {}
    for r in results:
        if not r["ok"]:
            causes.setdefault(cause(r["error"] or ""), []).append(r["name"])
    passed = sum(r["ok"] for r in results)
    return {
        "imported": passed,
        "meshes": len(results),
        "share_percent": round(100.0 * passed / max(len(results), 1), 1),
        "by_group": {g: f"{sum(r['ok'] for r in rs)}/{len(rs)}" for g, rs in by_group.items()},
        "failures_by_cause": {c: sorted(n) for c, n in sorted(causes.items(), key=lambda kv: -len(kv[1]))},
        "results": sorted(results, key=lambda r: r["name"]),
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--groups", default="synthetic,dm_control,pybullet")
    parser.add_argument("--only", default="", help="regex on the mesh names")
    parser.add_argument("--failed-in", type=Path, help="only the meshes this results file has as failed, of the "
                        "causes matching --causes")
    parser.add_argument("--causes", default="", help="regex on the failure causes (with --failed-in)")
    parser.add_argument("--wheels", type=Path, help="folder holding the PLY_WHEELS (the ply group)")
    parser.add_argument("--timeout", type=float, default=300.0)
    parser.add_argument("--out", type=Path, help="JSON file with every mesh's outcome")
    parser.add_argument("--merge", type=Path, nargs="+", help="merge these result files (shards) into --out")
    args = parser.parse_args()
    if args.merge:
        merged = summarize(args.merge)
        print(f"imported with default options: {merged['imported']}/{merged['meshes']} = {merged['share_percent']} %")
        for group, count in merged["by_group"].items():
            print(f"  {group}: {count}")
        for label, names in merged["failures_by_cause"].items():
            print(f"  {len(names):3d}  {label}")
        if args.out:
            args.out.write_text(json.dumps(merged, indent=1) + "\n")
        return
    folder = Path(tempfile.mkdtemp(prefix="sb-import-corpus-"))
    makers = {
        "synthetic": lambda: synthetic(folder / "synthetic"),
        "dm_control": dm_control_meshes,
        "pybullet": pybullet_meshes,
        "ply": lambda: ply_meshes(folder / "ply", args.wheels),
    }
    cases = [case for group in args.groups.split(",") for case in makers[group]()]
    cases = [c for c in cases if re.search(args.only, c[0])]
    if args.failed_in:
        failed = json.loads(args.failed_in.read_text())["failures_by_cause"]
        again = {name for label, names in failed.items() if re.search(args.causes, label) for name in names}
        cases = [c for c in cases if c[0] in again]
    results = []
    for name, path, options in cases:
        result = run_one(name, path, options, folder / "objects", args.timeout)
        results.append(result)
        status = "ok" if result["ok"] else f"FAIL {result['error']}"
        print(f"{result['seconds']:7.1f} s  {name}  {status}", flush=True)
    by_group: dict[str, list[dict]] = {}
    for r in results:
        by_group.setdefault(r["name"].split("/")[0], []).append(r)
    summary = {g: f"{sum(r['ok'] for r in rs)}/{len(rs)}" for g, rs in by_group.items()}
    passed = sum(r["ok"] for r in results)
    share = 100.0 * passed / max(len(results), 1)
    print(f"imported with default options: {passed}/{len(results)} = {share:.1f} %  ({summary})")
    shutil.rmtree(folder, ignore_errors=True)
    if args.out:
        args.out.write_text(
            json.dumps(
                {
                    "groups": args.groups,
                    "share_percent": round(share, 1),
                    "imported": passed,
                    "meshes": len(results),
                    "by_group": summary,
                    "results": results,
                },
                indent=1,
            )
            + "\n"
        )


if __name__ == "__main__":
    main()
