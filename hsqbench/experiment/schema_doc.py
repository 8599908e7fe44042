"""docs/results-format.md's column tables, rendered from :mod:`hsqbench.experiment.schema`.

``python -m hsqbench.experiment.schema_doc`` rewrites them; ``--check`` exits 1 when they
drifted from the schema.
"""

from __future__ import annotations

import argparse
import re
import sys
from pathlib import Path

from hsqbench.experiment.generated import write_or_check
from hsqbench.experiment.schema import ATTEMPTS, ROUNDS, Column, SchemaError

DOC = Path(__file__).resolve().parents[2] / "docs" / "results-format.md"
BLOCK = re.compile(r"(<!-- columns: (?P<table>\w+) -->\n)(.*?)(<!-- /columns -->)", re.DOTALL)


def _cell(text: str) -> str:
    return text.replace("|", "\\|")


def _dtype_cell(c: Column) -> str:
    return f"`{c.dtype}`" + (" (`object` before pandas 3)" if c.kind == "text" else "")


def render_table(table: str) -> str:
    """The markdown table of ``table``'s columns; in ``rounds``, the columns that are the same
    as in ``attempts.csv`` say so. Consecutive columns alike but for the name share a row."""
    columns = ATTEMPTS if table == "attempts" else ROUNDS
    shared = {id(c) for c in ATTEMPTS} if table == "rounds" else set()
    groups: list[list[Column]] = []
    for c in columns:
        prev = groups[-1][-1] if groups else None

        def same(a: Column, b: Column) -> bool:
            if id(a) in shared or id(b) in shared:
                return id(a) in shared and id(b) in shared
            return (a.kind, a.values, a.meaning) == (b.kind, b.values, b.meaning)

        if prev is not None and same(prev, c):
            groups[-1].append(c)
        else:
            groups.append([c])
    lines = [
        "| column | meaning | units / values | pandas dtype (`load_run`) |",
        "| --- | --- | --- | --- |",
    ]
    for g in groups:
        names = ", ".join(f"`{c.name}`" for c in g)
        c = g[0]
        if id(c) in shared:
            lines.append(f"| {names} | as in `attempts.csv` | | |")
        else:
            lines.append(f"| {names} | {_cell(c.meaning)} | {_cell(c.values)} | {_dtype_cell(c)} |")
    return "\n".join(lines) + "\n"


def update_doc(text: str) -> str:
    """``text`` (docs/results-format.md) with its column tables rendered from the schema."""
    found = {m["table"] for m in BLOCK.finditer(text)}
    if found != {"attempts", "rounds"}:
        raise SchemaError(
            f"{DOC.name} needs one <!-- columns: attempts --> and one <!-- columns: rounds --> "
            f"block, each closed by <!-- /columns -->; found {sorted(found)}"
        )
    return BLOCK.sub(lambda m: m[1] + render_table(m["table"]) + m[4], text)


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(
        prog="python -m hsqbench.experiment.schema_doc",
        description="Rewrite the column tables of docs/results-format.md from the schema.",
    )
    parser.add_argument("--doc", type=Path, default=DOC)
    parser.add_argument("--check", action="store_true", help="exit 1 if the doc's tables differ")
    args = parser.parse_args(argv)
    text = args.doc.read_text()
    new = update_doc(text)
    schema = "hsqbench/experiment/schema.py"
    module = "hsqbench.experiment.schema_doc"
    return write_or_check(args.doc, text, new, args.check, "column tables", schema, module)


if __name__ == "__main__":
    sys.exit(main())
