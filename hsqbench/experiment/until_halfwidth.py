"""Enough trials, not a fixed count (``benchmark --until-halfwidth H``): add base seeds to a run
until every planner's GSR interval is at most H wide on either side, or a seed cap is reached.

The protocol's seeds come first, then the next unused integers up to ``max_seeds`` seeds in all.
The run's config lists all of them (so its hash, and a later ``--resume`` with the same
options, covers the whole sequence); each step runs one more seed's trials into the same folder
(:func:`hsqbench.experiment.runner.run_benchmark`'s ``base_seeds``). The half-width is the
Wilson interval's (high - low) / 2 at the run's confidence, per planner and experiment. What was
asked, the seeds that ran and the widths reached go into ``run.json`` (``until_halfwidth``).

The stop looks at the widths, not at which planner is ahead. A width depends a little on its
rate (p (1 - p)), so the intervals after such a stop are close to, not exactly at, their nominal
coverage; for a sharp comparison of two planners read the paired section instead.
"""

from __future__ import annotations

import sys
from collections.abc import Callable
from dataclasses import replace
from pathlib import Path
from typing import Any

from hsqbench.experiment.config import ExperimentConfig
from hsqbench.experiment.results import STATUS_OK, ResultStore
from hsqbench.experiment.run_data import load_run
from hsqbench.experiment.runner import RunSummary
from hsqbench.experiment.stats import Rate

META_KEY = "until_halfwidth"


def seed_sequence(seeds: tuple[int, ...], max_seeds: int) -> tuple[int, ...]:
    """``seeds``, then the smallest unused non-negative integers, ``max_seeds`` in all.

    Raises:
        ValueError: ``max_seeds`` below the number of the protocol's own seeds.
    """
    if max_seeds < len(seeds):
        raise ValueError(
            f"--max-seeds {max_seeds}: the protocol already has {len(seeds)} seeds {list(seeds)}; "
            "give at least that many"
        )
    out, candidate = list(seeds), 0
    while len(out) < max_seeds:
        if candidate not in out:
            out.append(candidate)
        candidate += 1
    return tuple(out)


def gsr_halfwidths(run_dir: Path, confidence: float) -> dict[str, float]:
    """``"<experiment> <planner>"`` -> half-width of its GSR's Wilson interval (fractions)."""
    attempts = load_run(run_dir).attempts
    if attempts.empty:
        return {}
    ok = attempts[attempts["status"] == STATUS_OK]
    out = {}
    for (experiment, planner), g in ok.groupby(["experiment", "planner"], sort=False):
        rate = Rate.of(int(g["success"].sum()), len(g), confidence)
        out[f"{experiment} {planner}"] = (rate.high - rate.low) / 2
    return out


def run_until_halfwidth(
    config: ExperimentConfig,
    run_dir: Path,
    target: float,
    max_seeds: int,
    run_seeds: Callable[[ExperimentConfig, tuple[int, ...], bool], RunSummary],
    resume: bool = False,
) -> RunSummary:
    """Run seed after seed until every GSR half-width is at most ``target``; returns the last
    step's summary with the trials run, errors and planner errors of all steps.

    ``run_seeds(config, base_seeds, resume)`` runs the trials of those base seeds into
    ``run_dir`` (the command passes :func:`run_benchmark` with its options).

    Raises:
        ValueError: ``target`` not in (0, 0.5), or ``max_seeds`` too small.
    """
    if not 0.0 < target < 0.5:
        raise ValueError(f"--until-halfwidth {target}: give a half-width in (0, 0.5), e.g. 0.02")
    sequence = seed_sequence(config.seeds, max_seeds)
    full = replace(config, seeds=sequence)
    count = len(config.seeds)
    ran = errors = planner_errors = 0
    first_planner_error = ""
    while True:
        summary = run_seeds(full, sequence[:count], resume)
        resume, ran, errors = True, ran + summary.ran, errors + summary.errors
        planner_errors += summary.planner_errors
        first_planner_error = first_planner_error or summary.first_planner_error
        widths = gsr_halfwidths(run_dir, config.confidence)
        wide = {k: w for k, w in widths.items() if w > target}
        print(_progress(sequence[:count], widths, wide, target), file=sys.stderr)
        if not wide or count == len(sequence):
            break
        count += 1
    _record(run_dir, target, max_seeds, sequence[:count], widths, reached=not wide)
    summary.ran, summary.errors = ran, errors
    summary.planner_errors, summary.first_planner_error = planner_errors, first_planner_error
    return summary


def _progress(seeds: tuple[int, ...], widths: dict, wide: dict, target: float) -> str:
    widest = max(widths.items(), key=lambda kv: kv[1], default=("-", 0.0))
    state = (
        f"{len(wide)} GSR interval(s) wider than ±{100 * target:g} points"
        if wide
        else f"every GSR interval within ±{100 * target:g} points"
    )
    return f"seeds {list(seeds)}: {state} (widest: {widest[0]} ±{100 * widest[1]:.1f})"


def _record(run_dir: Path, target: float, max_seeds: int, seeds: tuple[int, ...],
            widths: dict[str, float], reached: bool) -> None:  # fmt: skip
    store = ResultStore(run_dir)
    with store.locked():
        meta: dict[str, Any] = store.read_meta() or {}
        meta[META_KEY] = {
            "target_halfwidth": target,
            "max_seeds": max_seeds,
            "seeds_run": list(seeds),
            "reached": reached,
            "halfwidths": {k: round(v, 6) for k, v in widths.items()},
        }
        store.write_meta(meta)
