"""Train → track: the vehicle–track stage, which gives the force into the tunnel invert.

Paper §2 and §4.1, docs/model.md §1–6, implementation notes in docs/vehicle_track.md.

- ``irregularity``: the FRA rail-profile PSD, its trigonometric-series synthesis and measured
  profiles from CSV (§4);
- ``assembly``: the kernel records (rail modes on blocks, per-car vehicle matrices, wheels and
  irregularity grid) built from a scenario, and the static equilibrium the passage starts from;
- ``kernels``: the Numba kernels over those records: Hertz contact, accelerations, Zhai's
  explicit step (§3, §5);
- ``vehicle_track``: :func:`simulate` (one passage → ``VehicleTrackResult``), the input checks
  and the explicit stability limit, the Winkler-beam check.
"""
