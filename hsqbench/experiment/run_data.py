"""A run's results as typed frames with its metadata (:class:`RunData`, :func:`load_run`): the
data every renderer of a report (tables, markdown, plots, paired comparisons) reads. It sits
below them all, so none of them imports the report module that calls them."""

from __future__ import annotations

import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import pandas as pd

from hsqbench.experiment.csv_fields import typed_frame
from hsqbench.experiment.results import (
    ATTEMPTS_FILE,
    ROUNDS_FILE,
    RUN_FILE,
    STATUS_OK,
    load_results,
)
from hsqbench.experiment.rows import has_attempts
from hsqbench.experiment.settling import unsettled_note

MEASURED = "measured, simulation (this run)"  # the label of rows from the MuJoCo backend


@dataclass
class RunData:
    """A run's complete trials as typed frames (dtypes: :mod:`hsqbench.experiment.schema`),
    and its metadata."""

    attempts: pd.DataFrame
    rounds: pd.DataFrame
    meta: dict[str, Any]
    planners: list[str]
    objects: list[str]
    confidence: float
    notes: list[str] = field(default_factory=list)
    measured: str = MEASURED  # provenance label of this run's rows (names a non-simulation backend)
    # Planners joined from other runs (``--join``): planner -> their rows' provenance label.
    joined: dict[str, str] = field(default_factory=dict)

    def source(self, planner: str) -> str:
        """The provenance label of ``planner``'s rows: this run's, or the run it was joined from."""
        return self.joined.get(planner, self.measured)


def load_run(run_dir: str | Path) -> RunData:
    """Read ``attempts.csv``, ``rounds.csv`` and (if present) ``run.json`` of a run folder.

    Raises:
        FileNotFoundError: ``run_dir`` has no ``attempts.csv``.
    """
    run_dir = Path(run_dir)
    if not has_attempts(run_dir):
        raise FileNotFoundError(
            f"{run_dir}: no attempts.csv; give the folder of a run (runs/<run>)"
        )
    results = load_results(run_dir)
    notes = []
    if results.partial_tail:
        notes.append("a partial last line (run killed mid-write) was ignored")
    if results.duplicate_keys:
        notes.append(f"{len(results.duplicate_keys)} trial(s) recorded twice were counted once")
    if results.incomplete_keys:
        notes.append(f"{len(results.incomplete_keys)} incomplete trial(s) were left out")
    meta: dict[str, Any] = {}
    if (run_dir / RUN_FILE).exists():
        meta = json.loads((run_dir / RUN_FILE).read_text())
    # Typed by the schema: the same dtypes under every pandas the package allows.
    attempts = typed_frame(results.attempts, "attempts", str(run_dir / ATTEMPTS_FILE))
    rounds = typed_frame(results.rounds, "rounds", str(run_dir / ROUNDS_FILE))
    config = meta.get("config", {})
    seen_planners = list(dict.fromkeys(attempts["planner"])) if len(attempts) else []
    planners = [p for p in config.get("planners", []) if p in seen_planners]
    planners += [p for p in seen_planners if p not in planners]
    iso = attempts[attempts["experiment"] == "isolated"] if len(attempts) else attempts
    seen_objects = list(dict.fromkeys(iso["objects"])) if len(iso) else []
    objects = [o for o in config.get("isolated", {}).get("objects", []) if o in seen_objects]
    objects += [o for o in seen_objects if o not in objects]
    hashes = set(attempts["config_hash"]) if len(attempts) else set()
    if len(hashes) > 1:
        notes.append(f"rows carry {len(hashes)} config hashes {sorted(hashes)}: results mixed")
    broken = _stop_rule_violations(attempts, rounds, meta)
    if broken:
        notes.append(
            f"{broken} packed or pile round(s) ended with objects left and without the stop rule's "
            "reasons (consecutive failures, the attempt cap, an unstable simulation): check the "
            "trial runner's stop rule (in a run older than the rounds' objects_lost column, an object "
            "taken out of the workspace also looks left)"
        )
    if moving := unsettled_note(attempts, meta):
        notes.append(moving)
    confidence = float(config.get("confidence", 0.95))
    backend = meta.get("backend", {}).get("backend")
    if backend == "sim":
        measured = MEASURED
    elif backend is None:
        measured = "measured (this run; backend unknown, run.json missing)"
    else:
        measured = f"measured, {backend} backend (this run)"
    return RunData(attempts, rounds, meta, planners, objects, confidence, notes, measured)


def _stop_rule_violations(attempts: pd.DataFrame, rounds: pd.DataFrame, meta: dict) -> int:
    """Rounds that stopped although the stop rule (:mod:`hsqbench.sim.stop_rule`, with the
    run's own ``packed:`` or ``pile:`` settings) says they should have gone on: objects left,
    and none of the rule's reasons (failures in a row, the cap, ...) ended them."""
    from hsqbench.config import from_dict
    from hsqbench.sim.stop_rule import PackedConfig

    backend = meta.get("backend") or {}
    count = 0
    ok_rounds = rounds[rounds["status"] == STATUS_OK]
    ok = attempts[attempts["status"] == STATUS_OK]
    by_key = {k: g.sort_values("attempt_index") for k, g in ok.groupby("trial_key")}
    for _, r in ok_rounds.iterrows():
        kind = str(r["trial_key"]).split("/", 1)[0]
        stored = (backend.get("trial_config") or {}).get(kind, backend.get(kind))
        rule = from_dict(PackedConfig, stored) if isinstance(stored, dict) else PackedConfig()
        tail = by_key.get(r["trial_key"])
        outcomes = [] if tail is None else [str(o) for o in tail["outcome"]]
        # Runs before objects_lost existed read it empty: an object lost there looks left.
        out = r["n_cleared"] + (0 if pd.isna(r.get("n_lost")) else r["n_lost"])
        if rule.ended_early(outcomes, objects_left=out < r["n_objects"]):
            count += 1
    return count
