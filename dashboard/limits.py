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
