"""``sweep.md``: the sweep table as Markdown, one table per parameter and protocol; each cell the
planner's rate at the point and its paired difference to the default point (bold when the
Holm-adjusted p of that point's comparison with its default calls it a difference)."""

from __future__ import annotations

from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.markdown import md_table, p_text, signed_pp
from hsqbench.experiment.paired import SAME
from hsqbench.experiment.sweep_table import default_point


def _cell(r: Any) -> str:
    rate = f"{r.gsr_percent:.1f} ({int(r.successes)}/{int(r.n)})" if r.n else "no attempts"
    if np.isfinite(r.cr_percent):
        rate += f", CR {r.cr_percent:.1f}"
    if not np.isfinite(r.vs_default_difference_pp):
        return rate
    diff = f"{signed_pp(r.vs_default_difference_pp)} [{signed_pp(r.vs_default_ci_low_pp)}, "
    diff += f"{signed_pp(r.vs_default_ci_high_pp)}]"
    if r.vs_default_verdict != SAME:
        diff = f"**{diff}**"
    return f"{rate}; {diff}, p {p_text(r.vs_default_p_holm)}"


def sweep_markdown(table: pd.DataFrame, meta: dict[str, Any]) -> str:
    """The Markdown of ``sweep.csv``'s rows (``table``) for the sweep described by ``meta``."""
    lines = [
        "# Sweep results",
        "",
        "Per point and planner: GSR % (successes/n; packed: and CR %) and the paired difference "
        "to the parameter's default point on the same presentations (isolated: GSR, Newcombe's "
        "95 % interval and the exact McNemar test; packed and pile: CR over rounds, bootstrap "
        "interval and exact sign-flip test), in percentage points; p Holm-adjusted over the "
        "planners' tests of the point against its default, as `hsqbench compare` does; bold: a "
        "difference after the adjustment. Intervals of the rates are in sweep.csv.",
    ]
    for name, param in meta["parameters"].items():
        rows = table[table["parameter"] == name]
        if not len(rows):
            continue
        default = (default_point(param) or {}).get("label")
        lines += ["", f"## {name}: {param.get('axis', name)}", "", f"![{name}]({name}.png)"]
        for (protocol, experiment), part in rows.groupby(["protocol", "experiment"], sort=False):
            planners = list(dict.fromkeys(part["planner"]))
            body = []
            for label, point in part.groupby("value", sort=False):
                cells = {r.planner: _cell(r) for r in point.itertuples()}
                shown = f"{label} (default)" if label == default else str(label)
                body.append([shown, *(cells.get(p, "") for p in planners)])
            lines += [
                "",
                f"**{protocol}, {experiment}**",
                "",
                md_table(["point", *planners], body),
            ]
    return "\n".join(lines) + "\n"
