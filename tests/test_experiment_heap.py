"""hsqbench.experiment.heap: a process that runs trials keeps freed memory for reuse (glibc), and
the trial backend sets that up before its first trial."""

from __future__ import annotations

import platform
import subprocess
import sys
import textwrap

import pytest

from hsqbench.experiment import backend as backend_module
from tests.test_experiment_backend import _trial_module

# Allocates and frees a 256 MiB block, then prints how much of it the process still holds.
_PROBE = textwrap.dedent(
    """
    import sys
    import numpy as np
    from hsqbench.experiment.heap import keep_freed_memory

    def resident_mib():
        with open("/proc/self/statm") as f:
            return int(f.read().split()[1]) * 4096 / 2**20

    if sys.argv[1] == "keep":
        assert keep_freed_memory()
    before = resident_mib()
    block = np.ones(2**25)  # 256 MiB, every page touched
    del block
    print(resident_mib() - before)
    """
)


def _held_after_free_mib(mode: str) -> float:
    out = subprocess.run(
        [sys.executable, "-c", _PROBE, mode], capture_output=True, text=True, check=True
    )
    return float(out.stdout.strip())


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="glibc's mallopt only")
def test_freed_blocks_stay_in_the_process_for_the_next_trial():
    assert _held_after_free_mib("default") < 64  # glibc unmaps a block that large on free
    assert _held_after_free_mib("keep") > 192  # kept: the next allocation reuses those pages


def test_the_backend_keeps_freed_memory_before_its_first_trial(tmp_path, monkeypatch):
    calls = []
    monkeypatch.setattr(backend_module, "keep_freed_memory", lambda: calls.append(1))
    monkeypatch.setitem(sys.modules, "hsqbench.sim.trial", _trial_module([]))
    path = tmp_path / "trial.yaml"
    path.write_text("settle_s: 0.25\n")
    backend = backend_module.SimBackend(str(path))
    backend._trial_config()
    backend._trial_config()  # the config is loaded once, and the setting made once with it
    assert calls == [1]
