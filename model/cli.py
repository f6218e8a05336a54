"""Command line (``python -m model``): run a scenario and write its results as CSV and JSON.

Examples::

    python -m model --preset paper --out results --set train.speed_kmh=60
    python -m model study --preset paper --vary train.speed_kmh=40:80:5 --seeds 20 --out study
    python -m model fe --preset paper --law mohr_coulomb --passages 3 --out fe

The first word picks a subcommand of :data:`model.commands.MODEL_SUBCOMMANDS` (``study``:
parameter sweeps and Monte-Carlo bands on Dask, ``fe``: the OpenSeesPy section check, ``band``:
the Monte-Carlo band of the long-term settlement); without one, a single run is made. The
``tunnelsettle`` console script (``dashboard.console``) offers the same subcommands, the run as
``run``, and the dashboard's.
"""

from __future__ import annotations

import argparse
import json
import sys
import time
import warnings
from pathlib import Path

from model.commands import MODEL_SUBCOMMANDS, subcommand_help
from model.longterm.statements import OUTSIDE_LAW_RANGE, SETTLEMENT_COVERS
from model.outputs import (
    check_output_folder,
    replacing_folder,
    write_csv_table,
    write_text_atomic,
)
from model.params import Scenario
from model.params.borehole import load_borehole_csv
from model.pipeline import STAGES, Results, SimulationError, run
from model.run_cost import SLOW_RUN_SECONDS, SlowRunWarning, estimate_run
from model.scenarios import SAMPLE, SAMPLE_SCENARIO_FILE, named_file
from model.soil.response import COMPARISON_DEPTH_M

PROGRESS_AFTER_S = 1.0  # show the bar only for runs that take longer than this


def add_scenario_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--preset`` / ``--scenario``, the repeatable ``--set`` and ``--borehole`` (read by
    load_scenario)."""
    source = parser.add_mutually_exclusive_group()
    source.add_argument(
        "--preset",
        default="paper",
        choices=Scenario.preset_names(),
        help="named scenario from model/data/presets.json (default: paper)",
    )
    source.add_argument(
        "--scenario",
        type=Path,
        help=f"scenario JSON file written by a run or the dashboard, or '{SAMPLE}' for the "
        "shipped sample (the single bogie on a measured rail profile)",
    )
    parser.add_argument(
        "--set",
        dest="overrides",
        action="append",
        default=[],
        metavar="SECTION.PARAM=VALUE",
        help="override one parameter, e.g. train.speed_kmh=60 (repeatable)",
    )
    parser.add_argument(
        "--borehole",
        type=Path,
        help="site layers from a borehole CSV (one row a layer, the header names the columns "
        "and units: model.params.borehole)",
    )


def add_output_arguments(parser: argparse.ArgumentParser) -> None:
    """Add ``--out`` (a folder, new or empty) and ``--force`` (replace it): checked with
    :func:`model.outputs.check_output_folder` before any computation, written through
    :func:`model.outputs.replacing_folder`."""
    parser.add_argument(
        "--out",
        type=Path,
        required=True,
        help="output folder (created; new or empty unless --force)",
    )
    parser.add_argument(
        "--force",
        action="store_true",
        help="replace --out even if it holds files (once the new results are complete)",
    )


def build_parser(
    prog: str = "python -m model", with_subcommands: bool = False
) -> argparse.ArgumentParser:
    """Argument parser of a single run (``tunnelsettle run``; with the list of subcommands in
    its help for ``python -m model``, whose first word may be one)."""
    parser = argparse.ArgumentParser(
        prog=prog,
        description="Run the vehicle–track–tunnel–soil model on one scenario and write its "
        "results (CSV and JSON)."
        + (" Without a subcommand, the options below make this single run." * with_subcommands),
        epilog=subcommand_help(MODEL_SUBCOMMANDS, prog) if with_subcommands else None,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    add_scenario_arguments(parser)
    add_output_arguments(parser)
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    return parser


def load_scenario(args: argparse.Namespace) -> Scenario:
    """Scenario from the preset or file, with the borehole's layers and the ``--set``
    overrides applied."""
    if args.scenario:
        scenario = Scenario.from_file(named_file(args.scenario, SAMPLE_SCENARIO_FILE))
    else:
        scenario = Scenario.preset(args.preset)
    if args.borehole:
        scenario.site.layers = load_borehole_csv(args.borehole)
    for item in args.overrides:
        path, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"--set {item!r} must be of the form section.parameter=value")
        scenario.set_value(path.strip(), value.strip())
    return scenario


class TerminalProgress:
    """Text progress bar on stderr, shown once a run has lasted ``PROGRESS_AFTER_S``; ``stages``
    are the stage names reported, in order (default: the pipeline's)."""

    def __init__(self, stream=sys.stderr, width: int = 30, stages: tuple[str, ...] = STAGES):
        self.stream, self.width, self.stages = stream, width, stages
        self.start = time.perf_counter()
        self.shown = False

    def __call__(self, stage: str, fraction: float) -> None:
        if time.perf_counter() - self.start < PROGRESS_AFTER_S:
            return
        overall = (self.stages.index(stage) + fraction) / len(self.stages)
        filled = round(overall * self.width)
        bar = "#" * filled + "-" * (self.width - filled)
        self.stream.write(f"\r[{bar}] {overall:4.0%} {stage:<14}")
        self.stream.flush()
        self.shown = True

    def close(self) -> None:
        """End the bar's line."""
        if self.shown:
            self.stream.write("\n")


def write_results(results: Results, out: Path) -> list[Path]:
    """Write time histories, spectra, the depth profile, the long-term settlement against time and
    per depth, the pore pressures against time at each depth, and (half-space ground) the
    ground-surface levels and peaks (CSV), scenario and summary (JSON); each file written whole
    (:func:`model.outputs.write_atomic`)."""
    out.mkdir(parents=True, exist_ok=True)
    vt, load, soil, lt = results.vehicle_track, results.load, results.soil, results.longterm
    tables = {
        "time_histories.csv": {
            "t_s": vt.t_s,
            "block_force_N": vt.block_force_N,
            "block_disp_m": vt.block_disp_m,
            "rail_disp_m": vt.rail_disp_m,
            "winkler_block_disp_m": vt.winkler_block_disp_m,
            "line_load_N_per_m": load.line_load_N_per_m,
        },
        "wheel_forces.csv": {
            "t_s": vt.t_s,
            **{f"wheel_{i + 1}_N": force for i, force in enumerate(vt.wheel_force_N)},
        },
        "load_psd.csv": {"f_hz": load.f_hz, "psd_N2_per_m2_per_hz": load.psd},
        "interface_psd.csv": {"f_hz": soil.f_hz, "psd_m2_per_hz": soil.interface_psd},
        "depth_profile.csv": {"depth_m": soil.depth_m, "peak_disp_m": soil.peak_disp_m},
        "soil_time_histories.csv": {
            "t_s": soil.t_s,
            **{f"disp_{d:g}m_m": row for d, row in zip(soil.depth_m, soil.disp_m, strict=True)},
        },
        "longterm_settlement.csv": {
            "years": lt.years,
            "settlement_m": lt.settlement_m,
            "plastic_settlement_m": lt.plastic_settlement_m,
            "consolidation_settlement_m": lt.consolidation_settlement_m,
        },
        "longterm_depth.csv": {
            "depth_m": lt.depth_m,
            "depth_below_ground_m": lt.depth_below_ground_m,
            "layer_index": lt.layer_index,
            "deviator_Pa": lt.deviator_Pa,
            "strength_Pa": lt.strength_Pa,
            "stress_ratio": lt.stress_ratio,
            "static_deviator_Pa": lt.static_deviator_Pa,
            "vertical_effective_stress_Pa": lt.vertical_effective_stress_Pa,
            "cycles_per_train": lt.cycles_per_train,
            "n_cycles": lt.n_cycles,
            "strain_percent": lt.strain_percent,
            "consolidation_strain_percent": lt.consolidation_strain_percent,
            "compressibility_per_Pa": lt.compressibility_per_Pa,
            "hydraulic_conductivity_m_per_s": lt.hydraulic_conductivity_m_per_s,
            "consolidation_coefficient_m2_per_s": lt.consolidation_coefficient_m2_per_s,
            "generated_pore_pressure_Pa": lt.generated_pore_pressure_Pa[-1],
            "excess_pore_pressure_Pa": lt.excess_pore_pressure_Pa[-1],
        },
        **{
            f"longterm_{name}.csv": {
                "years": lt.years,
                **{
                    f"{name}_{d:g}m_Pa": column
                    for d, column in zip(lt.depth_m, values.T, strict=True)
                },
            }
            for name, values in (
                ("generated_pore_pressure", lt.generated_pore_pressure_Pa),
                ("excess_pore_pressure", lt.excess_pore_pressure_Pa),
            )
        },
    }
    ground = results.ground
    if ground is not None:  # the half-space model's ground surface (docs/halfspace.md)
        tables["ground_levels.csv"] = {
            "band_centre_hz": ground.band_centre_hz,
            "band_nominal_hz": ground.band_nominal_hz,
            **{
                f"level_{d:g}m_dB": level
                for d, level in zip(ground.distance_m, ground.velocity_level_dB.T, strict=True)
            },
        }
        tables["ground_profile.csv"] = {
            "distance_m": ground.distance_m,
            "overall_level_dB": ground.overall_level_dB,
            "peak_velocity_m_per_s": ground.peak_velocity_m_per_s,
            "peak_disp_m": ground.peak_disp_m,
        }
    written = []
    for name, columns in tables.items():
        written.append(write_csv_table(out / name, columns))
    scenario_path = write_text_atomic(out / "scenario.json", results.scenario_json + "\n")
    summary = {
        "summary": results.summary(),
        "settlement_covers": SETTLEMENT_COVERS,
        "longterm_law": lt.statement,
        "longterm_pore_pressure": lt.pore_pressure_statement,
        "warnings": results.warnings,
        "stage_seconds": results.stage_seconds,
    }
    summary_path = write_text_atomic(out / "summary.json", json.dumps(summary, indent=2) + "\n")
    return [*written, scenario_path, summary_path]


def main(argv: list[str] | None = None) -> int:
    """``python -m model``: a subcommand, or a single run; returns the exit code."""
    argv = sys.argv[1:] if argv is None else list(argv)
    if argv and argv[0] in MODEL_SUBCOMMANDS:
        return MODEL_SUBCOMMANDS[argv[0]].run(argv[1:], prog=f"python -m model {argv[0]}")
    return run_main(argv, with_subcommands=True)


def run_main(
    argv: list[str] | None = None, prog: str = "python -m model", with_subcommands: bool = False
) -> int:
    """A single run from the command line; returns the exit code (2 for bad input)."""
    parser = build_parser(prog, with_subcommands)
    args = parser.parse_args(argv)
    try:
        scenario = load_scenario(args)
        scenario.validate()
        estimate = estimate_run(scenario)
        check_output_folder(args.out, args.force)
        if estimate.total_seconds > SLOW_RUN_SECONDS and not args.quiet:
            print(f"warning: {estimate.slow_message()}", file=sys.stderr)
        progress = None if args.quiet else TerminalProgress()
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore", SlowRunWarning)  # told above
                results = run(scenario, progress=progress, cache=None)
        finally:
            if progress is not None:
                progress.close()
    except (ValueError, KeyError, OSError, SimulationError) as error:
        message = error.args[0] if isinstance(error, KeyError) and error.args else error
        parser.exit(2, f"error: {message}\n")
    with replacing_folder(args.out) as folder:  # an interrupted --force keeps the old folder
        written = write_results(results, folder)
    paths = [args.out / path.name for path in written]
    if not args.quiet:
        for warning in results.warnings:
            print(f"warning: {warning}", file=sys.stderr)
        summary = results.summary()
        print(
            f"{scenario.tunnel.model} tunnel–soil model: "
            f"peak invert force {summary['peak_invert_force_N'] / 1e3:.1f} kN, "
            f"peak displacement at the invert {summary['peak_disp_invert_m'] * 1e3:.2f} mm, "
            f"at {COMPARISON_DEPTH_M:g} m {summary['peak_disp_11m_m'] * 1e3:.2f} mm; "
            "long-term settlement after "
            f"{scenario.longterm.years:g} years {summary['longterm_settlement_m'] * 1e3:.2f} mm "
            f"({SETTLEMENT_COVERS}"
            f"{f'; {OUTSIDE_LAW_RANGE}' if results.longterm.outside_law_range else ''}); "
            f"{len(paths)} files in {args.out}"
        )
    return 0
