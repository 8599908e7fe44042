"""The report's sections that judge planners against each other and set rates in context: the
paired comparison with a reference planner, the object-level uncertainty of isolated GSR, and
the VGN/GIGA-comparable clutter metrics (definitions in docs/statistics.md)."""

from __future__ import annotations

import pandas as pd

from hsqbench.experiment.clutter import CLUTTER_CSV, clutter_table, render_clutter
from hsqbench.experiment.object_table import OBJECTS_CSV, object_level, render_object_level
from hsqbench.experiment.paired_table import (
    DEFAULT_REFERENCE,
    PAIRED_CSV,
    PAIRED_OBJECTS_CSV,
    paired_per_object,
    paired_table,
    render_paired,
)
from hsqbench.experiment.run_data import RunData


def check_reference(data: RunData, reference: str | None) -> str:
    """The reference planner: ``reference`` when given (it must have run), else hsq.

    Raises:
        ValueError: ``reference`` names a planner without rows in the run.
    """
    if reference is None:
        return DEFAULT_REFERENCE
    if reference not in data.planners:
        raise ValueError(
            f"--reference {reference}: no rows of that planner in this run; choose one of "
            f"{', '.join(data.planners) or '(none)'}"
        )
    return reference


def verdict_sections(
    data: RunData, reference: str | None = None
) -> tuple[dict[str, pd.DataFrame], list[str]]:
    """(CSV name -> table, markdown lines) of the three sections; empty tables are left out."""
    ref = check_reference(data, reference)
    paired, per_object = paired_table(data, ref), paired_per_object(data, ref)
    objects, clutter = object_level(data), clutter_table(data, ref)
    lines = render_paired(data, paired, per_object, ref)
    lines += render_object_level(data, objects)
    lines += render_clutter(data, clutter, ref)
    tables = {
        PAIRED_CSV: paired,
        PAIRED_OBJECTS_CSV: per_object,
        OBJECTS_CSV: objects,
        CLUTTER_CSV: clutter,
    }
    return {name: df for name, df in tables.items() if not df.empty}, lines
