"""Worker processes end with the process that started them, even when it is killed (SIGKILL,
the OOM killer), instead of running on as orphans holding gigabytes.

A ``ProcessPoolExecutor`` on the forkserver leaves three kinds of process behind a killed
parent: the workers (blocked on a queue whose other end they hold themselves), the fork server
(whose children hold it up) and the resource tracker (which waits for every one of them). Each
worker and the fork server get a daemon thread (:func:`exit_with`) that waits for the parent's
end on a pidfd (Linux >= 5.3; elsewhere it polls the pid twice a second) and then ends its own
process; the resource tracker then sees its last writer gone and exits by itself.

The workers call :func:`exit_with` as the pool's initializer. The fork server cannot be given
an initializer, but it imports its preload modules, this one among them
(:mod:`hsqbench.experiment.executor`): on import, a process whose parent is the pid in
:data:`PARENT_ENV` (set by the parent before the server starts) watches that parent.
"""

from __future__ import annotations

import os
import select
import threading
import time

#: The pid of the process that starts the pools; a child of it that imports this module watches it.
PARENT_ENV = "HSQBENCH_POOL_PARENT"
_POLL_S = 0.5
_watched: set[int] = set()  # the pids this process watches (its threads do not survive a fork)
if hasattr(os, "register_at_fork"):  # POSIX; elsewhere workers are spawned, not forked
    os.register_at_fork(after_in_child=_watched.clear)


def _alive(pid: int) -> bool:
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # alive, someone else's (a reused pid)
        return True
    return True


def exit_with(pid: int) -> None:
    """End this process (``os._exit``, no clean-up: its work is lost with the parent's) as soon
    as process ``pid`` ends; at once if it has already. Returns immediately; idempotent."""
    if pid in _watched or pid == os.getpid():
        return
    _watched.add(pid)
    try:
        fd: int | None = os.pidfd_open(pid)
    except ProcessLookupError:
        os._exit(1)
    except (AttributeError, OSError):  # not Linux, or a kernel before 5.3
        fd = None

    def wait() -> None:
        if fd is not None:
            select.select([fd], [], [])  # readable once the process has ended
        else:
            while _alive(pid):
                time.sleep(_POLL_S)
        os._exit(1)

    threading.Thread(target=wait, name=f"exit-with-{pid}", daemon=True).start()


def _watch_parent_if_asked() -> None:
    """In the fork server (or any child of the pool's parent that imports this module)."""
    parent = os.environ.get(PARENT_ENV)
    if parent is not None and parent == str(os.getppid()):
        exit_with(int(parent))


_watch_parent_if_asked()
