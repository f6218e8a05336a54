"""``python -m model band``: the settlement band (:mod:`model.study.band`) on the command line."""

from __future__ import annotations

import argparse
import sys
from collections.abc import Iterable, Sequence
from pathlib import Path
from typing import Any

from model.longterm.statements import SETTLEMENT_COVERS
from model.outputs import check_output_folder, replacing_folder
from model.params import Scenario
from model.study.band import (
    DEFAULT_DRAWS,
    DEFAULT_SEEDS,
    LAW_CONSTANTS,
    SITE_PROPERTIES,
    save_band,
    settlement_band,
)


def _parse_cvs(items: Iterable[str], option: str, n_layers: int | None = None):
    """``NAME=CV`` items (``LAYER:NAME=CV`` for ``--site-cv``) as the mappings of the API."""
    every: dict[str, str] = {}
    layered: dict[int, dict[str, str]] = {}
    for item in items:
        name, sep, value = item.partition("=")
        if not sep:
            raise ValueError(f"{option} {item!r} must be of the form name=cv")
        layer, colon, name = name.strip().rpartition(":") if n_layers else ("", "", name.strip())
        if colon:
            try:
                index = int(layer)
            except ValueError:
                raise ValueError(
                    f"{option} {item!r}: the layer {layer!r} is not an index"
                ) from None
            if not 0 <= index < n_layers:
                raise ValueError(
                    f"{option} {item!r}: layer {index} is outside the allowed range "
                    f"[0, {n_layers - 1}] (site.layers, top down)"
                )
            layered.setdefault(index, {})[name] = value.strip()
        else:
            every[name] = value.strip()
    if not layered:
        return every
    return [{**every, **layered.get(index, {})} for index in range(n_layers)]


def build_parser(prog: str = "python -m model band") -> argparse.ArgumentParser:
    """Argument parser of ``python -m model band``."""
    from model.cli import add_output_arguments, add_scenario_arguments
    from model.study.cli import add_cluster_arguments

    parser = argparse.ArgumentParser(
        prog=prog,
        description="5-50-95 % band of the long-term settlement by Monte Carlo on Dask "
        "distributed: irregularity seeds, law constants and site properties drawn.",
    )
    add_scenario_arguments(parser)
    parser.add_argument("--draws", type=int, default=DEFAULT_DRAWS, help="number of draws")
    parser.add_argument(
        "--seeds",
        default=str(DEFAULT_SEEDS),
        help="irregularity seeds: a count N (the base seed and the N-1 after it) or a,b,c",
    )
    parser.add_argument(
        "--law-cv",
        action="append",
        default=[],
        metavar="NAME=CV",
        help=f"coefficient of variation of a law constant ({', '.join(LAW_CONSTANTS)}) of "
        "every layer (repeatable)",
    )
    parser.add_argument(
        "--site-cv",
        action="append",
        default=[],
        metavar="[LAYER:]NAME=CV",
        help=f"coefficient of variation of a layer property ({', '.join(SITE_PROPERTIES)}), "
        "of every layer or of layer LAYER (0 the top one); repeatable",
    )
    parser.add_argument(
        "--calibration",
        type=Path,
        help="cyclic-triaxial CSV: Li & Selig's law fitted to it is applied to --calibrated-layer "
        "and its a, b, m drawn from the fit's covariance",
    )
    parser.add_argument(
        "--calibrated-layer", type=int, default=0, help="layer given the calibration (default 0)"
    )
    parser.add_argument("--sampling-seed", type=int, default=0, help="seed of the draws")
    add_output_arguments(parser)
    add_cluster_arguments(parser)
    parser.add_argument("--quiet", action="store_true", help="no progress bar or summary")
    return parser


def _calibrate(scenario: Scenario, path: Path, layer_index: int) -> dict[str, Any]:
    """Fit Li & Selig's law to a triaxial CSV and apply it to one layer; the fit."""
    from model.longterm.calibration import fit_strain_law, load_triaxial_csv

    layers = scenario.site.layers
    if not 0 <= layer_index < len(layers):
        raise ValueError(
            f"--calibrated-layer {layer_index} is outside the allowed range "
            f"[0, {len(layers) - 1}] (site.layers, top down)"
        )
    data = load_triaxial_csv(path)
    fit = fit_strain_law(data.n_cycles, data.strain_percent, data.stress_ratio)
    scenario.longterm.law = "li_selig"
    layer = layers[layer_index]
    layer.soil_class = "user"
    layer.a, layer.b, layer.m = fit["a"], fit["b"], fit["m"]
    return fit


def main(argv: Sequence[str] | None = None, prog: str = "python -m model band") -> int:
    """``python -m model band``: returns the exit code (2 bad input, 130 cancelled)."""
    from model.cli import TerminalProgress, load_scenario
    from model.study.cli import parse_seeds

    class BandProgress(TerminalProgress):
        """Seeds done out of all, on the command line's progress bar."""

        def __call__(self, done: int, total: int, row: dict) -> None:
            filled = round(done / total * self.width)
            bar = "#" * filled + "-" * (self.width - filled)
            self.stream.write(f"\r[{bar}] {done}/{total} seeds")
            self.stream.flush()
            self.shown = True

    parser = build_parser(prog)
    args = parser.parse_args(None if argv is None else list(argv))
    progress = None if args.quiet else BandProgress()
    try:
        scenario = load_scenario(args)
        check_output_folder(args.out, args.force)  # before the draws
        calibration = (
            _calibrate(scenario, args.calibration, args.calibrated_layer)
            if args.calibration
            else None
        )
        table = settlement_band(
            scenario,
            args.draws,
            parse_seeds(args.seeds, scenario.irregularity.seed),
            args.scheduler,
            law_cv=_parse_cvs(args.law_cv, "--law-cv"),
            site_cv=_parse_cvs(args.site_cv, "--site-cv", len(scenario.site.layers)) or None,
            calibration=calibration,
            sampling_seed=args.sampling_seed,
            progress=progress,
            n_workers=args.workers,
        )
        with replacing_folder(args.out) as folder:  # an interrupted write keeps the old band
            paths = [args.out / path.name for path in save_band(table, folder)]
    except (ValueError, KeyError, OSError) as error:
        message = error.args[0] if isinstance(error, KeyError) and error.args else error
        parser.exit(2, f"error: {message}\n")
    finally:
        if progress is not None:
            progress.close()
    cancelled = table.attrs["cancelled"]
    if not args.quiet and len(table):
        final = table.iloc[-1]
        print(
            f"band of {table.attrs['n_draws']} of {table.attrs['n_requested']} draws "
            f"({len(table.attrs['seeds'])} seeds): settlement after {final['years']:g} years "
            f"p05 {final['p05'] * 1e3:.3g} mm, p50 {final['p50'] * 1e3:.3g} mm, "
            f"p95 {final['p95'] * 1e3:.3g} mm ({SETTLEMENT_COVERS}); "
            f"{', '.join(str(p) for p in paths)}",
            file=sys.stderr if cancelled else sys.stdout,
        )
    return 130 if cancelled else 0
