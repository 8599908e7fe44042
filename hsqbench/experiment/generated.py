"""Tracked text the package generates (README.md's tables, docs/results-format.md's column
tables): written anew, or checked for drift (``--check``, for a test or CI)."""

from __future__ import annotations

import sys
from pathlib import Path


def write_or_check(
    path: Path, text: str, new: str, check: bool, what: str, source: object, module: str
) -> int:
    """Write ``new`` over ``path`` (which holds ``text``); with ``check`` write nothing, and say
    on stderr when ``what`` (the generated part) differs from ``source`` and that
    ``python -m <module>`` rewrites it. The exit status: 1 stale, else 0."""
    if check:
        if new != text:
            print(f"{path}: {what} differ from {source}; run `python -m {module}`", file=sys.stderr)
            return 1
        return 0
    path.write_text(new)
    print(f"{path}: {what} written from {source}")
    return 0
