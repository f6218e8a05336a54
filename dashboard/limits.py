"""Sizes the server accepts from a user, in one place (issue 29, item 3).

The limits bound the memory and parse time one upload can take on a shared server; they are
operating choices, not physics.
"""

from __future__ import annotations

import os
import threading
from collections.abc import Callable

from model.run_cost import estimate_run
from model.study.execution import SCHEDULER_ENV

MEGABYTE = 1_000_000
SESSION_JSON_BYTES = 2 * MEGABYTE  # a what-if session or a scenario file
PROFILE_CSV_BYTES = 12 * MEGABYTE  # a measured track-irregularity profile
BOREHOLE_CSV_BYTES = 3 * MEGABYTE  # a borehole log's layer table
TRIAXIAL_CSV_BYTES = 3 * MEGABYTE  # a cyclic triaxial test's records
SERVED_RUN_SECONDS = 180.0
"""Longest run the dashboard computes for a session, as :func:`model.run_cost.estimate_run`
puts it: a longer one would hold one of the server's few workers for minutes (the paper case
takes about half a second; the command line computes any run)."""
LOCAL_CLUSTERS = 1
"""Studies and settlement bands computing at once on a LocalCluster of their own, per server
process: each starts a worker process per core, so a second one would only share the cores and
add its memory. A shared Dask scheduler (``$TUNNELSETTLE_SCHEDULER``) is not limited here."""
_local_clusters = threading.BoundedSemaphore(LOCAL_CLUSTERS)


def refuse_oversized(data: bytes | str, what: str, limit_bytes: int) -> None:
    """Refuse ``data`` (an uploaded file) when it is larger than ``limit_bytes``.

    Decoded text is measured in characters (one byte each for the ASCII of a CSV file).

    Raises
    ------
    ValueError
        Naming ``what``, its size and the limit.
    """
    size = len(data)
    if size > limit_bytes:
        raise ValueError(
            f"{what} is {size / MEGABYTE:.1f} MB; the server accepts at most "
            f"{limit_bytes / MEGABYTE:.1f} MB"
        )


def whole_number_input(widget) -> int:
    """The value of a whole-number input (``pn.widgets.IntInput``), checked on the server.

    The browser keeps a typed value within the input's ``start`` and ``end``; a message sent to
    the server's websocket by other means need not, and a grid or a list of seeds of that size
    would take the server's memory and time.

    Raises
    ------
    ValueError
        An empty input, or a value outside ``start``–``end``, naming the input's label, the
        value and the allowed range.
    """
    value, low, high = widget.value, widget.start, widget.end
    if value is None:
        raise ValueError(f"{widget.label} is empty: give a whole number from {low} to {high}")
    if not low <= value <= high:
        raise ValueError(f"{widget.label} = {value} is outside the allowed range [{low}, {high}]")
    return int(value)


def reserve_local_cluster(scheduler) -> Callable[[], None]:
    """Take one of the server's :data:`LOCAL_CLUSTERS` for a study or band that would start a
    LocalCluster of its own (``scheduler`` None and no ``$TUNNELSETTLE_SCHEDULER``).

    Returns
    -------
    callable
        Gives the cluster back; call it once the study or band has ended (it does nothing for
        one on a shared scheduler).

    Raises
    ------
    ValueError
        Every local cluster is taken, saying when to start again and what lifts the limit.
    """
    if scheduler is not None or os.environ.get(SCHEDULER_ENV):
        return lambda: None
    if not _local_clusters.acquire(blocking=False):
        raise ValueError(
            f"this server computes at most {LOCAL_CLUSTERS} study or settlement band at a time "
            "on its own cores, and one is computing: start again when it has finished (a "
            f"shared Dask scheduler, ${SCHEDULER_ENV}, lifts the limit)"
        )
    return _local_clusters.release


def refuse_long_run(scenario) -> None:
    """Refuse a run the server would compute for longer than :data:`SERVED_RUN_SECONDS`.

    Raises
    ------
    ValueError
        Naming the estimate, the stage and parameters that drive it, the bound, and the
        command line that computes the run anyway.
    """
    estimate = estimate_run(scenario)
    if estimate.total_seconds > SERVED_RUN_SECONDS:
        raise ValueError(
            f"{estimate.slow_message()}; the dashboard computes runs of at most "
            f"{SERVED_RUN_SECONDS:.0f} s: change those inputs, or compute it with "
            "tunnelsettle run on your own machine"
        )
