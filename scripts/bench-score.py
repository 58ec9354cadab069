#!/usr/bin/env python3
"""Times `gleaner score` after a recorded mission, from the persisted utility state (the fast
path) and from the whole history (the same readings, forced through the full path with
`--history-until 2100-01-01`), on CAF and on a 10,000-sensor synthetic farm.

Usage: scripts/bench-score.py [--work DIR] [--runs N] [--full-runs N] [--only caf|synth]
Needs target/release/gleaner (cargo build --release -p gleaner-cli) and the CAF data
(GLEANER_DATA_DIR, default ../shared/data). Prints one markdown table row per measurement.

Scenario, per farm: init; ingest the history; `gleaner explore` stores the exploration
sorties; sortie #1 is recorded as flown with the readings its sensors logged since the end of
the history (CAF: vw@30cm of Jan-Feb 2014; synthetic: every modality of the last 14 days);
then `gleaner score` (whole command, wall clock, median of N runs (default 9; full path 3);
each run also writes the
cell metadata table, as the command does).
"""

import argparse
import csv
import json
import os
import statistics
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
GLEANER = ROOT / "target" / "release" / "gleaner"


def run(*args, capture=False):
    r = subprocess.run([str(GLEANER), *map(str, args)], check=True,
                       stdout=subprocess.PIPE if capture else subprocess.DEVNULL)
    return r.stdout.decode() if capture else None


def timed(args, runs):
    times = []
    for _ in range(runs):
        t0 = time.perf_counter()
        run(*args)
        times.append(time.perf_counter() - t0)
    return statistics.median(times), min(times), max(times)


def sortie_sensors(project):
    """Sensors of the cells of mission #1."""
    mission = json.loads(run("missions", "--project", project, "--mission", "1", "--json",
                             capture=True))
    stops = {s["cell"] for s in find_stops(mission)}
    cells = json.loads(run("cells", "--project", project, "--json", capture=True))
    rows = cells["cells"] if isinstance(cells, dict) else cells
    return sorted({s for c in rows if c["cell"] in stops for s in c["sensors"]})


def find_stops(doc):
    if isinstance(doc, dict):
        if "stops" in doc:
            return doc["stops"]
        for v in doc.values():
            found = find_stops(v)
            if found is not None:
                return found
    return None


def caf(work, runs, data):
    daily = data / "caf" / "Daily"
    hist = work / "caf-history"
    hist.mkdir(parents=True, exist_ok=True)
    files = []
    for path in sorted(daily.iterdir()):
        lines = path.read_text().splitlines()
        kept = [lines[0]] + [l for l in lines[1:]
                             if l.split("\t")[1][-4:] in ("2011", "2012", "2013")]
        (hist / path.name).write_text("\n".join(kept) + "\n")
        files.append(hist / path.name)
    project = work / "caf"
    run("init", "--dir", project, "--sensors",
        data / "caf" / "sensors" / "CAF_sensor_locations.csv", "--utm-zone", "11N", "--force")
    run("ingest", "--project", project, *files)
    run("explore", "--project", project, "--at", "2014-03-01")
    sensors = sortie_sensors(project)
    flight = work / "caf-flight.csv"
    with flight.open("w") as f:
        f.write("sensor_id,timestamp,modality,value,unit\n")
        for s in sensors:
            for l in (daily / f"{s}.txt").read_text().splitlines()[1:]:
                cols = l.split("\t")
                m, d, y = cols[1].split("/")
                if y == "2014" and int(m) <= 2 and cols[2] != "NA":
                    f.write(f"{s},{y}-{int(m):02}-{int(d):02},vw@30cm,{cols[2]},m3/m3\n")
    run("record", "--project", project, "--mission", "1", "--at", "2014-03-01", flight)
    return project, "2014-03-01"


def synth(work, runs, sensors=10_000, days=365):
    out = work / "big"
    # The farm of the foundation benchmark (BENCHMARKS.md): 10,000 stations on CAF's extent.
    run("synth", "--out", out, "--sensors", sensors, "--days", days, "--vw-depths", "30",
        "--t-depths", "30")
    readings = out / "readings.csv"
    with readings.open() as f:
        reader = csv.reader(f)
        header = next(reader)
        rows = list(reader)
    last = max(r[1] for r in rows)
    # The last 14 days come back with the flight.
    cut = sorted({r[1] for r in rows})[-14]
    hist = work / "big-history.csv"
    with hist.open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(r for r in rows if r[1] < cut)
    project = work / "big-project"
    run("init", "--dir", project, "--sensors", out / "sensors.csv", "--force")
    run("ingest", "--project", project, hist)
    at = last
    run("explore", "--project", project, "--at", at)
    visited = set(sortie_sensors(project))
    flight = work / "big-flight.csv"
    with flight.open("w", newline="") as f:
        w = csv.writer(f, lineterminator="\n")
        w.writerow(header)
        w.writerows(r for r in rows if r[1] >= cut and r[0] in visited)
    run("record", "--project", project, "--mission", "1", "--at", at, flight)
    return project, at


def main():
    p = argparse.ArgumentParser()
    p.add_argument("--work", type=Path, default=Path("/tmp/gleaner-bench-score"))
    p.add_argument("--runs", type=int, default=9)
    p.add_argument("--full-runs", type=int, default=3, help="runs of the full-history path")
    p.add_argument("--only", choices=["caf", "synth"])
    a = p.parse_args()
    data = Path(os.environ.get("GLEANER_DATA_DIR", ROOT.parent / "shared" / "data"))
    a.work.mkdir(parents=True, exist_ok=True)
    farms = []
    if a.only in (None, "caf"):
        t0 = time.perf_counter()
        farms.append(("CAF", *caf(a.work, a.runs, data)))
        print(f"# CAF set-up {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    if a.only in (None, "synth"):
        t0 = time.perf_counter()
        farms.append(("10,000 sensors", *synth(a.work, a.runs)))
        print(f"# synthetic set-up {time.perf_counter() - t0:.1f} s", file=sys.stderr)
    for name, project, at in farms:
        for label, extra, runs in [
            ("persisted state", [], a.runs),
            ("persisted state, --at mission time", ["--at", at], a.runs),
            ("full history", ["--at", at, "--history-until", "2100-01-01"], a.full_runs),
        ]:
            med, lo, hi = timed(["score", "--project", project, *extra], runs)
            print(f"| `gleaner score` on {name} after a recorded mission, {label} "
                  f"| {med * 1000:.0f} ms (min {lo * 1000:.0f}, max {hi * 1000:.0f}) |")


if __name__ == "__main__":
    main()
