"""Freed memory kept in the process for reuse, where trials run.

glibc's malloc serves a large block (above a threshold that starts at 128 KiB and follows the
largest block freed, up to 32 MiB) with a fresh ``mmap`` and gives it back to the system when
freed, and trims the top of its heap as soon as 128 KiB there are free. A trial allocates and
frees such blocks all the time (a learned planner's activations reach tens of megabytes), so the
kernel maps, zero-fills and unmaps the same pages again and again: Contact-GraspNet spent 6.4 s
of system time beside 18 s of user time on eleven plans. With the threshold and the trim limit
at 1 GiB the blocks come from the heap and stay there for the next trial: 1.80 → 1.28 CPU s per
Contact-GraspNet plan, hsq and antipodal trials at 0.96 (the paper's objects), 0.94 (unseen
ones) and 0.98 (packed rounds) of their time, outcomes and grasps identical
(``docs/performance.md``). The process keeps the memory of its largest trial instead of giving
it back (under 1 GiB for Contact-GraspNet here).

Only the allocator's policy changes, never what is computed. Elsewhere than glibc (macOS, musl)
:func:`keep_freed_memory` does nothing.
"""

from __future__ import annotations

import ctypes
import ctypes.util
import functools

#: glibc's ``mallopt`` parameters (malloc.h).
_M_TRIM_THRESHOLD = -1
_M_MMAP_THRESHOLD = -3
#: Blocks below this come from the heap, and this much free at its top is kept (bytes).
KEEP_BYTES = 1 << 30


@functools.cache
def keep_freed_memory() -> bool:
    """Set this process's malloc to keep freed memory for reuse (once; module doc). True when
    the C library took both settings."""
    name = ctypes.util.find_library("c")
    try:
        mallopt = ctypes.CDLL(name).mallopt if name else None
    except (OSError, AttributeError):
        mallopt = None
    if mallopt is None:
        return False
    mallopt.argtypes = (ctypes.c_int, ctypes.c_int)
    took_mmap = mallopt(_M_MMAP_THRESHOLD, KEEP_BYTES) == 1
    took_trim = mallopt(_M_TRIM_THRESHOLD, KEEP_BYTES) == 1
    return took_mmap and took_trim
