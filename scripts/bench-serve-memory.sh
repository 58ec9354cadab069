#!/usr/bin/env bash
# The server's resident memory over repeated simulations (BENCHMARKS.md, "Server memory over
# repeated simulations"): makes the demo project in a temporary directory, starts
# `gleaner serve` on it on a free loopback port, posts N `POST /api/v1/simulate` with the
# body `{}` (the project's last 30 days, strategies gleaner, round-robin and freshness) one
# after another, and prints the server's VmRSS (from /proc) after each of the 1st, 2nd,
# 10th, 50th and 100th (and the last), then the last over the first.
#
# Usage: scripts/bench-serve-memory.sh [N] [GLEANER_BINARY]
#   N               simulations to post (default 100)
#   GLEANER_BINARY  the binary to serve with (default target/debug/gleaner; build it with
#                   `cargo build -p gleaner-cli`, or `--release` for target/release/gleaner)
# The server inherits the environment, so allocator settings can be compared: `gleaner serve`
# sets glibc's malloc thresholds itself (GLIBC_TUNABLES) unless that variable is set, so
# `GLIBC_TUNABLES= scripts/bench-serve-memory.sh` measures glibc's defaults and
# `MALLOC_ARENA_MAX=2 GLIBC_TUNABLES= ...` fewer arenas. Everything runs on this machine's loopback; the temporary directory and the
# server are removed at exit.
set -euo pipefail
cd "$(dirname "$0")/.."
n="${1:-100}"
bin="${2:-target/debug/gleaner}"
test -x "$bin" || { echo "bench-serve-memory: $bin is missing (cargo build -p gleaner-cli)" >&2; exit 1; }
work="$(mktemp -d)"
pid=""
cleanup() {
  if [ -n "$pid" ]; then kill "$pid" 2>/dev/null || true; wait "$pid" 2>/dev/null || true; fi
  rm -rf "$work"
}
trap cleanup EXIT

"$bin" demo --dir "$work/demo" >/dev/null
port="$(python3 -c 'import socket; s=socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')"
"$bin" serve --project "$work/demo" --addr "127.0.0.1:$port" >"$work/serve.log" 2>&1 &
pid=$!
url="http://127.0.0.1:$port"
for _ in $(seq 1 600); do
  curl -fsS -o /dev/null "$url/api/v1/project" 2>/dev/null && break
  kill -0 "$pid" 2>/dev/null || { cat "$work/serve.log" >&2; exit 1; }
  sleep 0.1
done

rss_mb() { awk '/^VmRSS:/ { printf "%.1f", $2 / 1024 }' "/proc/$pid/status"; }
echo "bench-serve-memory: $bin, $n simulations; before the first: $(rss_mb) MB"
first=""
for i in $(seq 1 "$n"); do
  code="$(curl -sS -o "$work/answer.json" -w '%{http_code}' -H 'Content-Type: application/json' \
    -d '{}' "$url/api/v1/simulate")"
  if [ "$code" != 200 ]; then
    echo "simulation $i: HTTP $code: $(head -c 400 "$work/answer.json")" >&2
    exit 1
  fi
  rss="$(rss_mb)"
  [ -n "$first" ] || first="$rss"
  case "$i" in 1 | 2 | 10 | 50 | 100 | "$n") echo "after simulation $i: $rss MB" ;; esac
done
echo "last / first: $(awk -v a="$rss" -v b="$first" 'BEGIN { printf "%.2f", a / b }')"
