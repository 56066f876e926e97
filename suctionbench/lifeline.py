"""Child processes that die with their parent: pool workers (`suctionbench.parallel`) and the CoACD
child (`suctionbench.objects.decompose`).

Standard library only: the CoACD child runs without the package and loads this file by its path.
"""

from __future__ import annotations

import os
import signal
import sys
import threading

PR_SET_PDEATHSIG = 1
"""linux/prctl.h: the signal a process gets when its parent dies."""

PARENT_POLL_S = 1.0
"""Where prctl is not available, how often a child checks that its parent still lives."""


def die_with_parent(parent_pid: int) -> None:
    """Called first thing in a child: end it when the process that started it dies (a killed
    `generate`, `eval` or `objects import` leaves no orphan blocked on a dead pipe or computing
    for no one).

    On Linux the kernel sends SIGKILL on the parent's death (prctl PR_SET_PDEATHSIG); elsewhere a
    daemon thread polls the parent id. Either way, a parent already gone ends the child at once.
    PR_SET_PDEATHSIG fires when the *thread* that started the child ends, so start children from a
    thread that outlives them (the main thread, or one that waits for the child).
    """
    armed = False
    if sys.platform.startswith("linux"):
        import ctypes

        try:
            libc = ctypes.CDLL(None, use_errno=True)
            armed = libc.prctl(PR_SET_PDEATHSIG, signal.SIGKILL, 0, 0, 0) == 0
        except (OSError, AttributeError):
            armed = False
    if os.getppid() != parent_pid:  # the parent died before the signal was armed
        os._exit(1)
    if not armed:
        def watch() -> None:
            while os.getppid() == parent_pid:
                threading.Event().wait(PARENT_POLL_S)
            os._exit(1)

        threading.Thread(target=watch, name="parent-watch", daemon=True).start()
