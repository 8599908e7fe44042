"""The report's note on scenes still moving when the cameras first looked."""

from __future__ import annotations

import pandas as pd

from hsqbench.experiment.settling import unsettled_note

META = {"backend": {"trial_config": {"physics": {"settle_speed_mps": 0.005}}}}


def _attempts(speeds: dict[str, list[str]]) -> pd.DataFrame:
    rows = [(key, s) for key, values in speeds.items() for s in values]
    return pd.DataFrame(rows, columns=["trial_key", "scene_max_speed"], dtype=str)


def test_scenes_above_the_rest_speed_are_counted_once_per_trial():
    attempts = _attempts({"a": ["0.02", "0.02", "0.02"], "b": ["0.001"], "c": ["0.0049"]})
    note = unsettled_note(attempts, META)
    assert note is not None and note.startswith("1 of 3 scenes were still moving")
    assert "0.020 m/s" in note and "below 0.005" in note


def test_no_note_when_every_scene_was_at_rest_or_the_run_predates_the_column():
    assert unsettled_note(_attempts({"a": ["0.001"], "b": ["0.0049"]}), META) is None
    assert unsettled_note(_attempts({"a": [""], "b": [""]}), META) is None
    assert unsettled_note(_attempts({"a": ["0.02"]}), {}) is None
    assert unsettled_note(pd.DataFrame({"trial_key": ["a"]}), META) is None


def test_older_runs_name_the_physics_file_and_keep_its_settings_under_configs():
    older = {"backend": {"trial_config": {"physics": "physics"},
                         "configs": {"physics": {"settle_speed_mps": 0.005}}}}  # fmt: skip
    note = unsettled_note(_attempts({"a": ["0.02"], "b": ["0.001"]}), older)
    assert note is not None and note.startswith("1 of 2 scenes were still moving")
