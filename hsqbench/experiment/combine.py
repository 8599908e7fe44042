"""One report over several runs of the same protocol (``hsqbench report --run RUN --join OTHER``).

A planner added later (e.g. one that needs an optional extra) can run in its own run folder:
trial seeds derive from (base seed, experiment, object, index) alone, so two runs of the same
protocol present the same poses and the same packed draws, and their rows can stand in one
table. The runs must agree on everything that decides the trials (seeds, objects, attempts,
rounds, draws, trial config); their config hashes differ, and the report says whose rows are
whose.
"""

from __future__ import annotations

from pathlib import Path
from typing import Any

import pandas as pd

from hsqbench.experiment.run_data import RunData

#: Protocol settings that decide which trials exist and what they present.
_SAME = ("seeds", "trial_config", "isolated", "packed", "pile")


class RunMismatch(ValueError):
    """Two runs do not present the same trials; their rows cannot share a table."""


def _protocol(meta: dict[str, Any]) -> dict[str, Any]:
    config = meta.get("config", {})
    out = {k: config.get(k) for k in _SAME}
    # Runs made before pile rounds existed had none: as a run with piles disabled.
    out["pile"] = out["pile"] or {"enabled": False}
    out["packed_draws"] = meta.get("packed_draws")
    out["pile_draws"] = meta.get("pile_draws") or {}
    return out


def _same(a: Any, b: Any) -> bool:
    """Equal, where mappings are compared on the keys both have (a setting added by a later
    version, such as ``exclude``, is absent from an older run's record)."""
    if isinstance(a, dict) and isinstance(b, dict):
        return all(_same(a[k], b[k]) for k in set(a) & set(b))
    return a == b


def check_same_trials(main: RunData, other: RunData, other_dir: Path, whose: str) -> None:
    """Raise unless ``other`` ran ``main``'s protocol: the same seeds, objects, attempts,
    rounds, trial config and draws (``whose``: how the message names ``main``).

    Raises:
        RunMismatch: names the first setting that differs.
    """
    mine, theirs = _protocol(main.meta), _protocol(other.meta)
    for key in (*_SAME, "packed_draws", "pile_draws"):
        if not _same(mine[key], theirs[key]):
            raise RunMismatch(
                f"{other_dir}: its '{key}' differs from {whose}, so its trials present "
                "other poses; run the same protocol (same config and seeds)"
            )


def check_part_of(main: RunData, part: RunData, part_dir: Path, whose: str) -> None:
    """Raise unless ``part`` ran part of ``main``'s trials: the same trial config, base seeds
    among ``main``'s, and each of its rounds on ``main``'s draw for that round.

    Raises:
        RunMismatch: names what differs.
    """
    mine, theirs = _protocol(main.meta), _protocol(part.meta)
    if not _same(mine["trial_config"], theirs["trial_config"]):
        raise RunMismatch(
            f"{part_dir}: its 'trial_config' differs from {whose}, so its trials present other "
            "poses; run a protocol that extends the same one"
        )
    extra = sorted(set(theirs["seeds"] or []) - set(mine["seeds"] or []))
    if extra:
        raise RunMismatch(
            f"{part_dir}: base seeds {extra} are not among {whose} ({mine['seeds']}); --part "
            "needs a subset of its trials"
        )
    keys = part.rounds["trial_key"].astype(str) if len(part.rounds) else pd.Series(dtype=str)
    for kind in ("packed", "pile"):
        draws = f"{kind}_draws"
        a, b = mine[draws] or {}, theirs[draws] or {}
        ran = set(keys[keys.str.startswith(f"{kind}/")].map(_round_id))
        other = sorted(k for k in set(a) & set(b) & ran if not _same(a[k], b[k]))
        if other:
            raise RunMismatch(
                f"{part_dir}: round {other[0]} drew other objects than {whose} ({draws}); "
                "--part needs the same draws (the same object list for packed and pile rounds)"
            )


def _round_id(trial_key: str) -> str:
    """``packed/hsq/s0/round/001`` -> ``s0/round/001``, the key of ``packed_draws``."""
    parts = str(trial_key).split("/")
    return "/".join(parts[2:])


def combine(main: RunData, other: RunData, other_dir: Path) -> None:
    """Add ``other``'s planners (those ``main`` lacks) to ``main`` in place, with a note.

    Raises:
        RunMismatch: the runs' protocols differ (names the first setting that does).
    """
    check_same_trials(main, other, other_dir, "the main run's")
    new = [p for p in other.planners if p not in main.planners]
    if not new:
        return
    main.attempts = pd.concat(
        [main.attempts, other.attempts[other.attempts["planner"].isin(new)]], ignore_index=True
    )
    main.rounds = pd.concat(
        [main.rounds, other.rounds[other.rounds["planner"].isin(new)]], ignore_index=True
    )
    main.planners = [*main.planners, *new]
    # Rows keep their own run's provenance (its backend), named by that run, not "this run".
    label = other.measured.replace("(this run", f"(run {other_dir.name}")
    main.joined.update({p: other.joined.get(p, label) for p in new})
    versions = sorted(set(other.attempts["code_version"]))
    main.notes.append(
        f"rows of {', '.join(new)} come from run {other_dir.name} (config hash "
        f"{other.meta.get('config_hash', '?')}, code {', '.join(versions)}): the same protocol, "
        "seeds and draws, so the same poses"
    )
