"""FE results and their storage: one ``.npz`` file per scenario and soil law, keyed by a hash."""

from __future__ import annotations

import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from model.params import Scenario


@dataclass
class FEResult:
    """Result of :func:`run_fe`: displacements below the invert, downward positive."""

    soil_law: str
    passages: int
    depth_m: np.ndarray
    """(nd,) depth below the ring–soil interface of the output nodes (m)."""
    peak_disp_m: np.ndarray
    """(nd,) peak downward displacement during the first passage (m)."""
    residual_disp_m: np.ndarray
    """(nd,) permanent displacement after the last passage, static equilibrium (m)."""
    peak_per_passage_m: np.ndarray
    """(passages, nd) peak displacement during each passage, from the initial state (m)."""
    residual_per_passage_m: np.ndarray
    """(passages, nd) permanent displacement after each passage (m), cumulative."""
    t_s: np.ndarray
    """(nt,) time of the histories (s), all passages with their tails."""
    disp_m: np.ndarray
    """(nd, nt) downward displacement histories (m)."""
    load_N_per_m: np.ndarray
    """(nt,) line load applied at the invert (N/m), after resampling."""
    mesh: dict = field(default_factory=dict)
    """Mesh and numerics: sizes, counts, band, time step, damping, iterations per step."""
    timings_s: dict = field(default_factory=dict)
    """Wall time of each phase (s)."""
    scenario_json: str = ""

    def to_npz(self, path: Path) -> None:
        """Write arrays and metadata to one ``.npz`` file."""
        meta = {
            "soil_law": self.soil_law,
            "passages": self.passages,
            "mesh": self.mesh,
            "timings_s": self.timings_s,
            "scenario_json": self.scenario_json,
        }
        np.savez_compressed(
            path, **{name: getattr(self, name) for name in _ARRAYS}, meta=json.dumps(meta)
        )

    @classmethod
    def from_npz(cls, path: Path) -> FEResult:
        """Read a file written by :meth:`to_npz`."""
        with np.load(path) as data:
            meta = json.loads(str(data["meta"]))
            arrays = {name: data[name] for name in _ARRAYS}
        return cls(**meta, **arrays)


_ARRAYS = (
    "depth_m",
    "peak_disp_m",
    "residual_disp_m",
    "peak_per_passage_m",
    "residual_per_passage_m",
    "t_s",
    "disp_m",
    "load_N_per_m",
)


# ---- stored results ---------------------------------------------------------------------------
def scenario_key(scenario: Scenario) -> str:
    """Hash of the scenario's JSON (16 hex digits): the key of stored FE results."""
    return hashlib.sha256(scenario.to_json(indent=None).encode("utf-8")).hexdigest()[:16]


def result_path(scenario: Scenario, folder, soil_law: str) -> Path:
    """File of the stored FE result of a scenario and soil law in ``folder``."""
    return Path(folder) / f"fe_{scenario_key(scenario)}_{soil_law}.npz"


def save_fe_result(result: FEResult, folder) -> Path:
    """Store a result under its scenario's key; returns the file written.

    Parameters
    ----------
    result : FEResult
        A result of :func:`run_fe`.
    folder : path-like
        Folder (created if missing).

    Returns
    -------
    Path
    """
    path = result_path(Scenario.from_json(result.scenario_json), folder, result.soil_law)
    path.parent.mkdir(parents=True, exist_ok=True)
    result.to_npz(path)
    return path


def stored_fe_result(scenario: Scenario, folder, soil_law: str | None = None) -> FEResult | None:
    """The stored FE result for this exact scenario, or None.

    Parameters
    ----------
    scenario : Scenario
        The scenario; any parameter change gives another key.
    folder : path-like
        Folder of stored results (missing: None).
    soil_law : {"elastic", "mohr_coulomb"} or None
        Law wanted; None takes Mohr–Coulomb if stored, else elastic.

    Returns
    -------
    FEResult or None
    """
    for law in (soil_law,) if soil_law else ("mohr_coulomb", "elastic"):
        path = result_path(scenario, folder, law)
        if path.is_file():
            return FEResult.from_npz(path)
    return None
