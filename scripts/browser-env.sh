#!/usr/bin/env bash
# The headless browser of the dashboard's browser test (crates/gleaner-server/tests): Debian's
# chromium and chromium-driver (WebDriver). Installs them with apt-get when missing (needs
# root, as on CI); does nothing when both are already there. Without them the browser test
# fails.
set -euo pipefail
if command -v chromium >/dev/null 2>&1 && command -v chromedriver >/dev/null 2>&1; then
  exit 0
fi
if [ "$(id -u)" != 0 ]; then
  echo "browser-env: chromium and chromium-driver are missing; run as root or install them: apt-get install chromium chromium-driver" >&2
  exit 1
fi
echo "== installing chromium and chromium-driver (apt-get)"
export DEBIAN_FRONTEND=noninteractive
apt-get update -qq
apt-get install -y -qq --no-install-recommends chromium chromium-driver >/dev/null
command -v chromium >/dev/null && command -v chromedriver >/dev/null
