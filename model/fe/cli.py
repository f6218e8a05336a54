"""``python -m model fe``: the FE section from the command line, written to a folder."""

from __future__ import annotations

import argparse
import json
import math
import sys
from pathlib import Path

from model.fe.analysis import SECTION_ENGINES, SOIL_LAWS, run_fe
from model.fe.build import FEConvergenceError, FEUnavailableError
from model.fe.mesh import ELEMENT_SIZE_ALLOWED, FEMesh
from model.fe.store import FEResult, save_fe_result
from model.outputs import write_csv_table, write_text_atomic

# ---- command line -----------------------------------------------------------------------------
FE_STAGES = ("load", "gravity", "dynamic")


def _positive_length(text: str) -> float:
    """A length > 0 m from the command line; refused in argparse's "argument --x: ..." line."""
    try:
        value = float(text)
    except ValueError:
        value = math.nan
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text!r} is not a length > 0 m")
    return value


def _element_size(text: str) -> float:
    """``--element-size``: a length > 0 m; omitting it takes the size from the load band."""
    try:
        return _positive_length(text)
    except argparse.ArgumentTypeError:
        raise argparse.ArgumentTypeError(
            f"{text!r} must be {ELEMENT_SIZE_ALLOWED.replace('or None', 'or omitted')}"
        ) from None


def build_parser(prog: str = "python -m model fe") -> argparse.ArgumentParser:
    """Argument parser of ``python -m model fe``."""
    from model.cli import add_scenario_arguments

    parser = argparse.ArgumentParser(
        prog=prog,
        description="Run the plane-strain FE section (docs/model.md §12) and store its depth "
        "profile of peak and permanent displacement.",
    )
    add_scenario_arguments(parser)
    parser.add_argument("--law", choices=SOIL_LAWS, default="mohr_coulomb", help="soil law")
    parser.add_argument("--passages", type=int, default=1, help="passages in a row (default 1)")
    parser.add_argument(
        "--outer-radius",
        type=_positive_length,
        default=FEMesh.outer_radius,
        help="boundary radius R (m)",
    )
    parser.add_argument(
        "--element-size",
        type=_element_size,
        default=None,
        help="largest element edge (m); default: the size that resolves the load band",
    )
    parser.add_argument(
        "--engine",
        choices=tuple(SECTION_ENGINES),
        default="native",
        help="who solves the section: this package (default) or OpenSeesPy (the 'fe' extra); "
        "the same model, results within ~1e-7 of the peak",
    )
    parser.add_argument("--out", type=Path, required=True, help="output folder (created)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    return parser


def write_fe_outputs(result: FEResult, out: Path) -> list[Path]:
    """Stored result (npz, keyed by the scenario), depth-profile CSV and summary JSON."""
    stored = save_fe_result(result, out)
    columns = {"depth_m": result.depth_m, "peak_disp_m": result.peak_disp_m}
    for p, row in enumerate(result.residual_per_passage_m, start=1):
        columns[f"residual_after_passage_{p}_m"] = row
    profile = write_csv_table(out / f"fe_depth_profile_{result.soil_law}.csv", columns)
    content = {
        "soil_law": result.soil_law,
        "passages": result.passages,
        "peak_disp_invert_m": float(result.peak_disp_m[0]),
        "residual_disp_invert_m": float(result.residual_disp_m[0]),
        "mesh": result.mesh,
        "timings_s": result.timings_s,
    }
    summary = write_text_atomic(
        out / f"fe_summary_{result.soil_law}.json", json.dumps(content, indent=2) + "\n"
    )
    return [stored, profile, summary]


def main(argv: list[str] | None = None, prog: str = "python -m model fe") -> int:
    """``python -m model fe``: returns the exit code (2 for bad input or an unavailable FE)."""
    from model.cli import TerminalProgress, load_scenario
    from model.pipeline import SimulationError

    parser = build_parser(prog)
    args = parser.parse_args(argv)
    try:
        scenario = load_scenario(args)
        mesh = FEMesh(outer_radius=args.outer_radius, element_size=args.element_size)
        progress = None if args.quiet else TerminalProgress(stages=FE_STAGES)

        def announce(hint: str) -> None:
            if progress is not None:
                progress.close()  # the hint on a line of its own; the bar resumes below it
                progress.shown = False
                print(hint, file=sys.stderr)

        try:
            result = run_fe(
                scenario,
                args.law,
                args.passages,
                mesh,
                progress=progress,
                announce=announce,
                engine=args.engine,
            )
        finally:
            if progress is not None:
                progress.close()
    except (
        ValueError,
        KeyError,
        OSError,
        FEUnavailableError,
        FEConvergenceError,
        SimulationError,
    ) as error:
        message = error.args[0] if isinstance(error, KeyError) and error.args else error
        parser.exit(2, f"error: {message}\n")
    paths = write_fe_outputs(result, args.out)
    if not args.quiet:
        residual = ", ".join(f"{r * 1e3:.3f}" for r in result.residual_per_passage_m[:, 0])
        print(
            f"{result.soil_law}: peak displacement at the invert "
            f"{result.peak_disp_m[0] * 1e3:.2f} mm, permanent after each passage {residual} mm; "
            f"{result.mesh['n_elements']} elements, {sum(result.timings_s.values()):.0f} s; "
            f"{len(paths)} files in {args.out}"
        )
    return 0
