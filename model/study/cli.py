"""``python -m model study``: a study from the command line, written to a folder."""

from __future__ import annotations

import argparse
import json
import math
import sys
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from model.outputs import check_output_folder, replacing_folder
from model.study.definition import (
    MAX_RUNS_UNCONFIRMED,
    SAMPLINGS,
    Study,
    check_run_count,
    define_study,
)
from model.study.execution import SCHEDULER_ENV, execute_study, study_table
from model.study.tables import STUDY_FILES, load_study, save_study

JOURNAL_FILE = "runs.partial.jsonl"
"""Finished runs, one JSON line each, while a study runs (in the folder being assembled)."""


# ---- command line --------------------------------------------------------------------------
def parse_values(spec: str) -> list[str] | tuple[str, str] | None:
    """Grid text of ``--vary``: ``a,b,c`` → values; ``start:stop:step`` → the inclusive range;
    ``low:high`` → a sampling range; empty → None (softbounds)."""
    if not spec.strip():
        return None
    if ":" not in spec:
        return [part.strip() for part in spec.split(",")]
    parts = [part.strip() for part in spec.split(":")]
    if len(parts) == 2:
        return parts[0], parts[1]
    start, step, count = _grid_range(spec)
    # rounded to 12 significant digits so 0.1-type steps give 0.3, not 0.30000000000000004
    return [f"{start + i * step:.12g}" for i in range(count)]


def grid_count(spec: str) -> int:
    """Number of values of a ``--vary`` grid text, found without building them (1 for a
    sampling range or nothing: it counts no points)."""
    if ":" not in spec:
        return len(spec.split(",")) if spec.strip() else 1
    return _grid_range(spec)[2] if spec.count(":") == 2 else 1


def _grid_range(spec: str) -> tuple[float, float, int]:
    """(start, step, number of values) of a ``start:stop:step`` text."""
    parts = [part.strip() for part in spec.split(":")]
    if len(parts) != 3:
        raise ValueError(f"{spec!r} is not start:stop:step, low:high or a,b,c")
    try:
        start, stop, step = (float(part) for part in parts)
    except ValueError:
        raise ValueError(f"{spec!r}: start:stop:step must be numbers") from None
    if not step > 0:
        raise ValueError(f"{spec!r}: the step must be > 0")
    if not (math.isfinite(start) and math.isfinite(stop)):
        raise ValueError(f"{spec!r}: start and stop must be finite numbers")
    count = math.floor((stop - start) / step * (1 + 1e-12) + 1e-9) + 1
    if count < 1:
        raise ValueError(f"{spec!r}: stop is below start, the grid is empty")
    return start, step, count


def build_parser(prog: str = "python -m model study") -> argparse.ArgumentParser:
    """Argument parser of ``python -m model study``."""
    from model.cli import add_output_arguments, add_scenario_arguments

    parser = argparse.ArgumentParser(
        prog=prog,
        description="Parameter sweeps and Monte-Carlo bands on Dask distributed.",
    )
    add_scenario_arguments(parser)
    parser.add_argument(
        "--vary",
        action="append",
        default=[],
        metavar="SECTION.PARAM=SPEC",
        help="grid: start:stop:step (inclusive) or a,b,c; random/lhs: low:high or nothing "
        "(the parameter's softbounds). Repeatable.",
    )
    parser.add_argument("--sampling", choices=SAMPLINGS, default="grid")
    parser.add_argument("--samples", type=int, help="number of random / lhs points")
    parser.add_argument("--sampling-seed", type=int, default=0, help="seed of the random points")
    parser.add_argument(
        "--seeds",
        default="1",
        help="irregularity seeds: a count N (the base seed and the N-1 after it) or a,b,c",
    )
    parser.add_argument("--depth-profile", action="store_true", help="keep every depth's peak")
    parser.add_argument("--study", type=Path, help="re-run a study.json (ignores the above)")
    add_output_arguments(parser)
    add_cluster_arguments(parser)
    parser.add_argument(
        "--yes", action="store_true", help=f"allow more than {MAX_RUNS_UNCONFIRMED} runs"
    )
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    return parser


def add_cluster_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--scheduler`` and ``--workers`` (where a study's or a band's runs go)."""
    parser.add_argument(
        "--scheduler",
        help=f"existing Dask scheduler tcp://host:port (default ${SCHEDULER_ENV}, else a "
        "LocalCluster with one single-threaded worker per core)",
    )
    parser.add_argument("--workers", type=int, help="LocalCluster workers (default: cores)")


def parse_seeds(text: str, base_seed: int) -> list[int]:
    """``N`` → N seeds from the base scenario's; ``a,b,c`` → those seeds."""
    try:
        if "," in text:
            return [int(part) for part in text.split(",")]
        count = int(text)
    except ValueError:
        raise ValueError(f"--seeds {text!r} is not a count or a list of whole numbers") from None
    if count < 1:
        raise ValueError(f"--seeds {count} must be at least 1")
    check_run_count(count, confirm=True)  # the seeds alone already too many: before the list
    return list(range(base_seed, base_seed + count))


def study_from_args(args: argparse.Namespace) -> Study:
    """The :class:`Study` described by the command line."""
    from model.cli import load_scenario

    if args.study:
        return load_study(args.study)
    base = load_scenario(args)
    seeds = parse_seeds(args.seeds, base.irregularity.seed)
    if args.sampling == "grid":  # the size from the value counts, before any value is built
        counts = [grid_count(item.partition("=")[2]) for item in args.vary]
        check_run_count(math.prod(counts) * len(seeds), args.yes)
    vary: dict[str, Any] = {}
    for item in args.vary:
        path, sep, spec = item.partition("=")
        path = path.strip()
        if not sep and args.sampling == "grid":
            raise ValueError(f"--vary {item!r} must be of the form section.parameter=values")
        if path in vary:
            raise ValueError(f"--vary {path} is given twice")
        values = parse_values(spec)
        if args.sampling == "grid" and not isinstance(values, list):
            raise ValueError(f"--vary {item!r}: a grid needs a,b,c or start:stop:step")
        if args.sampling != "grid" and isinstance(values, list):
            raise ValueError(f"--vary {item!r}: {args.sampling} sampling needs low:high or nothing")
        vary[path] = values
    return define_study(
        base,
        vary,
        seeds=seeds,
        sampling=args.sampling,
        n_samples=args.samples,
        sampling_seed=args.sampling_seed,
        depth_profile=args.depth_profile,
        confirm=args.yes,
    )


def main(argv: Sequence[str] | None = None, prog: str = "python -m model study") -> int:
    """``python -m model study``: returns the exit code (2 bad input, 130 cancelled)."""
    from model.cli import TerminalProgress

    class StudyProgress(TerminalProgress):
        """Runs done out of all, on the command line's progress bar."""

        failed = 0

        def __call__(self, done: int, total: int, row: dict) -> None:
            self.failed += bool(row.get("error"))
            filled = round(done / total * self.width)
            bar = "#" * filled + "-" * (self.width - filled)
            failed = f", {self.failed} failed" if self.failed else ""
            self.stream.write(f"\r[{bar}] {done}/{total} runs{failed}")
            self.stream.flush()
            self.shown = True

    parser = build_parser(prog)
    args = parser.parse_args(None if argv is None else list(argv))
    progress = None if args.quiet else StudyProgress()
    try:
        study = study_from_args(args)
        check_output_folder(args.out, args.force)  # before any run
        with replacing_folder(args.out) as folder:
            table = _run_and_save(study, args, progress, folder)
    except (ValueError, KeyError, OSError) as error:
        message = error.args[0] if isinstance(error, KeyError) and error.args else error
        parser.exit(2, f"error: {message}\n")
    finally:
        if progress is not None:
            progress.close()
    paths = [args.out / name for name in STUDY_FILES]
    cancelled = table.attrs["cancelled"]
    if not args.quiet:
        failed = int((table["error"] != "").sum()) if "error" in table else 0
        state = "cancelled after" if cancelled else "done:"
        print(
            f"study {state} {len(table)} of {study.n_runs} runs ({failed} failed); "
            f"{', '.join(str(p) for p in paths)}",
            file=sys.stderr if cancelled else sys.stdout,
        )
    return 130 if cancelled else 0


def _run_and_save(study: Study, args: argparse.Namespace, progress, folder: Path):
    """Run the study, each finished run appended to ``runs.partial.jsonl`` in ``folder`` as it
    comes back, then save the study there (a second Ctrl-C saves the runs finished so far, as
    a cancelled study); the table."""
    rows: dict[int, dict] = {}
    journal = folder / JOURNAL_FILE
    with journal.open("a", encoding="utf-8") as file:

        def record(run: int, row: dict) -> None:
            rows[run] = row
            file.write(json.dumps({"run": run, **row}) + "\n")
            file.flush()

        try:
            table = execute_study(
                study,
                args.scheduler,
                progress=progress,
                confirm=args.yes,
                n_workers=args.workers,
                record=record,
            )
        except KeyboardInterrupt:  # the second Ctrl-C, while the cancelled runs were stopping
            table = study_table(study, rows, cancelled=True)
    save_study(table, folder)
    journal.unlink()
    return table
