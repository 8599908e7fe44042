"""bench/trial_timing.py: each second counted once, in the innermost wrapped call, and physics
stepped by the stepper named by its phase (issue 42's breakdown)."""

from __future__ import annotations

import sys
import time
import types

import pytest

from bench import trial_timing
from bench.trial_timing import PHYSICS, Attribution


def _busy(seconds: float) -> None:
    end = time.process_time() + seconds
    while time.process_time() < end:
        pass


class _Stepper:
    def __init__(self, phase: str) -> None:
        self.phase = phase

    def step(self, seconds: float) -> None:
        sys.modules["_fake_engine"].mj_step(seconds)


@pytest.fixture
def fake(monkeypatch):
    """A module standing in for the trial: ``run`` opens a step, ``_Stepper.step`` calls the
    engine's ``mj_step``, which is also called outside any stepper."""
    engine = types.ModuleType("_fake_engine")
    engine.mj_step = _busy
    trial = types.ModuleType("_fake_trial")
    trial.Stepper = _Stepper

    def run(phases: list[tuple[str, float]], bare_s: float, own_s: float) -> None:
        _busy(own_s)
        for phase, seconds in phases:
            trial.Stepper(phase).step(seconds)
        engine.mj_step(bare_s)

    trial.run = run
    monkeypatch.setitem(sys.modules, "_fake_engine", engine)
    monkeypatch.setitem(sys.modules, "_fake_trial", trial)
    wrapped = (
        ("_fake_trial", "run", "execution", None),
        ("_fake_trial", "Stepper.step", None, trial_timing._phase_physics),
        ("_fake_engine", "mj_step", None, trial_timing._physics),
    )
    timing = Attribution()
    assert timing.install(wrapped) == []
    yield timing, trial
    timing.uninstall()


def test_physics_is_split_by_the_steppers_phase(fake):
    timing, trial = fake
    timing.reset()
    trial.run([("lift", 0.06), ("approach", 0.02), ("lift", 0.04), ("", 0.02)], 0.03, 0.02)
    cpu = {key: seconds[1] for key, seconds in timing.seconds.items()}
    assert cpu[("execution", f"{PHYSICS}: lift")] == pytest.approx(0.10, abs=0.01)
    assert cpu[("execution", f"{PHYSICS}: approach")] == pytest.approx(0.02, abs=0.01)
    assert cpu[("execution", f"{PHYSICS}: no phase")] == pytest.approx(0.02, abs=0.01)
    # mj_step outside a stepper is plain physics; the step's own time is its rest
    assert cpu[("execution", PHYSICS)] == pytest.approx(0.03, abs=0.01)
    assert cpu[("execution", "rest")] == pytest.approx(0.02, abs=0.01)
    # every second once: the parts add up to the time measured around the call
    total = sum(cpu.values())
    assert total == pytest.approx(0.19, abs=0.02)


def test_the_table_prints_each_phase_and_uninstall_restores(fake):
    timing, trial = fake
    timing.reset()
    trial.run([("carry", 0.02)], 0.0, 0.0)
    lines = timing.table(trials=1)
    assert any(f"{PHYSICS}: carry" in line for line in lines)
    timing.uninstall()
    assert trial.Stepper.step is _Stepper.step
    assert sys.modules["_fake_engine"].mj_step is _busy


def test_a_function_this_version_lacks_is_reported_not_wrapped():
    timing = Attribution()
    missing = timing.install((("_fake_absent_module", "f", "x", None),))
    assert missing == ["_fake_absent_module.f"]
    timing.uninstall()
