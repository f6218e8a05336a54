"""Memory of closed sessions given back: Panel's link registry, and the C heap (issue 29, item 4).

``deploy/smoke-test --probe`` found two things that kept a served process's memory after its
sessions had been discarded (docs/deploy.md, "Memory after sessions close"):

- **Panel's link registry**: each JavaScript callback of a widget (``jscallback``; the
  study view's two ``EditableRangeSlider`` register four, on their number fields) is kept in
  ``panel.links.Callback.registry``, a ``WeakKeyDictionary`` keyed on the widget whose value,
  the callback, refers to the widget again: the key never dies, and every session left its
  sliders, their parameters and watchers behind. :func:`release_links` removes a closed page's
  entries.
- **the C heap**: NumPy arrays of a run (tens of MB: the vehicle–track histories) are freed
  when a session closes, but glibc keeps the freed memory in its heaps (a server's RSS grew
  230 MB over four sessions that were gone; ``malloc_trim`` gave it back). :func:`release_memory`
  collects cycles and trims the heaps; :func:`release_soon` does it once after a burst of
  sessions closes, not once per session (a collection takes about 0.2 s of the event loop).

A later CI run found a third: after a burst the heaps still held 50–60 MB more than before it
now and then, pages pinned by objects scattered over where the burst's arrays had been;
``tunnelsettle serve`` therefore maps large blocks by themselves (:func:`map_large_blocks`).
"""

from __future__ import annotations

import ctypes
import ctypes.util
import gc
from collections.abc import Callable

RELEASE_DELAY_S = 2.0
"""Seconds after the last session closed before the memory is given back."""

LARGE_BLOCK_BYTES = 4 * 2**20
"""Blocks of this size or more get their own mapping in the server (:func:`map_large_blocks`).
Below it: a 2D soil run's spectra (1–4 MB), whose fresh mappings' page faults made that stage
15–30 % slower with a 1 MiB threshold."""

M_MMAP_THRESHOLD = -3
"""``mallopt`` parameter number of glibc's mapping threshold (``<malloc.h>``)."""

_libc: ctypes.CDLL | None = None
_pending: list = []


def release_links(root) -> int:
    """Remove the JavaScript callbacks and links of ``root`` and everything below it (Panel
    objects, :meth:`~panel.viewable.Viewable.select`) from Panel's registry; returns how many
    objects had entries."""
    from panel.links import Callback

    removed = 0
    for item in root.select():
        if Callback.registry.pop(item, None) is not None:
            removed += 1
    return removed


def glibc() -> ctypes.CDLL | None:
    """The C library if it is glibc (it has ``malloc_trim``), else None."""
    global _libc
    if _libc is None:
        name = ctypes.util.find_library("c")
        try:
            _libc = ctypes.CDLL(name)
            _libc.malloc_trim  # noqa: B018 - present in glibc only
        except (OSError, AttributeError, TypeError):
            _libc = False  # type: ignore[assignment]
    return _libc or None


def _malloc_trim() -> bool:
    """glibc's ``malloc_trim(0)``: freed heap memory back to the system (False elsewhere)."""
    libc = glibc()
    if libc is None:
        return False
    libc.malloc_trim(0)
    return True


def map_large_blocks(threshold_bytes: int = LARGE_BLOCK_BYTES) -> bool:
    """Every block of at least ``threshold_bytes`` in its own mapping, from now on (glibc's
    ``mallopt(M_MMAP_THRESHOLD, ...)``); returns whether it could be set (glibc only).

    glibc maps a large block by itself, but raises that threshold to the size of each such
    block freed (up to 32 MiB), so after a first run a run's arrays (4–30 MB: 181 of the 195
    MB of a paper-case run at 33 km/h) live in the heaps. A burst of sessions then spreads
    the heaps over gigabytes, and the objects made during it that live on (the stage cache
    refilled after it) are scattered over them: a trim cannot give back a page that holds
    any of them. With the threshold fixed, a freed array's mapping goes back at once and the
    heaps stay small.
    """
    libc = glibc()
    if libc is None:
        return False
    return bool(libc.mallopt(M_MMAP_THRESHOLD, threshold_bytes))


def release_memory() -> bool:
    """Collect reference cycles, then give freed heap memory back to the system. Returns
    whether the heap could be trimmed (glibc)."""
    gc.collect()
    return _malloc_trim()


def release_soon(call_later: Callable[[float, Callable[[], None]], object]) -> None:
    """:func:`release_memory` :data:`RELEASE_DELAY_S` after the last of a burst of calls.

    ``call_later(delay, callback)`` schedules on the server's event loop (e.g. Tornado's
    ``IOLoop.current().call_later``); calls while one release waits only push it back.
    """
    token = object()
    _pending[:] = [token]

    def release() -> None:
        if _pending == [token]:  # the newest request: nothing closed since
            _pending.clear()
            release_memory()

    call_later(RELEASE_DELAY_S, release)


def session_closed(close: Callable[[], None], session_context) -> None:
    """A served session was discarded: ``close()`` drops its memory, and once the sessions
    closing together are all gone the freed heap goes back to the system.

    Bound as ``partial(session_closed, close)``, it has the one argument (the session's
    context, unused) that Bokeh's ``on_session_destroyed`` requires.
    """
    from tornado.ioloop import IOLoop

    close()
    release_soon(IOLoop.current().call_later)
