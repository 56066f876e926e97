"""`suctionbench plan` (a grasp on the user's own depth image) and `suctionbench cameras` (the presets)."""

from __future__ import annotations

from pathlib import Path
from typing import Annotated, Any

import typer

from suctionbench.cli.common import JsonOpt, SeedOpt, app, console, print_rows, run_command

PolicyArgOpt = Annotated[
    list[str] | None,
    typer.Option("--policy-arg", help="key=value option of the policy's factory (repeatable)."),
]
"""`--policy-arg key=value`, shared by the commands that take `--policy`."""

POLICY_HELP = ("Policy: gqcnn, planarity-centroid, centroid, planarity, random, an installed plug-in's name, "
               "PATH.py:FACTORY or package.module:FACTORY.")
"""Help of `--policy` for image policies."""


@app.command()
def plan(
    depth: Annotated[
        Path, typer.Option(help="Depth image: .npy (float m or integer mm), 16-bit PNG (mm), float TIFF (m).")
    ],
    camera: Annotated[str, typer.Option(help="Camera preset (suctionbench cameras) or intrinsics TOML.")],
    mask: Annotated[Path | None, typer.Option(help="Object pixels: .npy or image, non-zero = object.")] = None,
    camera_pose: Annotated[
        Path | None, typer.Option(help="World-from-camera 4x4 (.npy, .json, text), table at z = --table-height; "
                                       "default: fit the support plane (RANSAC).")
    ] = None,
    policy: Annotated[str, typer.Option(help=POLICY_HELP)] = "gqcnn",
    policy_arg: PolicyArgOpt = None,
    model: Annotated[str | None, typer.Option(help="GQ-CNN model directory (default: the shipped one).")] = None,
    depth_scale: Annotated[
        float | None, typer.Option(help="Metres per stored depth unit (default: 1 for float, 0.001 for integers).")
    ] = None,
    table_height: Annotated[float, typer.Option(help="Table height (m) in the --camera-pose world.")] = 0.0,
    out: Annotated[Path | None, typer.Option(help="Draw the grasp on the depth image (PNG).")] = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Plan a suction grasp on your own depth image: point and approach in the camera frame, pixel, q."""

    def body() -> dict[str, Any]:
        from suctionbench.planning import plan_files
        from suctionbench.policies.plugins import parse_policy_args

        result = plan_files(depth, camera, mask=mask, camera_pose=camera_pose, policy=policy,
                            policy_args=parse_policy_args(policy_arg or []), model=model, seed=seed,
                            depth_scale=depth_scale, table_height=table_height, out=out)
        if not as_json:
            screen = console()
            q = "nan" if result["q"] is None else f"{result['q']:.3f}"
            screen.print(f"grasp ({result['policy']}, {result['camera']}): q = {q}, pixel (u, v) = "
                         f"({result['pixel'][0]:.0f}, {result['pixel'][1]:.0f})")
            screen.print(f"  point    (camera frame, m) = {_vector(result['point'])}")
            screen.print(f"  approach (camera frame)    = {_vector(result['approach'])}")
            plane = result["plane"]
            support = (f"fitted plane, normal {_vector(plane['normal'])}, {100 * plane['inlier_fraction']:.0f} % "
                       f"of the pixels" if plane else "the given camera pose")
            screen.print(f"  support: {support}; object pixels: {result['object_pixels']}; "
                         f"{1000 * result['timings']['total']:.0f} ms")
            if out is not None:
                screen.print(f"  drawn -> {out}")
        return result

    run_command(as_json, body)


def _vector(values: list[float]) -> str:
    return "(" + ", ".join(f"{v:+.4f}" for v in values) + ")"


@app.command()
def cameras(
    toml: Annotated[
        str | None, typer.Option(help="Print this preset (or TOML file) as an intrinsics TOML, a template.")
    ] = None,
    as_json: JsonOpt = False,
) -> None:
    """The camera presets with intrinsics, field of view and working range (--camera takes them or a TOML)."""

    def body() -> dict[str, Any]:
        from suctionbench.sensing.camera import CAMERA_PRESETS, camera_summary, intrinsics_to_toml, resolve_camera

        if toml is not None:
            text = intrinsics_to_toml(resolve_camera(toml))
            if not as_json:
                print(text, end="")
            return {"toml": text}
        rows = [camera_summary(c) for c in CAMERA_PRESETS.values()]
        if not as_json:
            print_rows("camera presets (pixels; fov in degrees, range in metres)", [
                {"name": r["name"] + (" *" if r["default"] else ""), "size": f"{r['width']}x{r['height']}",
                 "f": f"{r['fx']:g}" if r["fx"] == r["fy"] else f"{r['fx']:g},{r['fy']:g}",
                 "centre": f"{r['cx']:g},{r['cy']:g}", "fov": f"{r['hfov_deg']:g}x{r['vfov_deg']:g}",
                 "range": f"{r['min_depth']:g}-{r['max_depth']:g}"}
                for r in rows])
            console().print("* default. Your camera: --camera FILE.toml; start from "
                            "suctionbench cameras --toml PRESET > FILE.toml")
        return {"cameras": rows}

    run_command(as_json, body)  # with --toml and no --json, stdout is the TOML alone (`> my_camera.toml`)
