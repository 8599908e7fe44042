"""Names a user types (protocols, objects): checked early, with the closest known name.

A misspelt name gets one line naming the closest known one (``difflib``) and the choices, the
same way for every command and the Python API.
"""

from __future__ import annotations

import difflib
from collections.abc import Sequence
from pathlib import Path


def near(word: str, choices: Sequence[str]) -> str:
    """`` (did you mean 'x'?)`` for the closest of ``choices`` to ``word``, else ``""``."""
    close = difflib.get_close_matches(word, list(choices), n=1, cutoff=0.6)
    return f" (did you mean {close[0]!r}?)" if close else ""


def check_protocol(name: str | Path) -> None:
    """A benchmark protocol must be a YAML path or a name in ``configs/protocols/``.

    Raises:
        FileNotFoundError: a YAML path that does not exist.
        ValueError: an unknown name, with the closest one and every choice.
    """
    from hsqbench.settings import PROTOCOL_DIR

    path = Path(name)
    if path.suffix in (".yaml", ".yml"):
        if not path.is_file():
            raise FileNotFoundError(f"protocol {name}: no such file")
        return
    known = sorted(p.stem for p in PROTOCOL_DIR.glob("*.yaml"))
    if str(name) not in known:
        raise ValueError(
            f"no protocol {str(name)!r}{near(str(name), known)}: give a name in "
            f"{PROTOCOL_DIR} ({', '.join(known)}) or a YAML path"
        )


def check_objects(names: Sequence[str]) -> None:
    """Every name must be an object of the library.

    Raises:
        ValueError: the first unknown name, with the closest object and every choice.
    """
    from hsqbench.assets.library import object_names

    known = object_names()
    for name in names:
        if name not in known:
            raise ValueError(
                f"unknown object {name!r}{near(name, known)}; `hsqbench assets list` shows "
                f"them all: {', '.join(known)}"
            )
