"""Keep large temporary arrays in the heap instead of fresh memory maps (glibc's malloc).

Planning allocates and frees arrays of 1-30 MB many times a second (the dense trunk's maps, the
lattices, thumbnail batches). glibc serves every block above its mmap threshold (128 kB at start,
raised to the largest mapped block freed so far, at most 32 MB) with a fresh `mmap`, which the
first write then faults in page by page, and `free` unmaps it again. Measured on 2 cores: a
5 x 5 convolution of 16 x 124 x 122 pixels took 12.4 ms with fresh maps and 2.9 ms in reused
heap memory. `keep_large_blocks` raises the threshold (and the heap's trim threshold) so such
blocks are carved from the heap and reused; the process's peak memory is unchanged, but up to
`trim` bytes of freed heap stay mapped. The command line calls it at start; a program embedding
the policies may call it too.
"""

from __future__ import annotations

import ctypes
import os
import sys

M_TRIM_THRESHOLD = -1
"""mallopt parameter: free heap above this size at the heap's top is returned to the system."""

M_MMAP_THRESHOLD = -3
"""mallopt parameter: blocks this large or larger get their own memory map."""

MMAP_THRESHOLD = 64 << 20
"""Blocks under 64 MiB come from the heap (the largest planning temporaries are ~30 MB)."""

TRIM_THRESHOLD = 256 << 20
"""Up to 256 MiB of freed heap stays mapped for reuse."""


def keep_large_blocks(mmap_threshold: int = MMAP_THRESHOLD, trim: int = TRIM_THRESHOLD) -> bool:
    """Set glibc's mmap and trim thresholds (module doc); True when both were set. Does nothing
    (False) off Linux, without glibc's mallopt, or where the user set MALLOC_MMAP_THRESHOLD_ or
    MALLOC_TRIM_THRESHOLD_ in the environment (their choice stands)."""
    if not sys.platform.startswith("linux") or any(
            name in os.environ for name in ("MALLOC_MMAP_THRESHOLD_", "MALLOC_TRIM_THRESHOLD_")):
        return False
    try:
        mallopt = ctypes.CDLL(None).mallopt  # the C library this process runs on
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    return bool(mallopt(M_MMAP_THRESHOLD, mmap_threshold)) and bool(mallopt(M_TRIM_THRESHOLD, trim))
