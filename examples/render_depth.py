"""Render a depth image of a simulated pick scene to try `suctionbench plan` on.

    .venv/bin/python examples/render_depth.py --object typical/mug_classic --seed 2 --out scene.png
    .venv/bin/suctionbench plan --depth scene.png --camera primesense --out grasp.png

Writes a 16-bit PNG in millimetres (0 = no return), the convention of RealSense and OpenNI
cameras, of the overhead camera's view (with the simulated sensor's noise) after the object was
dropped on the table; `--npy` writes float32 metres instead.
"""

import argparse

import numpy as np
from PIL import Image

from suctionbench.sim.pick import PickRequest, PickRunner


def main(object_key: str, seed: int, out: str, camera: str) -> None:
    runner = PickRunner(PickRequest(object_key, seed=seed, camera=camera))
    runner.reset()  # drop the object and let it settle
    depth = runner.observe().depth  # metres, float32
    if out.endswith(".npy"):
        np.save(out, depth)
    else:
        Image.fromarray(np.round(depth * 1000.0).astype(np.uint16)).save(out)
    print(f"{out}: {depth.shape[1]} x {depth.shape[0]} depth image of {object_key} ({camera})")


if __name__ == "__main__":
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--object", dest="object_key", default="typical/mug_classic")
    parser.add_argument("--seed", type=int, default=2)
    parser.add_argument("--camera", default="primesense")
    parser.add_argument("--out", default="scene.png", help="a .png (16-bit millimetres) or .npy (float metres)")
    main(**vars(parser.parse_args()))
