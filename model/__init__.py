"""tunnelsettle's model: metro-tunnel vibration and settlement, train → track → soil → long term.

The sub-packages follow the chain of the computation (docs/model.md):

- ``params``: every input, with its bounds, unit and default (:class:`Scenario`);
- ``track``: train → track, the vehicle–track simulation and the force into the invert (§1–6);
- ``soil``: load → soil, the tunnel–soil response and stresses under the invert (§7–9);
- ``longterm``: stresses → settlement over years of traffic, plastic and consolidation, in the
  layered site (§10, §14, §15);
- ``pipeline``: :func:`run`, the one place the stages are chained, with their cache;
  ``run_checks``: what a run refuses before computing and warns about after;
- ``study``: many runs on Dask, sweeps and Monte-Carlo bands (§11);
- ``fe``: the OpenSeesPy finite-element check of the section (§12);
- ``spectra`` (PSD/FFT helpers shared by the stages), ``run_cost`` (memory and time of a run,
  estimated before it starts), ``scenarios`` (presets, train types, text overrides),
  ``outputs`` (result files written whole: a temporary name, then a rename), ``cli``
  (``python -m model``) and ``commands`` (its subcommand table, light enough for an instant
  ``--help``).

The public API is importable from the package itself, ``import model; model.run(...)``; each
name is imported from its module (``PUBLIC_API``) on first use, so ``import model`` stays cheap.
"""

import importlib

PUBLIC_API = {
    "Scenario": "model.params",
    "ScenarioError": "model.params",
    "Site": "model.params",
    "Layer": "model.params",
    "load_borehole_csv": "model.params.borehole",
    "run": "model.pipeline",
    "Results": "model.pipeline",
    "StageCache": "model.pipeline",
    "SimulationError": "model.pipeline",
    "fra_psd": "model.track.irregularity",
    "synthesize_profile": "model.track.irregularity",
    "simulate": "model.track.vehicle_track",
    "invert_receptance": "model.soil.section_2d",
    "receptance_2p5d": "model.soil.moving_load_2p5d",
    "point_load_response": "model.soil.point_load",
    "soil_response": "model.soil.response",
    "halfspace_point_response": "model.soil.halfspace",
    "long_term_settlement": "model.longterm.settlement",
    "fit_strain_law": "model.longterm.calibration",
    "fit_pore_pressure_law": "model.longterm.calibration",
    "solve_consolidation": "model.longterm.consolidation",
    "load_triaxial_csv": "model.longterm.calibration",
    "run_study": "model.study.execution",
    "aggregate": "model.study.tables",
    "settlement_band": "model.study.band",
    "run_fe": "model.fe.analysis",
}
"""Public name → the module that defines it."""

__all__ = list(PUBLIC_API)


def __getattr__(name: str):
    """Import a public name from its module on first use (PEP 562)."""
    try:
        module = PUBLIC_API[name]
    except KeyError:
        raise AttributeError(f"module 'model' has no attribute {name!r}") from None
    value = getattr(importlib.import_module(module), name)
    globals()[name] = value  # later lookups do not come here
    return value


def __dir__() -> list[str]:
    """The module's attributes and the public API."""
    return sorted({*globals(), *PUBLIC_API})
