"""The figures of a run's report (PNG): the headline rates, how attempts end, the paired
comparison with the reference planner, GSR per object and planning time. Every planner keeps
one colour across them (:mod:`hsqbench.experiment.plots.palette`)."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from hsqbench.experiment.paired_table import PAIRED_CSV
from hsqbench.experiment.plots.failures import draw_failures
from hsqbench.experiment.plots.forest import draw_forest
from hsqbench.experiment.plots.headline import draw_headline
from hsqbench.experiment.plots.per_object import draw_gsr_per_object, draw_planning_time
from hsqbench.experiment.run_data import RunData

HEADLINE_PLOT = "headline.png"
OUTCOMES_PLOT = "outcomes.png"
PAIRED_PLOT = "paired.png"
GSR_PLOT = "gsr_per_object.png"
TIMES_PLOT = "planning_time.png"


def write_plots(
    data: RunData,
    t1o: pd.DataFrame,
    outcomes: pd.DataFrame,
    judged: dict[str, pd.DataFrame],
    run_dir: Path,
) -> list[Path]:
    """Write every figure the run has data for into ``run_dir``; returns the paths written.

    ``t1o``: isolated GSR per object; ``outcomes``: outcome counts (``outcomes.csv``);
    ``judged``: the verdict tables by CSV name (the paired one, when present, is drawn).
    """
    paired = judged.get(PAIRED_CSV, pd.DataFrame())
    figures = {
        HEADLINE_PLOT: draw_headline(data),
        OUTCOMES_PLOT: draw_failures(outcomes, data.planners) if not outcomes.empty else None,
        PAIRED_PLOT: draw_forest(paired, data.planners, data.confidence),
        GSR_PLOT: draw_gsr_per_object(data, t1o),
        TIMES_PLOT: draw_planning_time(data),
    }
    written = []
    for name, fig in figures.items():
        if fig is not None:
            fig.savefig(run_dir / name)
            written.append(run_dir / name)
    return written
