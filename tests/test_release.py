"""The release over the bin (hsqbench.sim.trial.release, and the release phase of
hsqbench.sim.trial.execution): the turn toward pointing down, the lowering, the open hand's
contacts, the withdrawal and how a release is judged. Trials use the surface stand-in sensor
and the procedural box, as in test_trial.py."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from hsqbench.planner.api import PlanResult
from hsqbench.planner.grasp import Grasp
from hsqbench.sim.motion import Stepper
from hsqbench.sim.outcome import Outcome
from hsqbench.sim.trial import (
    TrialConfig,
    TrialEnv,
    load_trial_config,
    release,
    run_isolated_trial,
)

TOP_DOWN = np.array([[1.0, 0.0, 0.0], [0.0, -1.0, 0.0], [0.0, 0.0, -1.0]])


@pytest.fixture(scope="module")
def config() -> TrialConfig:
    return replace(load_trial_config(), sensor="surface")


def test_an_object_lost_while_lowered_into_the_bin_is_released_there(config, monkeypatch):
    """A slip or a lost finger during the lowering, over the bin, ends the lowering: the hand
    opens where it is and where the object comes to rest decides; the detail says so."""
    from hsqbench.sim.trial import execution

    lowering = {"started": False}
    real_lowering = execution.lowering

    def marked(env, drop):
        out = real_lowering(env, drop)
        lowering["started"] = True
        return out

    class SlipsWhenLowered(execution.HoldWatch):
        def __call__(self):
            if lowering["started"]:
                return "proc_box slipped 5.0 cm in the hand"
            return super().__call__()

    monkeypatch.setattr(execution, "lowering", marked)
    monkeypatch.setattr(execution, "HoldWatch", SlipsWhenLowered)
    [attempt] = run_isolated_trial("proc_box", 1, "hsq", config).attempts
    assert lowering["started"]
    assert attempt.outcome == Outcome.SUCCESS, attempt.detail
    assert attempt.detail.startswith("in the bin")
    assert "(lost while lowering: proc_box slipped 5.0 cm in the hand)" in attempt.detail


def test_an_object_still_in_the_open_hand_is_withdrawn_from_along_the_approach(config, monkeypatch):
    """An object not in the bin once the hand has opened (hooked on a finger) makes the hand
    pull back ``withdraw_m`` along its approach axis before the object is judged; one released
    into the bin is judged as it lies, the hand not moved."""
    from hsqbench.sim.trial import execution

    [attempt] = run_isolated_trial("proc_box", 1, "hsq", config).attempts
    assert attempt.outcome == Outcome.SUCCESS and "withdrawn" not in attempt.detail
    moves = []
    real_withdraw = execution.withdraw

    def recorded(env):
        before = env.panda.tcp_pose(env.data)
        note = real_withdraw(env)
        moves.append((before, env.panda.tcp_pose(env.data)[0]))
        return note

    # The hand does not open: the box stays between the pads, over the bin.
    monkeypatch.setattr(
        Stepper, "open_hand", lambda self, width: self.panda.gripper_width(self.data)
    )
    monkeypatch.setattr(execution, "withdraw", recorded)
    [attempt] = run_isolated_trial("proc_box", 1, "hsq", config).attempts
    assert attempt.outcome == Outcome.DROPPED, attempt.detail
    assert attempt.detail.endswith("(withdrawn 8 cm to free it from the fingers)")
    [((p0, r0), p1)] = moves
    moved = p1 - p0
    assert np.linalg.norm(moved) == pytest.approx(config.execution.withdraw_m, abs=0.01)
    assert moved @ -r0[:, 2] > 0.95 * np.linalg.norm(moved)


def test_an_object_in_the_bin_still_on_the_open_hand_is_withdrawn_from_then_judged(
    config, monkeypatch
):
    """An object in the bin that still touches a finger once the hand is open makes the hand
    pull back along its approach; it succeeds only if it is then free of the fingers (one
    wedged between the open pads would leave with the hand)."""
    from hsqbench.sim.judge import SceneProbe
    from hsqbench.sim.trial import execution

    withdrawn = []
    monkeypatch.setattr(execution, "withdraw", lambda env: withdrawn.append(1) or " (withdrawn)")
    for freed, outcome, detail in (
        (True, Outcome.SUCCESS, "in the bin"),
        (False, Outcome.DROPPED, "still on the open hand after the release"),
    ):
        withdrawn.clear()
        monkeypatch.setattr(
            SceneProbe, "on_hand", lambda self, data, name, f=freed: not (f and withdrawn)
        )
        [attempt] = run_isolated_trial("proc_box", 1, "hsq", config).attempts
        assert withdrawn == [1]
        assert attempt.outcome == outcome, attempt.detail
        assert attempt.detail.startswith(detail) and attempt.detail.endswith(" (withdrawn)")


def test_the_no_slip_pass_is_off_from_the_release_opening_and_set_back_after(config, monkeypatch):
    """The grasp closes with the solver's no-slip pass (it stops a squeezed grasp creeping) and
    the hand opens over the bin with ``physics.open_hand_noslip_iterations``; the model keeps
    its own value for the next attempt, also when the release raises."""
    from hsqbench.sim.motion import Stepper

    seen = []
    for name in ("close_hand", "open_hand"):
        real = getattr(Stepper, name)

        def spy(self, *a, _real=real, _name=name):
            seen.append((_name, int(self.model.opt.noslip_iterations)))
            return _real(self, *a)

        monkeypatch.setattr(Stepper, name, spy)
    [attempt] = run_isolated_trial("proc_box", 1, "hsq", config).attempts
    assert attempt.outcome == Outcome.SUCCESS, attempt.detail
    kept, opened = config.physics.noslip_iterations, config.physics.open_hand_noslip_iterations
    assert kept != opened
    assert ("close_hand", kept) in seen and seen[-1] == ("open_hand", opened)
    with TrialEnv.build("isolated", "proc_box", 1, config) as env:
        with pytest.raises(RuntimeError), release.open_hand_contacts(env):
            assert env.model.opt.noslip_iterations == opened
            raise RuntimeError("a failed release")
        assert env.model.opt.noslip_iterations == kept


def test_a_blocked_lowering_is_tried_away_from_a_sideways_wrist_before_a_shorter_one(
    config, monkeypatch
):
    """At each depth of ``lowering_fractions`` the lowering is tried straight down, then moved
    by each of ``lowering_shifts_m`` toward where the hand points, horizontally; a hand that
    points down is never moved."""
    from types import SimpleNamespace

    tried = []

    def first_clear(env, offsets):
        tried[:] = offsets
        return np.zeros((2, 7)), len(offsets) - 2, "link7 1.0 mm from the table or bin"

    monkeypatch.setattr(release, "first_clear_line", first_clear)
    ex = config.execution
    sideways = np.column_stack([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])  # points +x
    for rotation, shifts in ((sideways, (0.0, *ex.lowering_shifts_m)), (TOP_DOWN, (0.0,))):
        panda = SimpleNamespace(tcp_pose=lambda data, r=rotation: (np.zeros(3), r))
        env = SimpleNamespace(config=config, panda=panda, data=None)
        _, depth, shift, problem = release.lowering(env, 0.2)
        expected = [[s, 0.0, -f * 0.2] for f in ex.lowering_fractions for s in shifts]
        np.testing.assert_allclose(np.array(tried), expected, atol=1e-12)
        assert (depth, shift) == pytest.approx((-expected[-2][2], expected[-2][0]))
        assert problem == "link7 1.0 mm from the table or bin"
    for bad in [(0.06, 0.03), (0.0,), (-0.01,)]:
        with pytest.raises(ValueError, match="lowering_shifts_m"):
            replace(ex, lowering_shifts_m=bad)


def test_lowering_fractions_start_at_the_full_lowering_and_decrease():
    from hsqbench.sim.trial.config import ExecutionConfig

    assert ExecutionConfig(lowering_fractions=(1.0, 0.4)).lowering_fractions == (1.0, 0.4)
    for bad in [(), (0.5,), (1.0, 0.5, 0.6), (1.0, 0.0)]:
        with pytest.raises(ValueError, match=r"lowering_fractions .* start at 1.0"):
            ExecutionConfig(lowering_fractions=bad)


class SidePlanner:
    """Horizontal grasps across the box's short side at 6 cm height, approaching along its long
    side from either end: the hand holds it tilted 90 deg from pointing down."""

    name = "side"

    def plan(self, points, context) -> PlanResult:
        p = np.asarray(points)
        c = p.mean(axis=0)
        xy = p[:, :2] - c[:2]
        _, vectors = np.linalg.eigh(xy.T @ xy)  # ascending: the short horizontal side first
        grasps = []
        for sign in (1.0, -1.0):
            a = sign * np.array([*vectors[:, 1], 0.0])
            closing = np.array([*vectors[:, 0], 0.0])
            rotation = np.column_stack([closing, np.cross(a, closing), a])
            if np.linalg.det(rotation) < 0:
                rotation[:, 0] *= -1
            grasps.append(Grasp(np.array([*c[:2], 0.06]), rotation, 0.05, 0.9))
        return PlanResult(grasps=grasps, planner=self.name)


def test_rotation_toward_down_turns_the_approach_about_a_horizontal_axis():
    """The turn is the smallest one: the whole fraction points the approach straight down, half
    of it halves the tilt; the result is a rotation and the closing axis keeps its tilt
    relative to the approach."""
    from scipy.spatial.transform import Rotation

    from hsqbench.sim.trial.release import rotation_toward_down

    for r in Rotation.random(20, random_state=3).as_matrix():
        tilt = np.arccos(np.clip(-r[2, 2], -1, 1))
        full = rotation_toward_down(r, 1.0)
        np.testing.assert_allclose(full[:, 2], [0.0, 0.0, -1.0], atol=1e-9)
        half = rotation_toward_down(r, 0.5)
        assert np.arccos(np.clip(-half[2, 2], -1, 1)) == pytest.approx(tilt / 2, abs=1e-9)
        for turned in (full, half):
            np.testing.assert_allclose(turned.T @ turned, np.eye(3), atol=1e-9)
            assert np.linalg.det(turned) == pytest.approx(1.0)
            assert turned[:, 0] @ turned[:, 2] == pytest.approx(0.0, abs=1e-9)
        np.testing.assert_allclose(rotation_toward_down(r, 0.0), r, atol=1e-12)
    np.testing.assert_allclose(rotation_toward_down(TOP_DOWN, 1.0), TOP_DOWN)


def test_a_tilted_hand_is_turned_to_point_down_before_it_lowers_the_object(config, monkeypatch):
    """A side grasp is carried over the bin tilted as it was grasped; the hand then turns about
    the TCP to point straight down before the lowering, so it opens pointing down and the
    detail says so. With ``turn_down_fractions`` empty it opens as tilted as it grasped."""
    opened = []
    real_open = Stepper.open_hand

    def spy(self, width):
        opened.append(self.panda.tcp_pose(self.data)[1][:, 2])
        return real_open(self, width)

    monkeypatch.setattr(Stepper, "open_hand", spy)
    [attempt] = run_isolated_trial("proc_box", 1, SidePlanner(), config).attempts
    assert attempt.outcome == Outcome.SUCCESS, attempt.detail
    assert "(turned 100% of the way to pointing down)" in attempt.detail
    assert opened[-1][2] < -0.99
    untouched = replace(config, execution=replace(config.execution, turn_down_fractions=()))
    [attempt] = run_isolated_trial("proc_box", 1, SidePlanner(), untouched).attempts
    assert attempt.outcome == Outcome.SUCCESS, attempt.detail
    assert "turned" not in attempt.detail
    assert abs(opened[-1][2]) < 0.3


def test_turn_down_fractions_decrease_within_the_whole_turn_or_are_empty():
    from hsqbench.sim.trial.config import ExecutionConfig

    for good in [(), (1.0,), (1.0, 0.5), (0.6, 0.3)]:
        assert ExecutionConfig(turn_down_fractions=good).turn_down_fractions == good
    for bad in [(1.2,), (0.5, 0.5), (0.5, 0.7), (1.0, 0.0), (-0.5,)]:
        with pytest.raises(ValueError, match=r"turn_down_fractions .* decreasing values in"):
            ExecutionConfig(turn_down_fractions=bad)
