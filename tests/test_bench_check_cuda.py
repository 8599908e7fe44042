"""bench/check_cuda.py, the prepared GPU check, run against the CPU so that it cannot rot on
machines without one (needs torch and the published weights, as tests/test_volumetric.py)."""

from __future__ import annotations

import pytest

from hsqbench.planner.learned import volumetric, weights

pytestmark = pytest.mark.skipif(
    not volumetric.available(),
    reason="torch is not installed (the optional 'learned' extra: pip install -e '.[learned]')",
)


def _weights_or_skip() -> None:
    try:
        for network in ("vgn", "giga"):
            for training in ("packed", "pile"):
                weights.weights_path(network, training, "unused", download=False)
    except weights.WeightsError as exc:
        pytest.skip(f"the published weights are not here ({exc}); set HSQ_MODELS_DIR")


def test_cpu_against_cpu_finds_the_same_top_grasps(capsys):
    _weights_or_skip()
    from bench.check_cuda import main

    assert main(["--device", "cpu", "--repeats", "1", "--planners", "vgn", "giga"]) == 0
    out = capsys.readouterr().out
    assert out.count("0.00 mm") == 4  # two networks, two scenes, no grasp moved
    assert "every top grasp on cpu" in out


def test_a_missing_cuda_device_is_an_error_not_a_pass(capsys):
    import torch

    if torch.cuda.is_available():
        pytest.skip("this machine has CUDA")
    from bench.check_cuda import main

    assert main(["--planners", "vgn"]) == 1
    assert "torch sees no CUDA device" in capsys.readouterr().err
