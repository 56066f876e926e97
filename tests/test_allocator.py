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


def test_timings_name_the_cpu_they_ran_on():
    # the same 2-core `bench plan` took 0.050 s on one host and 0.024 s on another: a timing that
    # does not say which CPU is not comparable. On Linux the name is /proc/cpuinfo's "model name".
    from pathlib import Path

    from suctionbench.bench import cpu_model

    info = Path("/proc/cpuinfo")
    names = [line.split(":", 1)[1].strip() for line in info.read_text().splitlines()
             if line.startswith("model name")] if info.exists() else []
    assert cpu_model() == (names[0] if names else "unknown")
