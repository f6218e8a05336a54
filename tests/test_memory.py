"""Memory of closed sessions given back (dashboard/memory.py; found by deploy/smoke-test --probe).

Before: every session left its study view's range sliders in Panel's link registry (a
WeakKeyDictionary whose values refer to their keys: four entries per session, with the widgets,
their parameters and watchers, for the life of the server), and the C heap kept the freed arrays
of closed sessions (the server's RSS grew 230 MB over four sessions that were gone).
"""

from __future__ import annotations

import gc
import os
import subprocess
import sys
import weakref
from functools import partial

import pytest
from bokeh.document import Document
from panel.links import Callback

from dashboard import memory
from dashboard.app import Dashboard
from model.params import Scenario
from model.pipeline import StageCache


def test_a_closed_dashboard_leaves_nothing_in_panels_link_registry():
    before = set(map(id, Callback.registry))
    board = Dashboard(scenario=Scenario.preset("single_bogie"), cache=StageCache())
    sliders = [weakref.ref(board.study.first_range), weakref.ref(board.study.second_range)]
    assert len(Callback.registry) > len(before)  # the range sliders' number fields
    board.close()
    assert set(map(id, Callback.registry)) <= before
    del board
    gc.collect()
    assert [ref() for ref in sliders] == [None, None]


def test_release_soon_trims_once_after_a_burst():
    scheduled = []
    calls = []
    real = memory.release_memory
    memory.release_memory = lambda: calls.append(1) or True
    try:
        for _ in range(3):  # three sessions discarded together
            memory.release_soon(lambda delay, callback: scheduled.append((delay, callback)))
        assert [delay for delay, _ in scheduled] == [memory.RELEASE_DELAY_S] * 3
        for _, callback in scheduled:
            callback()
    finally:
        memory.release_memory = real
    assert calls == [1]


def test_release_memory_trims_the_heap_on_glibc():
    assert memory.release_memory() in (True, False)  # False only without glibc


MAPPED_BYTES_AFTER_A_LARGE_FREE = """
import ctypes, sys
import numpy as np
from dashboard import memory

class MallInfo2(ctypes.Structure):
    _fields_ = [(name, ctypes.c_size_t) for name in (
        "arena", "ordblks", "smblks", "hblks", "hblkhd", "usmblks", "fsmblks", "uordblks",
        "fordblks", "keepcost")]

libc = memory.glibc()
libc.mallinfo2.restype = MallInfo2
if sys.argv[1] == "mapped":
    assert memory.map_large_blocks()
large = np.ones(16 * 2**20 // 8)
del large  # glibc raises its own threshold to a freed mapped block (up to 32 MiB)
before = libc.mallinfo2().hblkhd
array = np.ones(5 * 2**20 // 8)  # a run's typical history: 5 MiB
print(libc.mallinfo2().hblkhd - before)
"""


@pytest.mark.skipif(
    memory.glibc() is None or not hasattr(memory.glibc(), "mallinfo2"), reason="glibc only"
)
def test_large_blocks_keep_mappings_of_their_own_after_a_larger_one_was_freed():
    # glibc's own settings from the environment fix its threshold too (Dask's nanny writes
    # MALLOC_TRIM_THRESHOLD_ into the environment of the process that starts a cluster)
    environ = {
        name: value
        for name, value in os.environ.items()
        if not name.startswith("MALLOC_") and name != "GLIBC_TUNABLES"
    }

    def mapped_bytes(mode: str) -> int:
        done = subprocess.run(
            [sys.executable, "-c", MAPPED_BYTES_AFTER_A_LARGE_FREE, mode],
            capture_output=True, text=True, check=True, env=environ,
        )  # fmt: skip
        return int(done.stdout)

    assert mapped_bytes("glibc's default") == 0  # the 5 MiB array went into the heap
    assert mapped_bytes("mapped") >= 5 * 2**20


def test_session_closed_bound_to_a_close_is_accepted_by_bokeh_and_closes():
    closed = []
    callback = partial(memory.session_closed, lambda: closed.append(1))
    Document().on_session_destroyed(callback)  # Bokeh checks the signature: one argument
    scheduled = []
    real = memory.release_soon
    memory.release_soon = lambda call_later: scheduled.append(call_later)
    try:
        callback(None)
    finally:
        memory.release_soon = real
    assert closed == [1] and len(scheduled) == 1
