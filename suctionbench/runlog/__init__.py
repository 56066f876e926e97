"""Run logs: one MCAP file per pick episode, viewable in Foxglove and readable back in pure Python.

Why MCAP + JSON, written with the plain `mcap` package
-----------------------------------------------------
Every channel is ``message_encoding="json"`` with a ``jsonschema`` schema. Where a Foxglove
well-known schema exists (``foxglove.RawImage``, ``foxglove.CameraCalibration``,
``foxglove.FrameTransforms``, ``foxglove.SceneUpdate``) the channel carries that schema name and
Foxglove's *published* JSON Schema, vendored unchanged from the ``@foxglove/schemas`` npm package
(``runlog/schemas/``, version and licence in its README), and every message satisfies it, required
fields included, so strict consumers (the TypeScript ``@foxglove/schemas`` + ajv, Python
``jsonschema``) accept the log and Foxglove's Image and 3D panels render it directly; bytes fields
(the depth image, and a dense policy's quality map on ``/grasps/quality_map``, a 32FC1 image of
q per pixel, NaN where unscored) are base64 strings tagged ``contentEncoding: base64``, which is
how Foxglove reads bytes in JSON. Our own records (joint states, grasp table, suction state, episode result) are
``suctionbench.*`` JSON schemas in the same style (one type per field, ``properties`` on every
object, ``required`` for what is always there).

The alternatives were weighed and rejected:

* ``foxglove-sdk`` writes protobuf through a compiled (Rust) extension with a process-global
  logging context; its Python schema module was being renamed (``foxglove.schemas`` ->
  ``foxglove.messages``) at the time of writing, and reading the logs back would need
  ``protobuf`` + ``mcap-protobuf-support`` to rebuild message classes from embedded descriptors.
* Protobuf by hand needs the generated Foxglove ``.proto`` classes as a further dependency.

JSON needs no code generation, decodes with ``json.loads`` (so ``reader`` works on any machine
with only ``mcap`` installed), keeps every float exactly (Python writes the shortest repr that
round-trips), and is readable with ``mcap cat --json``. The cost is size: base64 adds a third
to the depth image, which zstd chunk compression (on by default in ``mcap``) largely recovers;
an episode with one 640x480 float32 depth frame and ~100 states of each kind is ~1.1 MB when the
depth carries sensor noise (its low mantissa bits are incompressible), ~0.05 MB noise-free.

Times
-----
Log time (and publish time) of every message is the episode's *simulated* time in integer
nanoseconds, so a log replays the episode at the speed of the simulation, independent of how
fast the host computed it. Message ``timestamp`` fields carry the same time.

Run metadata (config, versions, seed, ...) is an MCAP metadata record named ``suctionbench``
with plain string values (``mcap`` metadata is string -> string): strings as themselves, numbers,
booleans and tables as JSON text; a record ``suctionbench.types`` says which is which, and the
reader restores the types (logs written before it, all JSON text, still read).
"""

from suctionbench.runlog.reader import depth_image, float_image, grasp_table, iter_messages, read_episode, read_run
from suctionbench.runlog.writer import EpisodeLog

__all__ = ["EpisodeLog", "depth_image", "float_image", "grasp_table", "iter_messages", "read_episode", "read_run"]
