"""Stresses → long-term settlement: the permanent settlement accumulated over years of traffic.

docs/model.md §10, implementation notes in docs/longterm.md. The soil stage gives, per depth d
below the invert, the dynamic deviator q_d of one passage and its rainflow count
(``model.soil.stresses``); this stage adds the static state, counts the cycles, applies an
empirical strain-accumulation law and sums the strain over depth:

- ``geostatic``: σ′_v0, K0, the static deviator q_s and the undrained strength σ_s = 2c_u below
  the invert, from the tunnel's axis depth, the water table and the soil density;
- ``cycles``: load cycles per passage (one per bogie, or range-weighted rainflow) and
  N = trains per day × 365 × years × cycles per train;
- ``strain_laws``: Li & Selig, Chai & Miura and Monismith, ε_p(q_d, N) in %;
- ``settlement``: S = Σ ε_p/100 · Δz against service time (:func:`long_term_settlement`,
  ``LongTermResult``), the depth holding 90 % of S;
- ``calibration``: fitting Li & Selig's a, b, m to cyclic-triaxial data, and reading its CSV.
"""
