"""Studies: many runs of the chain, parameter sweeps and Monte-Carlo bands (docs/model.md §11).

A study is a base scenario, some of its parameters varied (a grid, or random / Latin-hypercube
samples within ranges) and a list of irregularity seeds: one run per (point, seed). Every run is
the task :func:`run_summary`, a pure function of the scenario's JSON, so a worker anywhere
computes exactly what :func:`model.pipeline.run` computes in-process. Runs go to Dask
distributed: a ``LocalCluster`` sized to this machine by default, or an existing scheduler
(``tcp://host:port``, argument or ``TUNNELSETTLE_SCHEDULER``).

Examples::

    from model.params import Scenario
    from model.study.execution import run_study
    from model.study.tables import aggregate
    table = run_study(Scenario.paper(), vary={"train.speed_kmh": [60, 80]}, seeds=range(20))
    bands = aggregate(table)     # mean and 5–95 % band per speed across the 20 seeds

    python -m model study --preset paper --vary train.speed_kmh=40:80:5 \\
        --vary soil.youngs_modulus=4e6,6e6,10e6 --seeds 20 --out study

Modules:

- ``definition``: :class:`Study` (base scenario, varied parameters, seeds, sampling; its JSON
  re-runs it) and :func:`define_study`, which checks every scenario before anything runs;
- ``execution``: the task :func:`run_summary`, the Dask client (:func:`study_client`) and
  :func:`run_study` / :func:`execute_study`, with progress and cancelling;
- ``tables``: the study's table, its input and output columns, the bands across seeds
  (:func:`aggregate`) and study folders written and read;
- ``band``: :func:`settlement_band`, the 5–50–95 % band of the long-term settlement by Monte
  Carlo over irregularity seeds, law constants and site properties (the passage once per
  seed);
- ``band_cli``: ``python -m model band``;
- ``cli``: ``python -m model study``.
"""
