"""The load and the plastic mesh of the FE section's tests (tests/test_fe_section.py and
tests/test_fe_native.py): a Hann pulse at the invert (0.4 s in a 1 s record, band 1–4 Hz by the
5 %/99 % energy rule, shortest S wavelength c₂/f_high = 8.95 m) on a 12 m section."""

from __future__ import annotations

import numpy as np

from model.fe.mesh import FEMesh

DT_S, PULSE_S = 1e-3, 0.4
PLASTIC_MESH = FEMesh(outer_radius=12.0, plastic_radius=8.0)
"""R = 12 m, plastic within 8 m of the axis."""


def hann_pulse(peak_N_per_m: float = 50e3) -> np.ndarray:
    """Hann pulse of PULSE_S at the invert, then zeros to 1 s (N/m)."""
    t = np.arange(0.0, 1.0, DT_S)
    return np.where(t < PULSE_S, peak_N_per_m * np.sin(np.pi * t / PULSE_S) ** 2, 0.0)
