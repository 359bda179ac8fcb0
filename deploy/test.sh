#!/usr/bin/env bash
# Sets up, builds and runs the whole test suite with ctest.
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/setup.sh
cd "${MODSKILL_BUILD_DIR:-build}"
ctest --output-on-failure -j "$(nproc)" "$@"
