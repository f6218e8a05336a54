"""Time a Monte-Carlo study on Dask against the same runs made one after another in-process.

Run: ``python benchmarks/bench_study.py [--runs 10] [--workers 2] [--band-draws 1000]``. The
paper case with ``--runs`` irregularity seeds:

- serial: ``run(scenario, cache=StageCache())`` for each seed in this process (warm Numba
  caches; the stage cache lets the runs share the tunnel–soil transfer functions, as each study
  worker's process does, so that the ratio measures the parallelism, not the cache);
- study, warm cluster: :func:`model.study.execution.execute_study` on a LocalCluster whose
  workers have already loaded the compiled kernels (an existing cluster, the usual case for big
  studies);
- study, cold: :func:`model.study.execution.run_study` with ``scheduler=None``, cluster start
  included;
- per-task overhead: the round trip of a task that does nothing, submitted and collected the
  way a study does, and the scenario-JSON parsing a study task adds to a run;
- settlement band: :func:`model.study.band.settlement_band` of the paper case with
  ``--band-draws`` draws (CV 0.2 on the strain-law constant a of every layer, 0.3 on the
  permeabilities) on a new LocalCluster of ``--workers`` workers, start included: the passage
  once per seed, the long-term stage alone for each draw (issue 27: 1000 draws in under a
  minute on two workers).

Serial and warm study alternate for ``--rounds`` rounds and the best wall time of each is kept,
so that a machine shared with other jobs biases neither. The CPU seconds per run (this process
for the serial runs, the workers' processes for the study) do not depend on that load: on an
idle machine the study takes about (CPU per run in a worker × runs / workers + overhead).

Prints wall times and the ratios study / serial (issue 27's target for 10 runs, cluster start
included: ≤ 0.6 with 2 workers).
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent.parent))

from model.params import Scenario  # noqa: E402
from model.pipeline import StageCache, run  # noqa: E402
from model.study.band import settlement_band  # noqa: E402
from model.study.definition import define_study  # noqa: E402
from model.study.execution import execute_study, run_study, study_client  # noqa: E402

N_NOOP = 200


def _noop(index: int) -> int:
    """A task that does nothing (measures Dask's own cost per task)."""
    return index


def _warm_worker() -> None:
    """Load the compiled kernels in a worker (a cheap run touches every kernel)."""
    scenario = Scenario.preset("single_bogie")
    scenario.numerics.n_depths = 11
    run(scenario, cache=None)


def serial_seconds(base: Scenario, seeds: list[int]) -> tuple[float, float]:
    """Wall and CPU time (this process, all its threads) of the runs one after another."""
    cache = StageCache(size=1, transfer_size=1)
    start, cpu = time.perf_counter(), time.process_time()
    for seed in seeds:
        scenario = base.copy()
        scenario.irregularity.seed = seed
        run(scenario, cache=cache)
    return time.perf_counter() - start, time.process_time() - cpu


def _cpu_seconds() -> float:
    """CPU time of this worker process so far (s)."""
    return time.process_time()


def study_seconds(study, client) -> tuple[float, float]:
    """Wall time of the study and the CPU time its workers spent (s)."""
    before = client.run(_cpu_seconds)
    start = time.perf_counter()
    table = execute_study(study, client)
    wall = time.perf_counter() - start
    after = client.run(_cpu_seconds)
    assert len(table) == study.n_runs and "error" not in table
    return wall, sum(after[w] - before[w] for w in after)


def task_overhead_seconds(client) -> float:
    """Mean wall time per no-op task, submitted at once and collected as they finish."""
    from distributed import as_completed

    start = time.perf_counter()
    futures = [client.submit(_noop, i, pure=False) for i in range(N_NOOP)]
    for future in as_completed(futures, loop=client.loop):
        future.result()
    return (time.perf_counter() - start) / N_NOOP


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=10)
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--rounds", type=int, default=2, help="alternating serial/study rounds")
    parser.add_argument("--band-draws", type=int, default=1000, help="0: no band")
    args = parser.parse_args()
    base = Scenario.paper()
    seeds = list(range(base.irregularity.seed, base.irregularity.seed + args.runs))
    run(base, cache=None)  # load the Numba caches in this process
    parse_start = time.perf_counter()
    text = base.to_json()
    for _ in range(100):
        Scenario.from_json(text)
    parse = (time.perf_counter() - parse_start) / 100

    study = define_study(base, {}, seeds)
    serial, warm = [], []
    with study_client(n_workers=args.workers) as client:
        client.wait_for_workers(args.workers)
        client.run(_warm_worker)
        for _ in range(args.rounds):
            serial.append(serial_seconds(base, seeds))
            warm.append(study_seconds(study, client))
        overhead = task_overhead_seconds(client)
    (serial_wall, serial_cpu), (warm_wall, warm_cpu) = min(serial), min(warm)
    n = args.runs
    print(
        f"serial, in-process: {n} runs of the paper case in {serial_wall:.2f} s "
        f"({serial_wall / n:.3f} s per run; CPU {serial_cpu / n:.3f} s per run); "
        f"best of {args.rounds}: {', '.join(f'{w:.1f}' for w, _ in serial)} s"
    )
    print(
        f"study, warm cluster of {args.workers} workers: {warm_wall:.2f} s = "
        f"{warm_wall / serial_wall:.2f} × serial (CPU {warm_cpu / n:.3f} s per run in the "
        f"workers); best of {args.rounds}: {', '.join(f'{w:.1f}' for w, _ in warm)} s"
    )
    idle = warm_cpu / args.workers + n * overhead
    print(
        f"idle-machine estimate from CPU time: study {idle:.1f} s vs serial {serial_cpu:.1f} s "
        f"= {idle / serial_cpu:.2f} × serial"
    )

    start = time.perf_counter()
    table = run_study(base, {}, seeds, n_workers=args.workers)
    cold = time.perf_counter() - start
    assert len(table) == args.runs and "error" not in table
    print(
        f"study, cold (LocalCluster start and kernel loading included): {cold:.2f} s = "
        f"{cold / serial_wall:.2f} × serial"
    )
    print(
        f"per-task overhead: Dask round trip of a no-op task {overhead * 1e3:.1f} ms "
        f"(mean of {N_NOOP}, {args.workers} workers); scenario JSON parsing in the task "
        f"{parse * 1e3:.1f} ms"
    )
    if args.band_draws:
        start = time.perf_counter()
        band = settlement_band(
            base,
            n_draws=args.band_draws,
            law_cv={"a": 0.2},
            site_cv={"permeability": 0.3},
            n_workers=args.workers,
        )
        seconds = time.perf_counter() - start
        assert band.attrs["n_draws"] == args.band_draws
        print(
            f"settlement band, {args.band_draws} draws over {len(band.attrs['seeds'])} seeds, "
            f"LocalCluster of {args.workers} workers (start included): {seconds:.1f} s "
            f"({seconds / args.band_draws * 1e3:.1f} ms per draw)"
        )


if __name__ == "__main__":
    main()
