#!/usr/bin/env bash
# Sets up, builds and runs the whole test suite with ctest, then each libFuzzer target for a few
# seconds on its seed corpus (fuzz/run.sh, clang build in build-fuzz/; skipped where clang or
# libFuzzer is missing). A failing test or a fuzzer crash fails the script.
set -euo pipefail
cd "$(dirname "$0")/.."
deploy/setup.sh
(cd "${MODSKILL_BUILD_DIR:-build}" && ctest --output-on-failure -j "$(nproc)" "$@")

fuzz_status=0
fuzz/run.sh "${MODSKILL_FUZZ_SECONDS:-5}" || fuzz_status=$?
if [[ ${fuzz_status} -eq 77 ]]; then
  echo "deploy/test.sh: fuzz targets skipped (no clang with libFuzzer)"
elif [[ ${fuzz_status} -ne 0 ]]; then
  echo "deploy/test.sh: a fuzz target failed (inputs in build-fuzz/artifacts/)" >&2
  exit "${fuzz_status}"
fi
