"""Time dataset assembly (units -> shards) of a generated dataset's first units with the code on a
given path, e.g. the current code against an older one checked out by `git archive REV suctionbench
| tar -x -C OLD`:

    python eval/dataset/assembly_time.py . DATASET 1
    python eval/dataset/assembly_time.py OLD DATASET 1

Writes the shards into a temporary folder in the working directory and removes it; the dataset is
only read."""

import shutil
import sys
import tempfile
import time
from pathlib import Path

code, dataset, count = sys.argv[1], Path(sys.argv[2]).resolve(), int(sys.argv[3])
sys.path.insert(0, code)
from suctionbench.dataset import generate as gen  # noqa: E402
from suctionbench.dataset.storage import DatasetWriter  # noqa: E402

tmp = Path(tempfile.mkdtemp(dir="."))
try:
    (tmp / "units").mkdir()
    units = []
    for index in range(count):
        source = gen.unit_path(dataset, index)
        (tmp / "units" / source.name).symlink_to(source)
        units.append(gen.Unit(index, quota=0))  # assembly counts each unit's datapoints itself
    per_shard = 1000
    start = time.perf_counter()
    stats = gen._assemble_shards(tmp, units, DatasetWriter(tmp, datapoints_per_shard=per_shard), per_shard, 0.2,
                                 threads=2)
    print(f"{code}: {count} units, {stats['shards']} shards, {time.perf_counter() - start:.1f} s")
finally:
    shutil.rmtree(tmp)
