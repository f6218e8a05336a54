"""Cyclic strain-accumulation laws ε_p(q_d, N), ε_p in % (docs/model.md §10).

Stresses enter as ratios: Li & Selig (1996) ε_p = a (q_d/σ_s)^m N^b; Chai & Miura (2002)
ε_p = a (q_d/q_f)^m (1 + q_s/q_f)^n N^b; Monismith (1975) ε_p = A N^b wherever the soil is
loaded (q_d > 0).
"""

from __future__ import annotations

import numpy as np

LAW_NAMES = {
    "li_selig": "Li & Selig (1996)",
    "chai_miura": "Chai & Miura (2002)",
    "monismith": "Monismith (1975)",
}


def permanent_strain_percent(
    law: str,
    a: float,
    b: float,
    m: float,
    n: float,
    deviator,
    strength,
    static_deviator,
    n_cycles,
) -> np.ndarray:
    """Accumulated permanent strain ε_p (%) of a cyclic strain-accumulation law.

    Li & Selig: ε_p = a (q_d/σ_s)^m N^b; Chai & Miura: ε_p = a (q_d/q_f)^m (1 + q_s/q_f)^n N^b
    with q_f = σ_s; Monismith: ε_p = a N^b where q_d > 0 and 0 where the soil is not loaded.

    Parameters
    ----------
    law : {"li_selig", "chai_miura", "monismith"}
        Strain law.
    a : float or array_like
        Coefficient (%), > 0; per depth (broadcast against the stresses) for a layered site.
    b, m, n : float or array_like
        Exponents of N, of the stress ratio and (Chai & Miura) of 1 + q_s/q_f, ≥ 0; per depth
        like ``a``.
    deviator : array_like
        Dynamic deviator q_d, ≥ 0 (any stress unit, the same for all three stresses).
    strength : array_like
        Static strength σ_s = q_f, > 0.
    static_deviator : array_like
        Static deviator q_s, ≥ 0 (used by Chai & Miura).
    n_cycles : array_like
        Number of load cycles N, ≥ 0; broadcast against the stresses.

    Returns
    -------
    ndarray
        ε_p in %.
    """
    if law not in LAW_NAMES:
        raise ValueError(f"law = {law!r} is not one of {', '.join(LAW_NAMES)}")
    checks = (("a", a, True), ("b", b, False), ("m", m, False), ("n", n, False))
    for name, value, positive in checks:
        value = np.asarray(value, dtype=float)
        bad = ~np.isfinite(value) | ((value <= 0.0) if positive else (value < 0.0))
        if np.any(bad):
            allowed = "(0, inf)" if positive else "[0, inf)"
            raise ValueError(
                f"{name} = {float(value[bad].flat[0])!r} is outside the allowed range {allowed}"
            )
    q_d, q_f, q_s, cycles = np.broadcast_arrays(
        *(np.asarray(x, dtype=float) for x in (deviator, strength, static_deviator, n_cycles))
    )
    a, b, m, n = (np.asarray(x, dtype=float) for x in (a, b, m, n))
    if np.any(q_f <= 0.0):
        raise ValueError(f"strength = {float(q_f[q_f <= 0.0][0])!r} must be > 0")
    if np.any(q_d < 0.0) or np.any(cycles < 0.0) or np.any(q_s < 0.0):
        raise ValueError("deviator, static_deviator and n_cycles must be ≥ 0")
    growth = a * cycles**b
    if law == "monismith":
        return np.where(q_d > 0.0, growth, 0.0)
    strain = growth * (q_d / q_f) ** m
    if law == "chai_miura":
        strain = strain * (1.0 + q_s / q_f) ** n
    return strain
