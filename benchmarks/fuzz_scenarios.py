"""Long run of the property test of tests/test_properties.py, with counts for docs/validity.md.

Run: ``python benchmarks/fuzz_scenarios.py [--examples 400] [--budget 10] [--changed 3]
[--seed 1]``.

Draws scenarios as the CI test does (1 to ``--changed`` parameters across their full hard
bounds on the cheap single-bogie base), but many more, with random (seeded) generation, and
with a larger run budget: examples estimated above ``--budget`` seconds stop after the input
checks. Prints the counts of sound results, clear refusals, examples only checked up to the
estimate, and failures (each with its drawn parameters and the assertion), and the parameters
named by the refusals.
"""

from __future__ import annotations

import argparse
import collections
import re
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from hypothesis import HealthCheck, given, settings  # noqa: E402
from hypothesis import seed as hypothesis_seed  # noqa: E402

from tests.test_properties import check_property, scenarios  # noqa: E402


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--examples", type=int, default=400)
    parser.add_argument("--budget", type=float, default=10.0, help="estimated seconds per run")
    parser.add_argument("--changed", type=int, default=3, help="most parameters drawn at once")
    parser.add_argument("--seed", type=int, default=1)
    args = parser.parse_args(argv)
    outcomes: collections.Counter[str] = collections.Counter()
    named: collections.Counter[str] = collections.Counter()
    failures: list[str] = []
    start = time.perf_counter()

    @settings(
        max_examples=args.examples,
        deadline=None,
        database=None,
        phases=["generate"],  # count every drawn scenario, do not shrink
        suppress_health_check=list(HealthCheck),
    )
    @given(scenarios(args.changed))
    def fuzz(drawn):
        scenario, changes = drawn
        try:
            outcome, parameter = check_property(scenario, budget_s=args.budget)
        except AssertionError as error:
            outcomes["failed"] += 1
            failures.append(f"{changes}: {error}")
            return
        except Exception as error:  # noqa: BLE001 - a raw exception is what we are counting
            outcomes["raw exception"] += 1
            failures.append(f"{changes}: {type(error).__name__}: {error}")
            return
        outcomes[outcome] += 1
        if outcome == "refused":
            named[parameter] += 1

    hypothesis_seed(args.seed)(fuzz)()
    elapsed = time.perf_counter() - start
    total = sum(outcomes.values())
    print(
        f"{total} scenarios in {elapsed:.0f} s (seed {args.seed}, up to {args.changed} "
        f"parameters drawn, budget {args.budget:g} s)"
    )
    for outcome in ("ok", "refused", "too slow", "failed", "raw exception"):
        print(f"  {outcome:<14} {outcomes[outcome]}")
    if named:
        print("refusals name: " + ", ".join(f"{k} {v}" for k, v in named.most_common()))
    for failure in failures:
        print("FAIL " + re.sub(r"\s+", " ", failure)[:400])
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
