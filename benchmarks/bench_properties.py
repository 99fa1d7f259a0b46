"""Long run of the property tests (tests/test_properties.py) with many hypothesis examples.

Run:  python benchmarks/bench_properties.py [--examples 1000] [-k EXPR]

The suite runs the same properties with a bounded number of examples (40, profile ``ci``);
this script sets ``IWAN_HYPOTHESIS_EXAMPLES`` and runs them in a fresh pytest session with
random (not derandomized) generation, then prints one row per property: outcome, examples
asked for and wall time.
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from pathlib import Path

import pytest

HERE = Path(__file__).resolve().parent
TESTS = HERE.parent / "tests" / "test_properties.py"


class _Timer:
    """pytest plugin: outcome and duration of each test."""

    def __init__(self):
        self.rows = {}

    def pytest_runtest_logreport(self, report):
        if report.when == "call" or (report.when == "setup" and report.outcome != "passed"):
            self.rows[report.nodeid.split("::")[-1]] = (report.outcome, report.duration)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--examples", type=int, default=1000, help="hypothesis examples per property")
    ap.add_argument("-k", default=None, help="pytest -k expression to select properties")
    args = ap.parse_args(argv)
    if args.examples < 1:
        ap.error("--examples must be >= 1")
    os.environ["IWAN_HYPOTHESIS_EXAMPLES"] = str(args.examples)
    timer = _Timer()
    pargs = ["-q", "-p", "no:cacheprovider", str(TESTS)] + (["-k", args.k] if args.k else [])
    t0 = time.perf_counter()
    code = pytest.main(pargs, plugins=[timer])
    total = time.perf_counter() - t0
    print(
        f"\npython {platform.python_version()}, {platform.machine()}; "
        f"{args.examples} examples per property; total {total:.1f} s\n"
    )
    print("| property | outcome | examples | wall time [s] |")
    print("|---|---|---|---|")
    for name, (outcome, dur) in timer.rows.items():
        print(f"| {name} | {outcome} | {args.examples} | {dur:.1f} |")
    return int(code)


if __name__ == "__main__":
    sys.exit(main())
