"""Stresses → long-term settlement: the settlement accumulated over years of traffic.

docs/model.md §10, §14, §15, implementation notes in docs/longterm.md. The soil stage gives, per
depth d below the invert, the dynamic deviator q_d of one passage and its rainflow count
(``model.soil.stresses``); this stage adds the site's static state, counts the cycles, applies
an empirical strain-accumulation law, generates excess pore pressure and lets it consolidate,
and sums both strains over depth:

- ``column``: the depth column, the soil stage's depths with each layer boundary given twice
  (one row per side), and its trapezoidal cells;
- ``geostatic``: σ′_v0 from the layers' unit weights and the water table, K0, the static
  deviator q_s and the undrained strength σ_s = 2c_u of each depth's layer;
- ``cycles``: load cycles per passage (one per bogie, or range-weighted rainflow) and
  N = trains per day × 365 × years × cycles per train;
- ``strain_laws``: Li & Selig, Chai & Miura and Monismith, ε_p(q_d, N) in %;
- ``pore_pressure``: the generated pore pressure u_g = σ′_v0 r_u(N) (power or hyperbolic law),
  m_v and k (or c_v) of each depth's layer;
- ``consolidation``: the 1D dissipation of u_g while traffic goes on (finite volumes, θ-scheme),
  the excess pore pressure u and S_c = Σ m_v (u_g − u) Δz;
- ``settlement``: S = S_p + S_c against service time (:func:`long_term_settlement`,
  ``LongTermResult``), the depth holding 90 % of S;
- ``statements``: the laws and constants behind a result, and its warnings, in words;
- ``calibration``: fitting the strain law and the pore-pressure law to cyclic-triaxial data,
  and reading its CSV by the header's column names.
"""
