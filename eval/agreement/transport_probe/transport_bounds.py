"""Planned transport times of random straight transports from the workspace, and which bound sets
each: the joints' speed limits (`PickEpisode._duration`), the cup's rated acceleration
(T = sqrt(5.774 L / a_rated)) or the shortest transport (EpisodeConfig.transport_min_time); and the
planned peak acceleration 5.774 L / T^2 the episode's labeller takes.

Usage: python eval/agreement/transport_probe/transport_bounds.py [COUNT] [MAX_TILT_DEG]  (300 45:
IK only, no physics, ~1 min). Lift ends within 10 cm of the workspace centre, 0.15-0.3 m high,
tools up to MAX_TILT_DEG off vertical (uniform over the cap's area), seeded.
"""

from __future__ import annotations

import math
import sys

import numpy as np

from suctionbench import minjerk
from suctionbench.sim.episode import CARRY_STEP
from suctionbench.sim.pick import PickRequest, PickRunner


def main(count: int, max_tilt_deg: float) -> None:
    runner = PickRunner(PickRequest("basic/box_brick", seed=0))
    runner.reset()
    episode = runner.episode
    rng = np.random.default_rng(0)
    end = episode._above_bin()
    cx, cy = episode.scene.config.workspace_centre
    rated = episode.scene.cup.cup.peak_acceleration
    rows = []
    for _ in range(count):
        tilt, azimuth = math.radians(max_tilt_deg) * math.sqrt(rng.random()), 2 * math.pi * rng.random()
        approach = np.array([math.sin(tilt) * math.cos(azimuth), math.sin(tilt) * math.sin(azimuth), -math.cos(tilt)])
        start = np.array([cx + rng.uniform(-0.1, 0.1), cy + rng.uniform(-0.1, 0.1), rng.uniform(0.15, 0.3)])
        try:
            q_up = episode._ik(start, approach, episode._ready_configuration())
            path = episode._line(start, end, approach, q_up, step=CARRY_STEP)
        except Exception:  # out of reach: no transport to time
            continue
        length = float(np.linalg.norm(end - start))
        duration = episode._carry_time(path, length)
        bounds = (episode._duration(path, 0.0), math.sqrt(minjerk.PEAK_ACCELERATION * length / rated),
                  episode.config.transport_min_time)
        rows.append((duration, int(np.argmax(bounds)), minjerk.PEAK_ACCELERATION * length / duration**2))
    times, setter, peaks = (np.array(column) for column in zip(*rows, strict=True))
    print(f"{len(rows)} transports; time (s) min / 10 % / median / 90 % / max:",
          np.round(np.percentile(times, [0, 10, 50, 90, 100]), 3))
    print("set by the joints' speed limits / the rated acceleration / the shortest transport:",
          [f"{np.mean(setter == k):.1%}" for k in range(3)])
    print("planned peak acceleration (m/s^2) min / 10 % / median / 90 % / max:",
          np.round(np.percentile(peaks, [0, 10, 50, 90, 100]), 2))


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 300, float(sys.argv[2]) if len(sys.argv) > 2 else 45.0)
