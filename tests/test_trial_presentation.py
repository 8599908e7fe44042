"""A presentation kept for the next planner (hsqbench.sim.trial.presentation): the trials that
reuse it give exactly the records of trials that build their own scene."""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from hsqbench.planner.api import PlanResult
from hsqbench.sim.trial import TrialEnv, load_trial_config, run_isolated_trial, run_packed_round
from hsqbench.sim.trial.presentation import CACHE, PresentationCache
from tests.test_trial import AbovePlanner, CountingRecorder, _timeless


@pytest.fixture(scope="module")
def config():
    return replace(load_trial_config(), sensor="surface")


@pytest.fixture(autouse=True)
def empty_cache():
    CACHE.clear()
    yield
    CACHE.clear()


class Scrambler:
    """Plans nothing, but first overwrites the cloud it was given (a planner may)."""

    name = "scrambler"

    def plan(self, points, context) -> PlanResult:
        points[:] = 0.0
        return PlanResult(grasps=[], reason="scrambled", planner=self.name)


def test_planners_sharing_a_presentation_get_the_records_of_their_own_builds(config):
    planners = ("hsq", "antipodal")
    kept = [_timeless(run_isolated_trial("proc_box", 4, p, config)) for p in planners]
    assert CACHE.get(CACHE.key("isolated", ["proc_box"], 4), config) is not None
    for planner, record in zip(planners, kept, strict=True):
        CACHE.clear()
        assert _timeless(run_isolated_trial("proc_box", 4, planner, config)) == record


def test_a_packed_round_after_another_planner_is_the_round_built_anew(config):
    objects = ["proc_box", "proc_cylinder"]
    run_packed_round(objects, 2, AbovePlanner(0.15), config)
    after = _timeless(run_packed_round(objects, 2, "hsq", config))
    CACHE.clear()
    assert _timeless(run_packed_round(objects, 2, "hsq", config)) == after


def test_a_kept_scene_comes_back_as_built(config):
    with TrialEnv.build("packed", ["proc_box", "proc_cylinder"], 3, config) as env:
        built_qpos = env.data.qpos.copy()
        contype = env.model.geom_contype.copy()
        env.look()
        env.remove("proc_box")
        env.stepper.hold(0.2)
        env.model.opt.noslip_iterations = 0
    with TrialEnv.build("packed", ["proc_box", "proc_cylinder"], 3, config) as again:
        assert again.model is env.model and again.data is not env.data
        assert np.array_equal(again.data.qpos, built_qpos) and again.data.time == 0.0
        assert np.array_equal(again.model.geom_contype, contype)
        assert again.model.opt.noslip_iterations == config.physics.noslip_iterations
        assert again.objects_on_table() == ["proc_box", "proc_cylinder"]


def test_the_first_look_is_handed_out_as_a_copy(config):
    scrambled = run_isolated_trial("proc_box", 5, Scrambler(), config)
    assert scrambled.attempts[0].detail == "scrambled"
    with TrialEnv.build("isolated", "proc_box", 5, config) as env:
        look = env.look()
        assert env.presentation is not None and env.presentation.first_look is not None
        assert np.asarray(look.obs.points).any()
        kept = env.presentation.first_look.look.obs.points
        assert np.array_equal(look.obs.points, kept) and look.obs.points is not kept
        second = env.look()  # a later look (a packed round's next attempt) perceives anew
        assert second.obs is not look.obs


def test_other_seeds_configs_and_recorded_trials_build_their_own(config):
    with TrialEnv.build("isolated", "proc_box", 6, config) as first:
        pass
    with TrialEnv.build("isolated", "proc_box", 7, config) as other_seed:
        assert other_seed.model is not first.model
    other_config = replace(config, max_ranks=config.max_ranks + 1)
    with TrialEnv.build("isolated", "proc_box", 7, other_config) as other:
        assert other.model is not other_seed.model
    with TrialEnv.build("isolated", "proc_box", 7, config, CountingRecorder()) as recorded:
        assert recorded.presentation is None and recorded.model is not other.model
    assert PresentationCache.key("isolated", [object()], 1) is None
