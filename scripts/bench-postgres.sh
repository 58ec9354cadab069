#!/usr/bin/env bash
# PostgreSQL vs SQLite on the same project (the real CAF daily network), release build:
# median wall times over RUNS runs (default 5) of
#   ingest  every CAF daily file into a new project (759,915 readings; binary COPY on PostgreSQL)
#   score   every cell at 2016-06-16 from all history
#   plan    a mission at 2016-06-16 (seed 1, 2,000 iterations: the same route every run)
# Starts a throwaway PostgreSQL cluster unless GLEANER_TEST_PG_URL is set. Prints a table;
# the figures in BENCHMARKS.md come from it.
set -euo pipefail
cd "$(dirname "$0")/.."
RUNS="${RUNS:-5}"
DATA="${GLEANER_DATA_DIR:-../shared/data}"
cargo build --release -q -p gleaner-cli
G="$PWD/target/release/gleaner"
if [ -z "${GLEANER_TEST_PG_URL:-}" ]; then
  pg_dir="$(bash scripts/pg-cluster.sh start)"
  trap 'bash scripts/pg-cluster.sh stop "$pg_dir"' EXIT
  eval "$(bash scripts/pg-cluster.sh env "$pg_dir")"
fi
work="$(mktemp -d)"
trap 'rm -rf "$work"; [ -n "${pg_dir:-}" ] && bash scripts/pg-cluster.sh stop "$pg_dir"' EXIT

now() { date +%s.%N; }
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }

declare -A times
for backend in sqlite postgres; do
  for run in $(seq "$RUNS"); do
    dir="$work/$backend-$run"
    db=()
    if [ "$backend" = postgres ]; then db=(--database "$GLEANER_TEST_PG_URL#bench_$run"); fi
    "$G" init --dir "$dir" --sensors "$DATA/caf/sensors/CAF_sensor_locations.csv" --utm-zone 11N \
      "${db[@]}" >/dev/null
    t0=$(now); "$G" ingest --project "$dir" "$DATA"/caf/Daily/*.txt >/dev/null; t1=$(now)
    "$G" score --project "$dir" --at 2016-06-16 >/dev/null; t2=$(now)
    "$G" plan --project "$dir" --at 2016-06-16 --seed 1 --iterations 2000 --time-limit 60 \
      --dry-run >"$work/plan-$backend-$run.txt"; t3=$(now)
    times[$backend-ingest]+="$(echo "$t1 - $t0" | bc) "
    times[$backend-score]+="$(echo "$t2 - $t1" | bc) "
    times[$backend-plan]+="$(echo "$t3 - $t2" | bc) "
  done
done
printf "%-8s %12s %12s %8s\n" step sqlite_s postgres_s ratio
for step in ingest score plan; do
  s=$(echo "${times[sqlite-$step]}" | tr ' ' '\n' | grep . | median)
  p=$(echo "${times[postgres-$step]}" | tr ' ' '\n' | grep . | median)
  printf "%-8s %12.3f %12.3f %8.2f\n" "$step" "$s" "$p" "$(echo "$p / $s" | bc -l)"
done
p=$(echo "${times[postgres-ingest]}" | tr ' ' '\n' | grep . | median)
printf "postgres ingest: %.0f readings/s (759915 readings, parsing included)\n" "$(echo "759915 / $p" | bc -l)"
cmp -s "$work/plan-sqlite-1.txt" "$work/plan-postgres-1.txt" && echo "plans identical on both backends" || echo "plans differ between backends"
