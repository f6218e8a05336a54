"""FE results and their storage: one ``.npz`` file per scenario and soil law, keyed by a hash."""

from __future__ import annotations

import hashlib
import json
import warnings
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from model.outputs import write_atomic
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
        arrays = {name: getattr(self, name) for name in _ARRAYS}
        # through an open file: savez would append ".npz" to write_atomic's temporary name
        write_atomic(path, lambda temporary: _savez(temporary, arrays, json.dumps(meta)))

    @classmethod
    def from_npz(cls, path: Path) -> FEResult:
        """Read a file written by :meth:`to_npz`."""
        with open(path, "rb") as file, np.load(file) as data:
            meta = json.loads(str(data["meta"]))
            arrays = {name: data[name] for name in _ARRAYS}
        return cls(**meta, **arrays)


def _savez(path: Path, arrays: dict[str, np.ndarray], meta: str) -> None:
    """Compressed ``.npz`` of the arrays and the metadata's JSON, at exactly ``path``."""
    with open(path, "wb") as file:
        np.savez_compressed(file, **arrays, meta=meta)


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
    """Hash (16 hex digits) of what an FE result depends on: the key of stored FE results.

    That is the pipeline's key of the line load (vehicle, train, track, irregularity with a
    measured profile by its content's digest, and their numerics) and the tunnel, soil and
    site the section is built from; the tunnel–soil numerics of the analytical model (e.g. the
    2.5D wavenumber integral) do not enter.
    """
    from model.pipeline import stage_keys

    data = scenario.to_dict()
    inputs = {
        "load": stage_keys(scenario)["load"],
        **{section: data[section] for section in ("tunnel", "soil", "site")},
    }
    text = json.dumps(inputs, sort_keys=True)
    return hashlib.sha256(text.encode("utf-8")).hexdigest()[:16]


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

    Warns
    -----
    UserWarning
        A stored file that cannot be read (cut short, not an FE result) is passed over, as if
        absent, so that it is computed again; the warning names the file.
    """
    for law in (soil_law,) if soil_law else ("mohr_coulomb", "elastic"):
        path = result_path(scenario, folder, law)
        if not path.is_file():
            continue
        try:
            return FEResult.from_npz(path)
        except (OSError, ValueError, KeyError, TypeError, EOFError, zipfile.BadZipFile) as error:
            warnings.warn(
                f"stored FE result {path} cannot be read ({type(error).__name__}): it is "
                "ignored and the result computed again",
                UserWarning,
                stacklevel=2,
            )
    return None
