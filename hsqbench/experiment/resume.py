"""Whether a run folder may take this run: a new run, a resumed one of the same config and
the same draws, or an old run moved aside (``--force``).

A resumed run's trials must mean what the recorded ones mean, so a run folder refuses a config
whose hash differs (naming the settings that differ) and packed or pile rounds that now draw
other objects; a gzipped (canonical) run is resumed by ``make results``, not here.
"""

from __future__ import annotations

import json
import sys
from datetime import UTC, datetime
from pathlib import Path
from typing import Any

from hsqbench.experiment.results import ATTEMPTS_FILE, RUN_FILE, ResultsError, ResultStore
from hsqbench.experiment.rows import attempts_paths, packed_files


def move_aside(run_dir: Path) -> Path:
    """Rename ``run_dir`` to ``<name>.replaced-<UTC time>`` (``--force``); the new path."""
    stamp = datetime.now(UTC).strftime("%Y%m%d-%H%M%S")
    target = run_dir.with_name(f"{run_dir.name}.replaced-{stamp}")
    run_dir.rename(target)
    return target


def existing_run(
    store: ResultStore, run_dir: Path, resume: bool, force: bool
) -> dict[str, Any] | None:
    """The ``run.json`` of the run in ``run_dir`` to continue (None: a new run), after the
    folder checks: ``force`` moves an old run aside; without ``resume`` an existing run is an
    error."""
    meta = store.read_meta()
    plain, packed = attempts_paths(run_dir)
    if resume and packed_files(packed):
        raise ResultsError(
            f"{run_dir}: its {ATTEMPTS_FILE} is gzipped (a canonical run): `make results` "
            "unpacks and resumes it, or gunzip it to resume it here"
        )
    has_data = meta is not None or plain.exists()
    if has_data and force:
        moved = move_aside(run_dir)
        print(f"moved the previous run to {moved}", file=sys.stderr)
        return None
    if has_data and not resume:
        raise ResultsError(
            f"{run_dir} already holds a run: pass --resume to continue it, choose another "
            "--run name, or --force to move it aside and start again"
        )
    if has_data and meta is None:
        raise ResultsError(f"{run_dir} has results but no {RUN_FILE}: choose another --run name")
    return meta


def check_resumable(
    run_dir: Path,
    meta: dict[str, Any] | None,
    draws: dict[str, dict[str, dict]],
    chash: str,
    identity: dict[str, Any],
) -> None:
    """A resumed run must draw the same packed and pile rounds and have the same config
    hash. ``draws``: ``run.json`` key (``packed_draws``, ``pile_draws``) -> the rounds' draws;
    ``identity``: this config and backend settings, as ``run.json`` records them, to name what
    differs."""
    if meta is None:
        return
    changed = []
    for key, rounds in draws.items():
        recorded = meta.get(key, {})
        kind = "" if key == "packed_draws" else "pile "
        changed += sorted(f"{kind}{k}" for k, v in rounds.items() if recorded.get(k, v) != v)
    if changed:
        raise ResultsError(
            f"{run_dir}: the packed rounds {changed} now draw other objects than when the run "
            f"was started (recorded in {RUN_FILE}); the objects' footprints or the scene's "
            "placement changed. Choose a new --run name, or --force to move the old run aside"
        )
    if meta.get("config_hash") != chash:
        recorded = {"config": meta.get("config"), "backend": meta.get("backend")}
        found = differences(recorded, json.loads(json.dumps(identity)))
        shown = "; ".join(found[:4]) + (f"; and {len(found) - 4} more" if len(found) > 4 else "")
        raise ResultsError(
            f"{run_dir} was run with config hash {meta.get('config_hash')}, but this config "
            f"(with its trial settings) hashes to {chash}"
            + (f" ({shown})" if shown else "")
            + ": results of two configs must not mix. Choose a new --run name, or --force to "
            "move the old run aside"
        )


def differences(old: Any, new: Any, path: str = "") -> list[str]:
    """``path: old -> new`` for every leaf where two JSON trees (``run.json``'s config and
    backend settings) differ, in key order."""
    if isinstance(old, dict) and isinstance(new, dict):
        out = []
        for key in sorted(set(old) | set(new), key=str):
            out += differences(old.get(key), new.get(key), f"{path}.{key}" if path else str(key))
        return out
    if old == new:
        return []

    def short(value: Any) -> str:
        text = json.dumps(value)
        return text if len(text) <= 60 else text[:57] + "..."

    return [f"{path}: {short(old)} -> {short(new)}"]
