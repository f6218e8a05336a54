"""Sizes the server accepts from a user, in one place (issue 29, item 3).

The limits bound the memory and parse time one upload can take on a shared server; they are
operating choices, not physics.
"""

from __future__ import annotations

MEGABYTE = 1_000_000
SESSION_JSON_BYTES = 2 * MEGABYTE  # a what-if session or a scenario file
PROFILE_CSV_BYTES = 12 * MEGABYTE  # a measured track-irregularity profile
BOREHOLE_CSV_BYTES = 3 * MEGABYTE  # a borehole log's layer table
TRIAXIAL_CSV_BYTES = 3 * MEGABYTE  # a cyclic triaxial test's records


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
