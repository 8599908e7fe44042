"""The README's headline tables, written from the canonical runs under ``results/``.

Each table is a block of README.md between ``<!-- table: NAME -->`` and ``<!-- /table -->``;
its rows come from the report files of one run (``table1_isolated.csv``, ``table2_packed.csv``,
``table4_pile.csv``, ``paired.csv``) and its "measured at" line from that run's ``run.json``, so
every number on the front page names the run and the code version that made it.

    python -m hsqbench.experiment.front_page            # rewrite the blocks of README.md
    python -m hsqbench.experiment.front_page --check    # exit 1 if README.md is out of date

``make results`` ends with the first; a test runs the second on the committed results.
"""

from __future__ import annotations

import argparse
import json
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.generated import write_or_check
from hsqbench.experiment.graspable import method_label
from hsqbench.experiment.markdown import md_table, p_text, signed_pp
from hsqbench.experiment.object_table import OBJECTS_CSV
from hsqbench.experiment.paired_table import DEFAULT_REFERENCE, PAIRED_CSV
from hsqbench.experiment.pile_table import TABLE4_CSV
from hsqbench.experiment.report import TABLE1_CSV, TABLE2_CSV
from hsqbench.settings import REPO_ROOT

BLOCK = re.compile(r"(<!-- table: (?P<name>[\w-]+) -->\n)(?P<body>.*?)(<!-- /table -->)", re.S)


_PAIRED_KEYS = ["comparison", "planner"]


class FrontPageError(ValueError):
    """A block or a run the front page needs is missing; the message says which and what to do."""


@dataclass(frozen=True)
class Run:
    """One run folder's report files (read once)."""

    folder: Path
    meta: dict
    paired: pd.DataFrame

    @classmethod
    def load(cls, folder: Path) -> Run:
        meta_path = folder / "run.json"
        if not meta_path.is_file():
            raise FrontPageError(
                f"{folder}: no run.json; make the canonical runs first (`make results`)"
            )
        paired = folder / PAIRED_CSV
        return cls(
            folder,
            json.loads(meta_path.read_text()),
            pd.read_csv(paired) if paired.is_file() else pd.DataFrame(columns=_PAIRED_KEYS),
        )

    def table(self, name: str) -> pd.DataFrame:
        path = self.folder / name
        if not path.is_file():
            raise FrontPageError(f"{path} is missing; write the run's report (`hsqbench report`)")
        return pd.read_csv(path)

    def vs_reference(self, comparison: str, label: str) -> str:
        """The paired difference of planner ``label`` to the reference over objects or rounds,
        its interval and Holm-adjusted p, as a cell."""
        if label == method_label(DEFAULT_REFERENCE):
            return "reference"
        r = self._paired_row(comparison, label)
        if r is None:
            return ""
        ci = (
            f" [{signed_pp(r.ci_low_pp)}, {signed_pp(r.ci_high_pp)}]"
            if np.isfinite(r.ci_low_pp)
            else ""
        )
        return f"{signed_pp(r.difference_pp)}{ci}, p {p_text(r.p_holm)}"

    def _paired_row(self, comparison: str, label: str) -> Any:
        p = self.paired
        rows = p[(p["comparison"] == comparison) & (p["planner"].map(method_label) == label)]
        return None if rows.empty else next(rows.itertuples())

    def paired_note(self, comparison: str) -> str:
        """The line under a table: what its paired column tests, and the Holm family."""
        p = self.paired
        family = p[p["comparison"] == comparison]
        if family.empty:
            return ""
        unit = str(family["unit"].iloc[0])
        judged = family[family["verdict"] != "not distinguishable"]
        words = ", ".join(f"{r.planner} {r.verdict}" for r in judged.itertuples()) or "none"
        return (
            f"Paired column: difference to {DEFAULT_REFERENCE} over {unit} (cluster-bootstrap "
            f"interval; exact sign-flip p over {unit}), p Holm-adjusted over the {len(family)} "
            f"planners of this table; at p < 0.05 after adjustment: {words}. Others: not "
            "distinguishable."
            + (" GSR and CR intervals: cluster bootstrap over rounds." if unit == "rounds" else "")
        )

    def objects_interval(self, label: str) -> str:
        """Planner ``label``'s isolated GSR interval over objects (``object_level.csv``; a run
        with too few objects has none: an empty cell)."""
        if not (self.folder / OBJECTS_CSV).is_file():
            return ""
        table = self.table(OBJECTS_CSV)
        rows = table[table["planner"].map(method_label) == label]
        if rows.empty:
            return ""
        r = rows.iloc[0]
        return _ci(r.objects_low_percent, r.objects_high_percent)

    def measured_line(self) -> str:
        m = self.meta
        seeds = ", ".join(str(s) for s in m["config"]["seeds"])
        machine = m.get("machine", {})
        where = f", {machine['cpus']} cores of {machine['cpu_model']}" if machine else ""
        rel = self.folder.name
        return (
            f"*Measured at:* code `{m['code_version']}`: `results/{rel}/` (config "
            f"`{m['config_name']}` {m['config_hash']}, base seeds {seeds}{where})."
        )


def _pct(v: float) -> str:
    return "" if not np.isfinite(v) else f"{v:.1f}"


def _ci(low: float, high: float) -> str:
    return "" if not np.isfinite(low) else f"[{low:.1f}, {high:.1f}]"


def _kn(k: float, n: float) -> str:
    return "" if not np.isfinite(n) or n == 0 else f"{int(k)}/{int(n)}"


#: A table's middle columns: (header, cell of a report CSV row).
Columns = tuple[tuple[str, Callable[[Any], str]], ...]

GSR_CELLS: Columns = (
    ("GSR", lambda r: _pct(r.gsr_percent)),
    ("95 % CI", lambda r: _ci(r.gsr_ci_low_percent, r.gsr_ci_high_percent)),
)
CR_CELLS: Columns = (
    ("CR", lambda r: _pct(r.cr_percent)),
    ("95 % CI", lambda r: _ci(r.cr_ci_low_percent, r.cr_ci_high_percent)),
)
KN_CELL: Columns = (("k/n", lambda r: _kn(r.successes, r.attempts)),)
ISOLATED: Columns = (
    ("GSR", lambda r: _pct(r.gsr_percent)),
    ("95 % CI", lambda r: _ci(r.ci_low_percent, r.ci_high_percent)),
    *KN_CELL,
    ("graspable", lambda r: _pct(r.graspable_gsr_percent)),
    ("95 % CI", lambda r: _ci(r.graspable_ci_low_percent, r.graspable_ci_high_percent)),
)
#: Unseen objects: the interval over objects first (the claim is about the next object).
ISOLATED_UNSEEN: Columns = (
    ("GSR", lambda r: _pct(r.gsr_percent)),
    ("95 % CI over objects", lambda r: r.objects_ci),
    ("95 % CI, Wilson", lambda r: _ci(r.ci_low_percent, r.ci_high_percent)),
    *KN_CELL,
    ("graspable", lambda r: _pct(r.graspable_gsr_percent)),
    ("95 % CI", lambda r: _ci(r.graspable_ci_low_percent, r.graspable_ci_high_percent)),
)
PACKED: Columns = (
    *GSR_CELLS,
    *CR_CELLS,
    ("CR, graspable at start", lambda r: _pct(r.graspable_cr_percent)),
)
PILE: Columns = (*GSR_CELLS, *KN_CELL, *CR_CELLS)


def _render(run: Run, csv: str, columns: Columns, comparison: str, reported: bool) -> str:
    """One row per planner of ``run``'s report ``csv``: method, ``columns``, source, and the
    paired difference to hsq in ``comparison`` (the papers' reported rows unless not
    ``reported``)."""
    table = run.table(csv)
    if not reported:
        table = table[table["source"].str.startswith("measured")]
    if columns is ISOLATED_UNSEEN:
        table = table.assign(objects_ci=[run.objects_interval(m) for m in table["method"]])
    rows = []
    for r in table.itertuples():
        measured = str(r.source).startswith("measured")
        rows.append(
            [
                r.method,
                *(cell(r) for _, cell in columns),
                "measured" if measured else str(r.source),
                run.vs_reference(comparison, r.method) if measured else "",
            ]
        )
    what = comparison.split()[-1]
    over = "objects" if comparison == "isolated GSR" else "rounds"
    paired = f"vs hsq over {over}, paired (pp)"
    paired = paired if what == "GSR" else f"{what} {paired}"
    table_md = md_table(["planner", *(h for h, _ in columns), "source", paired], rows)
    note = run.paired_note(comparison)
    return f"{table_md}\n\n{note}" if note else table_md


def isolated_table(run: Run, reported: bool = True) -> str:
    """Table I: isolated GSR over all and over graspable presentations, paired to hsq."""
    return _render(run, TABLE1_CSV, ISOLATED, "isolated GSR", reported)


def unseen_isolated_table(run: Run) -> str:
    """Table III: as Table I with the interval over objects first, and no reported rows."""
    return _render(run, TABLE1_CSV, ISOLATED_UNSEEN, "isolated GSR", reported=False)


def packed_table(run: Run, reported: bool = True) -> str:
    """Table II: packed GSR and CR (all and graspable), CR paired to hsq."""
    return _render(run, TABLE2_CSV, PACKED, "packed CR", reported)


def pile_table(run: Run) -> str:
    """Table IV: pile GSR and CR, CR paired to hsq (GIGA's reported row last, as context)."""
    return _render(run, TABLE4_CSV, PILE, "pile CR", reported=True)


#: README block name -> (run folder under results/, table writer).
TABLES: dict[str, tuple[str, Callable[[Run], str]]] = {
    "paper-isolated": ("paper3", isolated_table),
    "paper-packed": ("paper3", packed_table),
    # The papers report nothing on these objects: their rows would mislead here.
    "unseen-isolated": ("ycb3", unseen_isolated_table),
    "unseen-packed": ("ycb3", lambda run: packed_table(run, reported=False)),
    "paper-pile": ("paper3-pile", pile_table),
}


def render_block(name: str, results: Path) -> str:
    """The markdown of README block ``name`` from the runs under ``results``."""
    if name not in TABLES:
        raise FrontPageError(f"README block {name!r} is not one of {sorted(TABLES)}")
    folder, write = TABLES[name]
    run = Run.load(results / folder)
    return f"{write(run)}\n\n{run.measured_line()}\n"


def update(text: str, results: Path) -> str:
    """``text`` (README.md) with every table block rewritten from ``results``."""
    found = {m["name"] for m in BLOCK.finditer(text)}
    if not found:
        raise FrontPageError("README.md has no <!-- table: NAME --> ... <!-- /table --> block")
    return BLOCK.sub(lambda m: m[1] + render_block(m["name"], results) + m[4], text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m hsqbench.experiment.front_page",
        description="Rewrite README.md's headline tables from the canonical runs in results/.",
    )
    parser.add_argument("--readme", type=Path, default=REPO_ROOT / "README.md")
    parser.add_argument("--results", type=Path, default=REPO_ROOT / "results")
    parser.add_argument("--check", action="store_true", help="exit 1 if README.md is stale")
    args = parser.parse_args(argv)
    text = args.readme.read_text()
    try:
        new = update(text, args.results)
    except FrontPageError as exc:
        print(f"front page: {exc}", file=sys.stderr)
        return 2
    module = "hsqbench.experiment.front_page"
    return write_or_check(args.readme, text, new, args.check, "tables", args.results, module)


if __name__ == "__main__":
    sys.exit(main())
