#!/usr/bin/env bash
# The project's tests on a fresh machine: the Python environment of the flight files' real
# consumers (pymavlink, MAVSDK, geojson, shapely; see scripts/python-env.sh), then every
# Rust test of the workspace. Needs the shared data directory (../shared/data, or set
# GLEANER_DATA_DIR). Extra arguments go to `cargo test`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/python-env.sh
bash scripts/browser-env.sh  # headless chromium + chromium-driver for the dashboard's browser test
# Property tests draw their cases from a fixed seed, so every run tests the same cases (set
# PROPTEST_RNG_SEED to explore others; failures are kept in proptest-regressions/).
export PROPTEST_RNG_SEED="${PROPTEST_RNG_SEED:-20261130}"
# PostgreSQL backend tests: a throwaway local cluster unless GLEANER_TEST_PG_URL names a server
# (the tests fail without one); stopped and deleted at exit.
if [ -z "${GLEANER_TEST_PG_URL:-}" ]; then
  pg_dir="$(bash scripts/pg-cluster.sh start)"
  trap 'bash scripts/pg-cluster.sh stop "$pg_dir"' EXIT
  eval "$(bash scripts/pg-cluster.sh env "$pg_dir")"
fi
cargo test --workspace "$@"
