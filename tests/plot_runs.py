"""Synthetic runs with known counts for the report's figures, and a check that no two texts
of a drawn figure overlap (titles, tick labels, legends, annotations)."""

from __future__ import annotations

from typing import Any

from hsqbench.experiment.csv_fields import format_row, typed_frame
from hsqbench.experiment.run_data import RunData
from hsqbench.experiment.schema import ATTEMPTS, ROUNDS

OBJECTS = ("mug", "bowl")


def attempts(experiment: str, planner: str, outcomes: list[str], graspable: list[int]) -> list:
    """One attempt row per outcome (``success`` succeeds), objects alternating."""
    return [
        {
            "experiment": experiment,
            "planner": planner,
            "status": "ok",
            "outcome": o,
            "success": int(o == "success"),
            "graspable": g,
            "objects": OBJECTS[i % len(OBJECTS)],
            "base_seed": 0,
            "trial_index": i,
            "seed": i,
            "attempt_index": 0,
            "n_attempts": 1,
            "planning_s": 0.1 + 0.01 * i,
        }
        for i, (o, g) in enumerate(zip(outcomes, graspable, strict=True))
    ]


def rounds(kind: str, planner: str, cleared: list[int], per_round: int = 5) -> list:
    """Rounds of ``per_round`` objects (the first four graspable), ``cleared[i]`` removed."""
    names = [f"o{k}" for k in range(per_round)]
    return [
        {
            "trial_key": f"{kind}/{planner}/s0/{i:03d}",
            "planner": planner,
            "status": "ok",
            "base_seed": 0,
            "trial_index": i,
            "seed": i,
            "n_attempts": c,
            "objects": ";".join(names),
            "objects_cleared": ";".join(names[:c]),
            "objects_graspable": ";".join(names[:4]),
            "n_objects": per_round,
            "n_cleared": c,
        }
        for i, c in enumerate(cleared)
    ]


def synthetic_run(planners=("hsq", "antipodal", "oracle"), pile: bool = False) -> RunData:
    """hsq: isolated 9/10 (graspable 8/8), packed 6 attempts, rounds clearing 5 and 4 of 5;
    antipodal: isolated 4/10 (graspable 4/8), failures of three kinds; the oracle: 8/10."""
    iso = {
        "hsq": ["success"] * 9 + ["dropped"],
        "antipodal": ["success"] * 4 + ["no_grasp_found"] * 4 + ["unreachable", "empty_grasp"],
        "oracle": ["success"] * 8 + ["no_grasp_found"] * 2,
    }
    graspable = [1] * 8 + [0] * 2
    packed = ["success"] * 5 + ["dropped"]
    pile_outcomes = ["success", "no_grasp_found", "collision_on_approach", "empty_grasp", "dropped"]
    pile_outcomes += ["success"]
    rows, rnd = [], []
    for p in planners:
        rows += attempts("isolated", p, iso[p], graspable)
        rows += attempts("packed", p, packed, [1] * 6)
        rnd += rounds("packed", p, [5, 4] if p == "hsq" else [3, 2])
        if pile:
            rows += attempts("pile", p, pile_outcomes, [1] * 6)
            rnd += rounds("pile", p, [4, 4])
    # Typed as load_run types a run's files (hsqbench.experiment.schema).
    frame = typed_frame([format_row(ATTEMPTS, r) for r in rows], "attempts")
    rounds_frame = typed_frame([format_row(ROUNDS, r) for r in rnd], "rounds")
    meta = {"run": "synthetic", "config": {"planners": list(planners), "confidence": 0.95}}
    return RunData(frame, rounds_frame, meta, list(planners), list(OBJECTS), 0.95)


def overlapping_texts(fig: Any) -> list[tuple[str, str]]:
    """Pairs of drawn texts of ``fig`` whose boxes overlap by more than a pixel: titles, axis
    and tick labels in view, annotations and legend entries."""
    boxes = _drawn_texts(fig)
    return [
        (a, b)
        for i, (a, box_a) in enumerate(boxes)
        for b, box_b in boxes[i + 1 :]
        if box_a.overlaps(box_b)
    ]


def cut_off_texts(fig: Any) -> list[str]:
    """Drawn texts of ``fig`` that reach past the image's edge."""
    width, height = fig.get_size_inches() * fig.get_dpi()
    return [
        text
        for text, box in _drawn_texts(fig)
        if box.x0 < 0 or box.y0 < 0 or box.x1 > width or box.y1 > height
    ]


def _drawn_texts(fig: Any) -> list[tuple[str, Any]]:
    """(text, box in pixels, less a pixel all round) of every text ``fig`` draws."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg

    canvas = FigureCanvasAgg(fig)
    canvas.draw()
    renderer = canvas.get_renderer()
    texts = [*fig.texts, *(t for legend in fig.legends for t in legend.get_texts())]
    for ax in (a for a in fig.axes if a.get_visible()):
        texts += [ax.title, ax.xaxis.label, ax.yaxis.label, *ax.texts]
        if ax.axison:  # an axes turned off (a column of text) draws no ticks
            texts += _in_view(ax.get_xticklabels(), ax.get_xlim(), 0)
            texts += _in_view(ax.get_yticklabels(), ax.get_ylim(), 1)
    return [(t.get_text(), t.get_window_extent(renderer).padded(-1))
            for t in texts if t.get_visible() and t.get_text().strip()]  # fmt: skip


def _in_view(labels: list, limits: tuple[float, float], axis: int) -> list:
    lo, hi = sorted(limits)
    return [t for t in labels if lo <= t.get_position()[axis] <= hi]


def only(data: RunData, experiment: str) -> RunData:
    """``data`` with one experiment's attempts and rounds left (a pile-only run, say)."""
    data.attempts = data.attempts[data.attempts["experiment"] == experiment]
    data.rounds = data.rounds[data.rounds["trial_key"].str.startswith(f"{experiment}/")]
    return data
