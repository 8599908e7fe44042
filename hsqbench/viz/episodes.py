"""Recordings of a benchmark run's trials: chosen trials, or all failures, replayed with Rerun.

A trial is a pure function of its seed and config (``hsqbench.sim.trial``), so a finished run's
trial can be recorded afterwards by running it again with a :class:`RerunRecorder`: the run
itself pays nothing, and only the trials someone wants to look at are simulated twice. The
replay uses the trial config stored in the run's ``run.json`` (the backend fingerprint), and
every replay is checked against the outcomes in ``attempts.csv``; a mismatch (changed code or
data since the run) is reported, never hidden.

Files are named after the trial key, ``isolated/hsq/s0/mug/003`` ->
``isolated_hsq_s0_mug_003.rrd``.
"""

from __future__ import annotations

import json
import re
from collections.abc import Callable, Iterable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Literal

Which = Literal["failures", "all"]


@dataclass(frozen=True)
class TrialChoice:
    """One finished trial of a run.

    Attributes:
        key: the run's trial key; experiment: ``isolated`` or ``packed``.
        planner, seed, objects: what to run again.
        outcomes: the recorded outcome of each attempt, in order.
    """

    key: str
    experiment: str
    planner: str
    seed: int
    objects: tuple[str, ...]
    outcomes: tuple[str, ...]

    @property
    def failed(self) -> bool:
        """An isolated trial whose attempt failed, or a packed round with any failed attempt."""
        return any(o != "success" for o in self.outcomes)

    @property
    def filename(self) -> str:
        return re.sub(r"[^A-Za-z0-9_.+-]+", "_", self.key).strip("_") + ".rrd"


@dataclass(frozen=True)
class Episode:
    """A recorded replay: the file, the trial, and the outcomes of the replay."""

    path: Path
    choice: TrialChoice
    outcomes: tuple[str, ...]

    @property
    def matches(self) -> bool:
        """The replay reproduced the run's outcomes."""
        return self.outcomes == self.choice.outcomes


def choose_trials(
    run_dir: str | Path,
    which: Which = "failures",
    keys: Iterable[str] | None = None,
    limit: int | None = None,
) -> list[TrialChoice]:
    """The run's complete trials to record, in the order of ``attempts.csv``.

    Args:
        which: ``failures`` (see :attr:`TrialChoice.failed`) or ``all``; ignored with ``keys``.
        keys: exactly these trial keys (ValueError naming any that the run lacks).
        limit: at most this many.
    """
    from hsqbench.experiment.results import STATUS_OK, load_results

    if which not in ("failures", "all"):
        raise ValueError(f"which must be 'failures' or 'all', got {which!r}")
    results = load_results(run_dir)
    rows_by_key: dict[str, list[dict[str, str]]] = {}
    for row in results.attempts:
        if row["status"] == STATUS_OK:
            rows_by_key.setdefault(row["trial_key"], []).append(row)
    choices = []
    for key, rows in rows_by_key.items():
        rows = sorted(rows, key=lambda r: int(r["attempt_index"]))
        first = rows[0]
        choices.append(
            TrialChoice(
                key=key,
                experiment=first["experiment"],
                planner=first["planner"],
                seed=int(first["seed"]),
                objects=tuple(o for o in first["objects"].split(";") if o),
                outcomes=tuple(r["outcome"] for r in rows),
            )
        )
    if keys is not None:
        wanted = list(keys)
        known = {c.key: c for c in choices}
        missing = [k for k in wanted if k not in known]
        if missing:
            raise ValueError(
                f"{run_dir} has no finished trial {missing}; trial keys look like "
                f"{next(iter(known), 'isolated/hsq/s0/mug/000')}"
            )
        choices = [known[k] for k in wanted]
    elif which == "failures":
        choices = [c for c in choices if c.failed]
    return choices if limit is None else choices[: max(0, int(limit))]


def run_trial_config(run_dir: str | Path, overrides: dict[str, Any] | None = None) -> Any:
    """The :class:`~hsqbench.sim.trial.TrialConfig` a run used (from its ``run.json``), with
    ``overrides`` (dotted path -> value) applied."""
    from hsqbench.experiment.results import RUN_FILE
    from hsqbench.sim.trial.config import trial_config_from_record

    path = Path(run_dir) / RUN_FILE
    if not path.exists():
        raise FileNotFoundError(f"{path} is missing: {run_dir} is not a benchmark run folder")
    meta = json.loads(path.read_text())
    stored = (meta.get("backend") or {}).get("trial_config")
    if not isinstance(stored, dict):
        raise ValueError(
            f"{path} holds no trial config (backend {meta.get('backend', {}).get('backend')!r}): "
            "only runs of the simulation backend can be replayed"
        )
    return trial_config_from_record(stored, f"{path.name} trial_config", overrides)


def record_trial(choice: TrialChoice, trial_config: Any, path: str | Path, viewer_config=None):
    """Run ``choice`` again with a :class:`RerunRecorder` writing ``path``; returns the result."""
    from hsqbench.sim.trial import run_isolated_trial, run_packed_round
    from hsqbench.viz.rerun_recorder import RerunRecorder

    with RerunRecorder(path, viewer_config) as rec:
        if choice.experiment == "isolated":
            return run_isolated_trial(
                choice.objects[0], choice.seed, choice.planner, trial_config, recorder=rec
            )
        return run_packed_round(
            list(choice.objects), choice.seed, choice.planner, trial_config, recorder=rec
        )


def record_run(
    run_dir: str | Path,
    out_dir: str | Path,
    which: Which = "failures",
    keys: Iterable[str] | None = None,
    limit: int | None = None,
    report: Callable[[Episode], None] | None = None,
) -> list[Episode]:
    """Record the chosen trials of a finished run into ``out_dir`` (see the module docstring).

    ``report`` is called after each recording (e.g. to print progress and mismatches).
    """
    trial_config = run_trial_config(run_dir)
    out = Path(out_dir)
    episodes = []
    for choice in choose_trials(run_dir, which, keys, limit):
        path = out / choice.filename
        result = record_trial(choice, trial_config, path)
        episode = Episode(path, choice, tuple(str(a.outcome) for a in result.attempts))
        episodes.append(episode)
        if report is not None:
            report(episode)
    return episodes
