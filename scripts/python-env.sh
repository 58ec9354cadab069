#!/usr/bin/env bash
# Creates the Python environment the flight-file consumer checks run in: a venv at
# <workspace>/.venv with pinned versions of the real consumers of gleaner's flight files —
# pymavlink (QGC WPL 110 loader), MAVSDK-Python (QGroundControl .plan importer, with its
# bundled mavsdk_server), geojson and shapely (RFC 7946 checks), fastkml (its bundled OGC KML
# 2.2 schema) and lxml (the DJI WPML archive's KML parts validated against it).
#
# Idempotent: an existing venv is reused and only missing or mismatched pins are installed.
# Override the interpreter with PYTHON=/path/to/python3 (3.11 is what CI uses).
set -euo pipefail
cd "$(dirname "$0")/.."

PYTHON="${PYTHON:-python3}"
VENV=".venv"

PINS=(
  "pymavlink==2.4.50"
  "mavsdk==3.10.2"
  "geojson==3.3.0"
  "shapely==2.1.2"
  "fastkml==1.4.0"
  "lxml==6.1.3"
)

if [ ! -x "$VENV/bin/python" ]; then
  echo "== python-env: creating $VENV with $("$PYTHON" --version 2>&1)"
  "$PYTHON" -m venv "$VENV"
fi

if "$VENV/bin/python" - "${PINS[@]}" <<'PY'
import sys
from importlib import metadata
for pin in sys.argv[1:]:
    name, version = pin.split("==")
    try:
        if metadata.version(name) != version:
            sys.exit(1)
    except metadata.PackageNotFoundError:
        sys.exit(1)
PY
then
  echo "== python-env: $VENV already has ${PINS[*]}"
else
  echo "== python-env: installing ${PINS[*]}"
  "$VENV/bin/python" -m pip install --quiet --disable-pip-version-check "${PINS[@]}"
fi
"$VENV/bin/python" -c "import pymavlink, mavsdk, geojson, shapely, fastkml, lxml; print('== python-env: ok')"
