#!/usr/bin/env bash
# The main job: set up and build, start a simulation server on the shipped motion library,
# then drive a batch of envs through it from the command-line client and print throughput.
# Extra arguments go to `modskill-client simulate`.
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/setup.sh
BUILD="${MODSKILL_BUILD_DIR:-build}"
PORT="${MODSKILL_PORT:-$(/usr/bin/python3 -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')}"
"$BUILD/server/modskill-server" --port "$PORT" --threads "$(nproc)" &
SERVER_PID=$!
trap 'kill -TERM $SERVER_PID 2>/dev/null; wait $SERVER_PID 2>/dev/null || true' EXIT
"$BUILD/client/modskill-client" --server "127.0.0.1:$PORT" --timeout_s 20 describe
"$BUILD/client/modskill-client" --server "127.0.0.1:$PORT" motions
"$BUILD/client/modskill-client" --server "127.0.0.1:$PORT" simulate --envs 256 --steps 200 --actions random "$@"
"$BUILD/client/modskill-client" --server "127.0.0.1:$PORT" stats
