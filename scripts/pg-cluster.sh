#!/usr/bin/env bash
# A throwaway PostgreSQL cluster for gleaner's tests and benchmarks.
#
#   scripts/pg-cluster.sh start [DIR]   create (initdb) and start a cluster in DIR (default: a
#                                       new temporary directory); prints the cluster directory
#   scripts/pg-cluster.sh env [DIR]     prints `export GLEANER_TEST_PG_URL=...` for the cluster
#   scripts/pg-cluster.sh stop [DIR]    stops the cluster and deletes DIR
#
# The server listens on a Unix socket inside DIR only (no TCP port), so clusters of several
# checkouts never collide. PostgreSQL comes from Debian (installed with apt-get when missing
# and running as root). initdb refuses to run as root, so as root the cluster belongs to the
# unprivileged `postgres` account the Debian package creates. The database is `gleaner`, the
# role the cluster's owner, trust authentication on the socket: for tests only.
set -euo pipefail

cmd="${1:-}"
dir="${2:-${GLEANER_PG_DIR:-}}"

find_bin() {
  local b
  for b in /usr/lib/postgresql/*/bin; do
    if [ -x "$b/initdb" ]; then echo "$b"; return 0; fi
  done
  command -v initdb >/dev/null 2>&1 && dirname "$(command -v initdb)" && return 0
  return 1
}

ensure_installed() {
  if ! find_bin >/dev/null; then
    if [ "$(id -u)" -ne 0 ]; then
      echo "pg-cluster: PostgreSQL is not installed; run as root or install 'postgresql'" >&2
      exit 1
    fi
    echo "pg-cluster: installing postgresql from Debian" >&2
    DEBIAN_FRONTEND=noninteractive apt-get update -qq >&2
    DEBIAN_FRONTEND=noninteractive apt-get install -y -qq postgresql >&2
  fi
}

# Runs a command as the cluster's owner: `postgres` when we are root, ourselves otherwise.
as_owner() {
  if [ "$(id -u)" -eq 0 ]; then
    runuser -u postgres -- "$@"
  else
    "$@"
  fi
}

url_of() {
  echo "postgresql://$(as_owner id -un)@/gleaner?host=$1/socket"
}

case "$cmd" in
  start)
    ensure_installed
    bin="$(find_bin)"
    if [ -z "$dir" ]; then dir="$(mktemp -d /tmp/gleaner-pg.XXXXXX)"; fi
    mkdir -p "$dir/socket"
    if [ "$(id -u)" -eq 0 ]; then chown -R postgres: "$dir"; fi
    as_owner "$bin/initdb" -D "$dir/data" -A trust -E UTF8 --no-locale >"$dir/initdb.log" 2>&1 || {
      cat "$dir/initdb.log" >&2
      exit 1
    }
    # fsync stays on: the crash tests kill clients, not the server, but a benchmark should
    # measure a durable server.
    as_owner "$bin/pg_ctl" -D "$dir/data" -l "$dir/server.log" -w -o \
      "-c listen_addresses='' -c unix_socket_directories='$dir/socket' -c max_connections=200 -c shared_buffers=256MB" \
      start >/dev/null || {
      cat "$dir/server.log" >&2
      exit 1
    }
    as_owner "$bin/createdb" -h "$dir/socket" gleaner
    echo "$dir"
    ;;
  env)
    [ -n "$dir" ] || { echo "usage: $0 env DIR" >&2; exit 2; }
    echo "export GLEANER_TEST_PG_URL='$(url_of "$dir")'"
    ;;
  stop)
    [ -n "$dir" ] || { echo "usage: $0 stop DIR" >&2; exit 2; }
    bin="$(find_bin)"
    if [ -d "$dir/data" ]; then
      as_owner "$bin/pg_ctl" -D "$dir/data" -m fast -w stop >/dev/null || true
    fi
    rm -rf "$dir"
    ;;
  *)
    echo "usage: $0 start [DIR] | env DIR | stop DIR" >&2
    exit 2
    ;;
esac
