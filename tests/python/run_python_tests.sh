#!/usr/bin/env bash
# Runs the Python client tests (tests/python/test_*.py) against a freshly started server.
#
#   tests/python/run_python_tests.sh BUILD_DIR
#
# BUILD_DIR must hold server/modskill-server and tests/make_test_policy (the targets
# modskill-server and make_test_policy); test_viewer.py also runs client/modskill-client when it
# is there (MODSKILL_BUILD_DIR) and skips that one check otherwise. The package is imported from
# the source tree, client/python (its generated stubs are committed; test_install.py checks they match the proto).
# Exits 77 (skipped) when Debian's /usr/bin/python3 lacks grpc or numpy; otherwise with the
# unittest status.
set -u

PYTHON=/usr/bin/python3
if [ $# -ne 1 ]; then
  echo "usage: $0 BUILD_DIR" >&2
  exit 2
fi
BUILD_DIR=$(cd "$1" && pwd) || { echo "run_python_tests: no build directory '$1'" >&2; exit 2; }
REPO_DIR=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)

if ! "$PYTHON" -c 'import grpc, numpy' >/dev/null 2>&1; then
  echo "run_python_tests: SKIPPED: $PYTHON cannot import grpc and numpy (apt install python3-grpcio python3-numpy)"
  exit 77
fi

SERVER="$BUILD_DIR/server/modskill-server"
MAKE_POLICY="$BUILD_DIR/tests/make_test_policy"
PACKAGE_DIR="$REPO_DIR/client/python"
for needed in "$SERVER" "$MAKE_POLICY"; do
  if [ ! -e "$needed" ]; then
    echo "run_python_tests: missing $needed (build modskill-server make_test_policy)" >&2
    exit 1
  fi
done

WORK_DIR=$(mktemp -d "${TMPDIR:-/tmp}/modskill-python-tests.XXXXXX")
SERVER_PID=""
cleanup() {
  if [ -n "$SERVER_PID" ] && kill -0 "$SERVER_PID" 2>/dev/null; then
    kill -TERM "$SERVER_PID" 2>/dev/null
    # The server drains for up to 5 s; do not wait longer than that.
    for _ in $(seq 1 60); do
      kill -0 "$SERVER_PID" 2>/dev/null || break
      sleep 0.1
    done
    kill -KILL "$SERVER_PID" 2>/dev/null
    wait "$SERVER_PID" 2>/dev/null
  fi
  rm -rf "$WORK_DIR"
}
trap cleanup EXIT
trap 'exit 130' INT
trap 'exit 143' TERM

# A free port: bind port 0 and release it (the server takes it right after).
PORT=$("$PYTHON" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1]); s.close()')
ADDRESS="127.0.0.1:$PORT"
SERVER_LOG="$WORK_DIR/server.log"
# The test checkpoint is written to WORK_DIR: the server may read policy files there only.
"$SERVER" --port "$PORT" --bind 127.0.0.1 --checkpoint_dir "$WORK_DIR" >"$SERVER_LOG" 2>&1 &
SERVER_PID=$!

# Wait (at most ~10 s) until the server answers a Describe.
ready=0
deadline=$((SECONDS + 10))
while [ "$SECONDS" -lt "$deadline" ]; do
  if ! kill -0 "$SERVER_PID" 2>/dev/null; then
    break
  fi
  if PYTHONPATH="$PACKAGE_DIR" "$PYTHON" -c '
import sys, modskill
modskill.Client(sys.argv[1], timeout=0.5).describe()' "$ADDRESS" >/dev/null 2>&1; then
    ready=1
    break
  fi
  sleep 0.2
done
if [ "$ready" != 1 ]; then
  echo "run_python_tests: the server did not answer at $ADDRESS; its log:" >&2
  cat "$SERVER_LOG" >&2
  exit 1
fi

CHECKPOINT="$WORK_DIR/zero_policy.pt"
if ! "$MAKE_POLICY" "$CHECKPOINT"; then
  echo "run_python_tests: make_test_policy failed" >&2
  exit 1
fi

cd "$REPO_DIR"
PYTHONPATH="$PACKAGE_DIR" MODSKILL_SERVER="$ADDRESS" MODSKILL_TEST_CHECKPOINT="$CHECKPOINT" \
  MODSKILL_SERVER_BINARY="$SERVER" MODSKILL_BUILD_DIR="$BUILD_DIR" MODSKILL_TEST_WORK_DIR="$WORK_DIR" MPLBACKEND=Agg PYTHONDONTWRITEBYTECODE=1 \
  "$PYTHON" -m unittest discover -s tests/python -p 'test_*.py' -v
status=$?
if [ "$status" != 0 ]; then
  echo "run_python_tests: server log ($SERVER_LOG):" >&2
  cat "$SERVER_LOG" >&2
fi
exit "$status"
