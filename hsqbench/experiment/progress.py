"""Progress of a run: a live bar on a terminal, plain periodic lines in a log file.

A carriage-return bar written to a file (``make benchmark > log``, CI) becomes one line per
trial; so when the stream is not a terminal, one plain line is written every
``every_trials`` trials or ``every_s`` seconds (whichever comes first, checked as trials
finish), and a last one at the end, each with the running GSR per planner and the ETA.
"""

from __future__ import annotations

import sys
import time
from collections.abc import Iterable
from typing import TextIO

from hsqbench.experiment.results import STATUS_ERROR, STATUS_OK

# A paper run (495 trials, ~10 min on 2 cores) logs about 20 lines at these settings.
EVERY_TRIALS = 25
EVERY_S = 30.0


class Tally:
    """Running GSR per planner (status ``ok`` attempts only) and the error count."""

    def __init__(self) -> None:
        self.success: dict[str, int] = {}
        self.attempts: dict[str, int] = {}
        self.errors = 0

    def add(self, rows: Iterable[dict[str, str]]) -> None:
        for row in rows:
            if row["status"] == STATUS_ERROR:
                self.errors += 1
            elif row["status"] == STATUS_OK:
                p = row["planner"]
                self.attempts[p] = self.attempts.get(p, 0) + 1
                self.success[p] = self.success.get(p, 0) + (row["success"] == "1")

    def postfix(self) -> dict[str, str]:
        out = {f"gsr[{p}]": f"{self.success[p] / n:.2f}" for p, n in self.attempts.items()}
        if self.errors:
            out["errors"] = str(self.errors)
        return out


def format_duration(seconds: float) -> str:
    """``1h02m``, ``4m05s`` or ``12s``."""
    s = max(0, round(seconds))
    if s >= 3600:
        return f"{s // 3600}h{s % 3600 // 60:02d}m"
    if s >= 60:
        return f"{s // 60}m{s % 60:02d}s"
    return f"{s}s"


class RunProgress:
    """Shows ``done/total`` trials with the tally: tqdm on a terminal, plain lines otherwise.

    ``total`` counts every selected trial, ``initial`` those already done before this session
    (a resume); the ETA is the remaining trials at this session's own rate.
    """

    def __init__(
        self,
        label: str,
        total: int,
        initial: int,
        tally: Tally,
        stream: TextIO | None = None,
        every_trials: int = EVERY_TRIALS,
        every_s: float = EVERY_S,
        clock=time.monotonic,
    ) -> None:
        self.label, self.total, self.initial, self.tally = label, total, initial, tally
        self.stream = stream if stream is not None else sys.stderr
        self.every_trials, self.every_s, self.clock = every_trials, every_s, clock
        self.done = initial
        self.start = self.last_time = clock()
        self.last_done = initial
        self.bar = None
        if _is_terminal(self.stream):
            from tqdm import tqdm

            self.bar = tqdm(
                total=total,
                initial=initial,
                desc=label,
                unit="trial",
                dynamic_ncols=True,
                file=self.stream,
            )
            self.bar.set_postfix(tally.postfix())
        else:
            self._line(self.start)

    def update(self) -> None:
        """One more trial finished (its rows already added to the tally)."""
        self.done += 1
        if self.bar is not None:
            self.bar.set_postfix(self.tally.postfix(), refresh=False)
            self.bar.update(1)
            return
        now = self.clock()
        if self.done - self.last_done >= self.every_trials or now - self.last_time >= self.every_s:
            self._line(now)

    def line(self) -> str:
        """The plain progress line for the current state."""
        now = self.clock()
        ran = self.done - self.initial
        elapsed = now - self.start
        remaining = self.total - self.done
        pct = 100.0 * self.done / self.total if self.total else 100.0
        parts = [f"{self.label}: {self.done}/{self.total} trials ({pct:.0f} %)"]
        gsr = [
            f"{p} {self.tally.success[p] / n:.1%} ({self.tally.success[p]}/{n})"
            for p, n in self.tally.attempts.items()
        ]
        if gsr:
            parts.append("GSR " + ", ".join(gsr))
        if self.tally.errors:
            parts.append(f"{self.tally.errors} errors")
        parts.append(f"elapsed {format_duration(elapsed)}")
        if remaining == 0:
            parts.append("done")
        elif ran:
            parts.append(f"ETA {format_duration(elapsed / ran * remaining)}")
        else:
            parts.append("ETA unknown")
        return "; ".join(parts)

    def _line(self, now: float) -> None:
        print(self.line(), file=self.stream, flush=True)
        self.last_time, self.last_done = now, self.done

    def close(self) -> None:
        if self.bar is not None:
            self.bar.close()
        elif self.done != self.last_done:
            self._line(self.clock())


def _is_terminal(stream: TextIO) -> bool:
    try:
        return stream.isatty()
    except (AttributeError, ValueError):
        return False
