"""`suctionbench pick` (one simulated episode) and `suctionbench view` (the interactive viewer)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Annotated, Any

import numpy as np
import typer

from suctionbench.cli.common import JsonOpt, SeedOpt, app, parse_vector, print_kv, run_command
from suctionbench.cli.plan import PolicyArgOpt
from suctionbench.errors import InputError
from suctionbench.validate import BYTES_PER_TRIAL_LOG, output_file, require_disk


@app.command()
def pick(
    object_key: Annotated[str, typer.Option("--object", help="Object SET/NAME, e.g. basic/box_tea.")],
    grasp: Annotated[
        str | None, typer.Option(help="Grasp 'x,y,z,vx,vy,vz' in the object's own frame (default: --policy).")
    ] = None,
    policy: Annotated[
        str, typer.Option(help="Policy when no --grasp: analytic, analytic-image, analytic-image-uniform, "
                               "random-surface (known state) or an image policy (random, centroid, planarity, "
                               "planarity-centroid, gqcnn, an installed plug-in's name, PATH.py:FACTORY or "
                               "package.module:FACTORY).")
    ] = "analytic",
    policy_arg: PolicyArgOpt = None,
    model: Annotated[str | None, typer.Option(help="GQ-CNN model directory (gqcnn policy).")] = None,
    metric: Annotated[str, typer.Option(help="3D metric of the analytic policy: rwr, wr, ss, pc3d.")] = "rwr",
    placement: Annotated[str, typer.Option(help="drop (random orientation) or stable (most probable pose).")] = "drop",
    cup: Annotated[str, typer.Option(help="Cup preset: default or paper.")] = "default",
    camera: Annotated[str, typer.Option(help="Camera preset or intrinsics TOML.")] = "primesense",
    render: Annotated[Path | None, typer.Option(help="Save the overhead colour view before the pick (PNG).")] = None,
    log: Annotated[Path | None, typer.Option(help="Write the episode to this MCAP file (Foxglove).")] = None,
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Run one simulated pick episode with the YuMi and report its outcome."""

    def body() -> dict[str, Any]:
        from suctionbench.config import cup_preset
        from suctionbench.policies.plugins import parse_policy_args
        from suctionbench.sim.pick import PickRequest, PickRunner

        if log is not None:  # the outputs before the episode: a refused one costs no simulation
            if log.suffix != ".mcap":
                raise InputError(f"--log '{log}': expected a .mcap file name")
            output_file(log, "--log")
            require_disk(log, BYTES_PER_TRIAL_LOG, "--log")
        if render is not None:
            output_file(render, "--render")
        values = None
        if grasp is not None:
            values = parse_vector(grasp, 6, "--grasp")
            if abs(np.linalg.norm(values[3:]) - 1.0) > 1e-3:
                raise InputError(f"--grasp approach {values[3:].tolist()}: must be a unit vector")
            from suctionbench.objects.registry import load_object
            from suctionbench.validate import grasp_near_surface

            grasp_near_surface(load_object(object_key).mesh(), values[:3], "--grasp point", f"'{object_key}'")
        request = PickRequest(
            object_key, seed=seed, grasp=values, policy=policy, placement=placement, cup=cup_preset(cup),
            camera=camera, model=model, metric=metric, policy_args=parse_policy_args(policy_arg or []),
        )
        result = PickRunner(request).run(render=render, log=log)
        if not as_json:
            print_kv(f"pick {object_key}", result)
        return result

    run_command(as_json, body)


@app.command()
def view(
    object_key: Annotated[str, typer.Option("--object", help="Object SET/NAME.")] = "basic/box_tea",
    seed: SeedOpt = 0,
    as_json: JsonOpt = False,
) -> None:
    """Open the scene in MuJoCo's interactive viewer (needs a display)."""

    def body() -> dict[str, Any]:
        if not os.environ.get("DISPLAY") and not os.environ.get("WAYLAND_DISPLAY"):
            raise InputError("view: no display found (set DISPLAY); use `pick --render FILE.png` on a server")
        import mujoco.viewer

        from suctionbench.sim.pick import PickRequest, PickRunner

        runner = PickRunner(PickRequest(object_key, seed=seed))
        runner.episode.reset(np.random.default_rng(seed))
        mujoco.viewer.launch(runner.scene.model, runner.episode.data)
        return {"object": object_key, "seed": seed}

    run_command(as_json, body)
