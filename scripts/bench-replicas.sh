#!/usr/bin/env bash
# Two server replicas over one PostgreSQL farm: WRITES concurrent writes (half plans, half
# records, each pair's plan on one replica and its record on the other), checked for lost
# writes, duplicated mission ids and lost or doubled readings; prints the figures that go
# into BENCHMARKS.md. Needs the shared data (../shared/data or GLEANER_DATA_DIR).
#   scripts/bench-replicas.sh [WRITES]     (default 1000)
set -euo pipefail
cd "$(dirname "$0")/.."
writes="${1:-1000}"
if [ -z "${GLEANER_TEST_PG_URL:-}" ]; then
  pg_dir="$(bash scripts/pg-cluster.sh start)"
  trap 'bash scripts/pg-cluster.sh stop "$pg_dir"' EXIT
  eval "$(bash scripts/pg-cluster.sh env "$pg_dir")"
fi
GLEANER_REPLICA_WRITES="$writes" cargo test --release --locked -p gleaner-server --test it \
  farms::replicas_over_one_postgres_serialise_plans_and_records -- --exact --nocapture
