"""A results field as text and back, by its column's kind (:mod:`hsqbench.experiment.schema`).

The writer formats each field with :func:`format_field`, exactly and on one line, and
:func:`typed_frame` gives every reader (``load_run``, the report, a user's notebook) the same
dtypes whatever the pandas version: NumPy's, with NaN for an empty field, as the schema's
kinds say.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping, Sequence
from typing import Any

import numpy as np
import pandas as pd

from hsqbench.experiment.schema import ATTEMPTS, ROUNDS, Column, SchemaError


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
