#!/usr/bin/env bash
# The project's tests on a fresh machine: the Python environment of the flight files' real
# consumers (pymavlink, MAVSDK, geojson, shapely; see scripts/python-env.sh), then every
# Rust test of the workspace. Needs the shared data directory (../shared/data, or set
# GLEANER_DATA_DIR). Extra arguments go to `cargo test`.
set -euo pipefail
cd "$(dirname "$0")/.."
bash scripts/python-env.sh
cargo test --workspace "$@"
