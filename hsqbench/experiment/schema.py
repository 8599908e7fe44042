"""The columns of a run's results files, once: name, kind, units and meaning of every column of
``attempts.csv`` and ``rounds.csv``.

The writer formats each field by its column's kind (:func:`format_field`), :func:`typed_frame`
gives every reader (``load_run``, the report, a user's notebook) the same dtypes whatever the
pandas version, and docs/results-format.md's column tables are rendered from here
(``python -m hsqbench.experiment.schema`` rewrites them, ``--check`` says whether they drifted).

Dtypes are NumPy's, with NaN for an empty field, as ``pd.read_csv`` reads the files: a number
column that may be empty (an error row, an older run) is ``float64`` even when its values are
whole numbers, since only NaN behaves alike in masks, sums and means under pandas 2.2 and 3.x;
``int64`` columns are the trial's identity, filled on every row of every version. Text stays
text, ``""`` where empty (``str`` under pandas 3, ``object`` before).
"""

from __future__ import annotations

import argparse
import math
import re
import sys
from collections.abc import Iterable, Mapping, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
import pandas as pd

from hsqbench.sim.outcome import Outcome

#: kind -> (pandas dtype, what an empty field is). Text kinds differ only in what they document.
KINDS: dict[str, tuple[str, str]] = {
    "int": ("int64", "never empty"),
    "count": ("float64", "NaN where empty"),  # whole numbers, absent on some rows
    "float": ("float64", "NaN where empty"),
    "bool": ("float64", "1.0 / 0.0, NaN where empty"),
    "text": ("str", '"" where empty'),
}
TEXT_KINDS = ("text",)


class SchemaError(ValueError):
    """A field that does not hold what its column's kind says (a damaged or edited file)."""


@dataclass(frozen=True)
class Column:
    """One column: ``values`` is the doc's "units / values" cell (units in the name: ``_s``,
    ``_m``)."""

    name: str
    kind: str
    values: str
    meaning: str

    def __post_init__(self) -> None:
        if self.kind not in KINDS:
            raise ValueError(f"column {self.name}: kind {self.kind!r} is not one of {list(KINDS)}")

    @property
    def dtype(self) -> str:
        return KINDS[self.kind][0]


POSE = "pose"
_WALL = "s, wall"
_SIM = "s, simulated"

TRIAL_KEY = Column(
    "trial_key",
    "text",
    "text",
    "identity of the trial in the run: `isolated/<planner>/s<base seed>/<object>/<index>`, "
    "`packed/<planner>/s<base seed>/round/<index>`, `pile/...` likewise",
)
PLANNER = Column("planner", "text", "text", "the planner's name")
BASE_SEED = Column("base_seed", "int", "integer", "the protocol's base seed this trial belongs to")
TRIAL_INDEX = Column(
    "trial_index",
    "int",
    "integer",
    "index of the trial (per object for isolated, per round for packed and pile)",
)
SEED = Column(
    "seed", "int", "integer", "the trial's own seed (everything random in the trial comes from it)"
)
OBJECTS = Column("objects", "text", "names joined by `;`", "the objects of the scene")
SCENE_SETTLE_S = Column(
    "scene_settle_s",
    "float",
    _SIM,
    "simulated time the scene took to settle before the cameras looked",
)
SCENE_MAX_SPEED = Column(
    "scene_max_speed",
    "float",
    "m/s or rad/s",
    "largest object speed at the end of settling (above the physics config's "
    "`settle_speed_mps`: still moving)",
)
TRIAL_WALL_S = Column(
    "trial_wall_s",
    "float",
    _WALL,
    "wall time of the whole trial in its worker (the same on every row of a trial)",
)
WORKER = Column("worker", "text", "text", "`host:pid` of the worker process")
CONFIG_HASH = Column(
    "config_hash",
    "text",
    "hex",
    "hash of the run's full config (protocol, trial config tree, named files)",
)
CODE_VERSION = Column(
    "code_version",
    "text",
    "text",
    "`git describe` of the checkout (`-dirty` when modified), else the package version",
)
FINISHED_AT = Column("finished_at", "text", "ISO 8601, UTC", "when the row was written")

FACTOR_NAMES = ("h_alpha", "h_beta", "h_gamma", "h_delta")

ATTEMPTS: tuple[Column, ...] = (
    TRIAL_KEY,
    Column("experiment", "text", "text", "`isolated`, `packed` or `pile`"),
    PLANNER,
    BASE_SEED,
    TRIAL_INDEX,
    SEED,
    OBJECTS,
    Column(
        "attempt_index",
        "int",
        "integer",
        "0-based index of the attempt in its trial; `-1` on the error row of a trial that could "
        "not run",
    ),
    Column("n_attempts", "int", "integer", "attempts of the trial (0 on an error row)"),
    Column(
        "status",
        "text",
        "text",
        "`ok`, or `error` (the trial did not run: an infrastructure error, left out of GSR and "
        "CR; `detail` says why); a planner's own error is `ok` with outcome `planner_error`",
    ),
    Column(
        "outcome",
        "text",
        "text",
        ", ".join(f"`{o}`" for o in Outcome)
        + " (rules: `hsqbench/sim/trial/__init__.py`); empty on an error row. `planner_error`: "
        "the planner raised or broke its contract, a failed attempt in GSR and CR; `detail` "
        "names the planner's file and line",
    ),
    Column("success", "bool", "`1` / `0`", "outcome is `success`"),
    Column(
        "graspable",
        "bool",
        "`1` / `0`",
        "the oracle found a feasible grasp on the true meshes in this presentation (empty: not "
        "checked)",
    ),
    Column(
        "target",
        "text",
        "name",
        "the object grasped, or the one meant (nearest the grasp) for a failure; empty without a "
        "grasp",
    ),
    Column(
        "object_pose",
        "text",
        POSE,
        "settled world pose of `target` when the cameras looked (before the arm moved); for an "
        "isolated trial the only object's, even without a grasp",
    ),
    Column(
        "resting_pose",
        "count",
        "integer",
        "index of that object's drawn resting pose, most probable first; `-1` upright",
    ),
    Column(
        "rank_executed",
        "count",
        "integer",
        "0-based rank, in the planner's list, of the executed grasp; `-1` none executed",
    ),
    Column("n_grasps", "count", "integer", "grasps the planner returned"),
    Column(
        "score",
        "float",
        "planner's units, hsq in [0, 1]",
        "the executed grasp's score (for `unreachable`: the best grasp's)",
    ),
    *(
        Column(
            name,
            "float",
            "[0, 1]",
            "hsq's score factors of that grasp (empty for other planners)",
        )
        for name in FACTOR_NAMES
    ),
    Column(
        "factors", "text", "JSON object", "every score factor the planner reported for that grasp"
    ),
    Column("width_m", "float", "m", "the grasp's planned width between the contacts"),
    Column(
        "grasp_pose",
        "text",
        POSE,
        "world pose of the TCP at the executed grasp, as executed (nudged clear of the table if "
        "it was); for `unreachable`: the planner's best grasp, which no motion reached; empty for "
        "`no_grasp_found`",
    ),
    Column(
        "grasp_flipped",
        "bool",
        "`1` / `0`",
        "the executed grasp is the planner's turned by pi about its approach axis (the same "
        "parallel-jaw grasp, reached with a shorter move)",
    ),
    Column(
        "grasp_pose_object",
        "text",
        POSE,
        "`grasp_pose` in the frame of the object at `object_pose` (where on the object the hand "
        "closed)",
    ),
    Column(
        "top_scores",
        "text",
        "numbers joined by spaces",
        "scores of the planner's first grasps, best first (at most `recorded_scores` of the "
        "trial config, 5)",
    ),
    Column(
        "perception_s",
        "float",
        _WALL,
        "wall time of perception (rendering the cameras and fusing the cloud; the first attempt "
        "also makes the sensor)",
    ),
    Column("planning_s", "float", _WALL, "wall time of the planner's `plan` call"),
    Column(
        "execution_s",
        "float",
        _WALL,
        "wall time from motion planning to the outcome (includes `motion_planning_s`)",
    ),
    Column(
        "motion_planning_s",
        "float",
        _WALL,
        "wall time of the inverse kinematics and motion checks, part of `execution_s`",
    ),
    Column(
        "sim_time_s",
        "float",
        _SIM,
        "simulated time of the executed motion (0 when nothing was executed)",
    ),
    Column(
        "planner_stages_s",
        "text",
        "JSON object, s",
        "the planner's own wall time per stage (hsq: `cleaning`, `recovery`, `synthesis`, "
        "`elimination`, `scoring`, `total`); empty when the planner reports none",
    ),
    Column(
        "ranks_tried",
        "count",
        "integer",
        "distinct grasps motion-planned in this attempt (1: the first one tried was executed, "
        "and `hsqbench replay` reproduces it exactly)",
    ),
    Column(
        "detail",
        "text",
        "text",
        "why the attempt ended so, in words (which contact, which IK step, ...); on an error "
        "row, the error",
    ),
    SCENE_SETTLE_S,
    SCENE_MAX_SPEED,
    TRIAL_WALL_S,
    WORKER,
    CONFIG_HASH,
    CODE_VERSION,
    FINISHED_AT,
)

ROUNDS: tuple[Column, ...] = (
    TRIAL_KEY,
    PLANNER,
    BASE_SEED,
    TRIAL_INDEX,
    SEED,
    OBJECTS,
    Column("n_objects", "int", "integer", "objects placed in the round"),
    Column("objects_cleared", "text", "names joined by `;`", "objects carried into the bin"),
    Column("n_cleared", "count", "integer", "how many (empty on an error row)"),
    Column("clearance_rate", "float", "[0, 1]", "`n_cleared / n_objects`"),
    Column(
        "objects_lost",
        "text",
        "names joined by `;`",
        "objects taken out without being cleared (off the table, out of the cameras' view, or "
        "left on the hand)",
    ),
    Column("n_lost", "count", "integer", "how many"),
    Column(
        "objects_graspable",
        "text",
        "names joined by `;`",
        "objects on which the oracle found a feasible grasp in the settled scene before the first "
        "attempt (empty: not checked)",
    ),
    Column("n_graspable", "count", "integer", "how many (empty: not checked)"),
    Column("n_attempts", "int", "integer", "attempts of the round (0 on an error row)"),
    Column("n_success", "count", "integer", "successful attempts"),
    Column("status", "text", "text", "`ok` or `error`"),
    Column(
        "detail",
        "text",
        "text",
        "draws rejected before the round's objects (not placeable, or a pile that did not "
        "settle), or the error",
    ),
    SCENE_SETTLE_S,
    SCENE_MAX_SPEED,
    TRIAL_WALL_S,
    WORKER,
    CONFIG_HASH,
    CODE_VERSION,
    FINISHED_AT,
)

ATTEMPT_COLUMNS: tuple[str, ...] = tuple(c.name for c in ATTEMPTS)
ROUND_COLUMNS: tuple[str, ...] = tuple(c.name for c in ROUNDS)
_BY_NAME = {"attempts": {c.name: c for c in ATTEMPTS}, "rounds": {c.name: c for c in ROUNDS}}


# -- writing ---------------------------------------------------------------------------------
def _is_missing(value: Any) -> bool:
    return value is None or (isinstance(value, float | np.floating) and math.isnan(value))


def format_field(column: Column, value: Any) -> str:
    """``value`` as ``column``'s CSV field, on one line: numbers exact (``repr`` of the float),
    booleans ``1``/``0``, None and NaN empty. NumPy scalars are written as the Python numbers
    they hold (never ``np.float64(...)``).

    Raises:
        SchemaError: a value the column's kind cannot hold (text in a number column, a
            fraction in an integer column).
    """
    if _is_missing(value):
        return ""
    kind = column.kind
    if kind == "text":
        text = str(value)
        return (
            text.replace("\r", " ").replace("\n", " | ") if ("\n" in text or "\r" in text) else text
        )
    if isinstance(value, str):
        raise SchemaError(f"column {column.name} ({kind}) cannot hold the text {value!r}")
    if kind == "bool":
        if value not in (0, 1):
            raise SchemaError(f"column {column.name} (bool) cannot hold {value!r}")
        return "1" if value else "0"
    if isinstance(value, bool | np.bool_):
        return "1" if value else "0"
    if kind in ("int", "count") or isinstance(value, int | np.integer):
        whole = int(value)
        if whole != value:
            raise SchemaError(f"column {column.name} ({kind}) cannot hold the fraction {value!r}")
        return str(whole)
    return repr(float(value))


def format_row(columns: Sequence[Column], record: Mapping[str, Any]) -> dict[str, str]:
    """One CSV row of ``record`` (columns it lacks are empty)."""
    return {c.name: format_field(c, record.get(c.name)) for c in columns}


# -- reading ---------------------------------------------------------------------------------
def _parse(column: Column, fields: list[str], where: str) -> Any:
    if column.kind == "text":
        return pd.Series(fields, dtype=str)
    number = float if column.kind != "int" else int
    out = []
    for i, text in enumerate(fields):
        if text == "":
            if column.kind == "int":
                raise SchemaError(
                    f"{where}: row {i + 1} has no {column.name} (an integer every row holds); "
                    "the file was edited or damaged"
                )
            out.append(math.nan)
            continue
        try:
            out.append(number(text))
        except ValueError:
            raise SchemaError(
                f"{where}: row {i + 1}: {column.name} is {text!r}, not a {column.kind} "
                f"({column.values}); the file was edited or damaged"
            ) from None
    return np.array(out, dtype=column.dtype)


def typed_frame(
    rows: Iterable[Mapping[str, str]], table: str = "attempts", where: str = ""
) -> pd.DataFrame:
    """The rows of ``attempts.csv`` or ``rounds.csv`` (``table``), as read (every field text,
    a column a row lacks empty) as a frame of the schema's columns, in order, with their dtypes.

    Raises:
        SchemaError: a field its column's kind cannot hold (``where`` names the file).
    """
    columns = ATTEMPTS if table == "attempts" else ROUNDS
    rows = list(rows)
    where = where or f"{table}.csv"
    data = {c.name: _parse(c, [str(r.get(c.name, "")) for r in rows], where) for c in columns}
    return pd.DataFrame(data, index=pd.RangeIndex(len(rows)))


def column(table: str, name: str) -> Column:
    """The column ``name`` of ``table`` (``attempts`` or ``rounds``)."""
    return _BY_NAME[table][name]


# -- the doc's tables --------------------------------------------------------------------------
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
        prog="python -m hsqbench.experiment.schema",
        description="Rewrite the column tables of docs/results-format.md from the schema.",
    )
    parser.add_argument("--doc", type=Path, default=DOC)
    parser.add_argument("--check", action="store_true", help="exit 1 if the doc's tables differ")
    args = parser.parse_args(argv)
    text = args.doc.read_text()
    new = update_doc(text)
    if args.check:
        if new != text:
            print(
                f"{args.doc}: column tables differ from hsqbench/experiment/schema.py; run "
                "`python -m hsqbench.experiment.schema`",
                file=sys.stderr,
            )
            return 1
        return 0
    args.doc.write_text(new)
    print(f"{args.doc}: column tables written")
    return 0


if __name__ == "__main__":
    sys.exit(main())
