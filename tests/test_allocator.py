import subprocess
import sys

import pytest

from suctionbench.allocator import keep_large_blocks


@pytest.mark.skipif(not sys.platform.startswith("linux"), reason="glibc's mallopt")
def test_thresholds_are_set_unless_the_user_chose_them():
    # In fresh interpreters: glibc accepts both settings; a user's MALLOC_*_ environment stands.
    code = "from suctionbench.allocator import keep_large_blocks; print(keep_large_blocks())"
    run = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert run.stdout.strip() == "True"
    chosen = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                            env={"MALLOC_MMAP_THRESHOLD_": "131072", "PATH": ""})
    assert chosen.stdout.strip() == "False"


def test_off_linux_it_does_nothing(monkeypatch):
    monkeypatch.setattr(sys, "platform", "darwin")
    assert keep_large_blocks() is False
