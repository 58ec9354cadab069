#!/usr/bin/env python3
"""Times `gleaner simulate` (whole command: reading the dataset, preparing the template
project, every run, writing the results and the report) on the campaign-speed scenarios of
BENCHMARKS.md ("Campaign simulation speed").

Usage: scripts/bench-simulate.py [--work DIR] [--runs N] [--only short|sixty|year|synth] [--jobs J]
Needs target/release/gleaner (cargo build --release -p gleaner-cli) and the CAF data
(GLEANER_DATA_DIR, default ../shared/data). Prints one markdown table row per scenario: the
median, min and max wall-clock time and the median CPU time (user + system) of N runs
(default 3), and the peak resident memory of the last run.

Scenarios:
- short: CAF daily, history 2011-2013, 14 daily missions (2014-01-01 .. 2014-01-14),
  strategies gleaner, paper, exhaustive;
- year: CAF daily, history 2011-2013, daily missions through 2014 (365), all 12 strategies;
- sixty: the same over the first 60 missions (2014-01-01 .. 2014-03-01): the profiling run;
- synth: a 10,000-sensor synthetic farm (extent scaled to CAF's density, 30 days of history,
  30 daily missions), strategy gleaner.
"""

import argparse
import os
import resource
import shutil
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GLEANER = ROOT / "target" / "release" / "gleaner"

SCENARIOS = {
    "short": ["--dataset", "caf-daily", "--end", "2014-01-14",
              "--strategies", "gleaner,paper,exhaustive"],
    "year": ["--dataset", "caf-daily", "--strategies", "all"],
    "sixty": ["--dataset", "caf-daily", "--end", "2014-03-01", "--strategies", "all"],
    "synth": ["--dataset", "synthetic", "--farm-sensors", "10000", "--farm-scale-extent",
              "--farm-days", "60", "--farm-history-days", "30", "--farm-seeds", "1",
              "--strategies", "gleaner"],
}


def one_run(args, out):
    shutil.rmtree(out, ignore_errors=True)
    before = resource.getrusage(resource.RUSAGE_CHILDREN)
    t0 = time.perf_counter()
    subprocess.run([str(GLEANER), "simulate", *args, "--out", str(out)], check=True,
                   stdout=subprocess.DEVNULL)
    wall = time.perf_counter() - t0
    after = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
    return wall, cpu, after.ru_maxrss / 1024.0


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--work", default="/tmp/gleaner-bench-simulate")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--jobs", type=int, default=2)
    p.add_argument("--only", choices=sorted(SCENARIOS), action="append")
    a = p.parse_args()
    if not GLEANER.exists():
        sys.exit(f"{GLEANER} missing: cargo build --release -p gleaner-cli")
    data = os.environ.get("GLEANER_DATA_DIR", str(ROOT.parent / "shared" / "data"))
    work = Path(a.work)
    work.mkdir(parents=True, exist_ok=True)
    print("| scenario | wall median (min-max) | CPU median | peak memory | runs |")
    print("|---|---|---|---|---|")
    for name in a.only or ["short", "year", "synth"]:  # `sixty` only with --only
        args = [*SCENARIOS[name], "--data-dir", data, "--jobs", str(a.jobs)]
        runs = [one_run(args, work / name) for _ in range(a.runs)]
        walls = [r[0] for r in runs]
        cpus = [r[1] for r in runs]
        print(f"| {name} | {statistics.median(walls):.1f} s ({min(walls):.1f}-{max(walls):.1f}) "
              f"| {statistics.median(cpus):.1f} s | {runs[-1][2]:.0f} MiB | {a.runs} |",
              flush=True)


if __name__ == "__main__":
    main()
