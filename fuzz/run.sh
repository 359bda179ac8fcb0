#!/usr/bin/env bash
# Builds the libFuzzer targets with clang in build-fuzz/ and runs each for SECONDS (default 10)
# on a copy of its committed seed corpus (fuzz/corpus/<target>/ stays as it is), printing
# libFuzzer's final stats (executions, coverage). Exits 1 when a target crashes (the crashing
# input is left in build-fuzz/artifacts/), 77 when clang or libFuzzer is not installed.
#
#   fuzz/run.sh [SECONDS] [TARGET...]
#     TARGET: bvh deepmimic npz msclip policy_spec simulate_request (default: all)
#
# deploy/test.sh (CI) runs it for 5 s a target; for the 10-minute runs of fuzz/RESULTS.md:
# fuzz/run.sh 600.
set -euo pipefail

seconds="${1:-10}"
shift || true
targets=("$@")
[[ ${#targets[@]} -gt 0 ]] || targets=(bvh deepmimic npz msclip policy_spec simulate_request)
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${repo}/build-fuzz"
jobs="${FUZZ_BUILD_JOBS:-2}"

if ! command -v clang++ >/dev/null ||
   ! echo 'extern "C" int LLVMFuzzerTestOneInput(const char*, unsigned long) { return 0; }' |
     clang++ -x c++ -fsanitize=fuzzer -o /dev/null - 2>/dev/null; then
  echo "fuzz/run.sh: clang++ with libFuzzer is missing (apt-get install clang libfuzzer-14-dev)" >&2
  exit 77
fi
# MODSKILL_UNITY_BUILD=ON (.ci/run): a unity build, as in deploy/setup.sh.
unity=()
if [[ -n "${MODSKILL_UNITY_BUILD:-}" ]]; then unity=(-DCMAKE_UNITY_BUILD="${MODSKILL_UNITY_BUILD}"); fi
CC=clang CXX=clang++ cmake -S "${repo}" -B "${build}" -DCMAKE_BUILD_TYPE=RelWithDebInfo -DMODSKILL_FUZZ=ON \
  -DMODSKILL_BUILD_TESTS=OFF -DMODSKILL_BUILD_BENCH=OFF "${unity[@]}" >/dev/null
cmake --build "${build}" -j"${jobs}" --target "${targets[@]/%/_fuzzer}"

mkdir -p "${build}/artifacts"
work="$(mktemp -d)"
trap 'rm -rf "${work}"' EXIT
failed=0
for target in "${targets[@]}"; do
  corpus="${work}/${target}"
  cp -r "${repo}/fuzz/corpus/${target}" "${corpus}"
  echo "== ${target}_fuzzer, ${seconds} s"
  # rss_limit: the importers' own bounds keep every input far below it, so an unbounded
  # allocation shows up as a crash.
  if ! "${build}/fuzz/${target}_fuzzer" "${corpus}" -max_total_time="${seconds}" \
      -print_final_stats=1 -rss_limit_mb=2048 -max_len=65536 -timeout=30 \
      -artifact_prefix="${build}/artifacts/${target}-" 2>"${work}/${target}.log"; then
    failed=1
    tail -n 40 "${work}/${target}.log"
  fi
  grep -E "^#[0-9]+.*(DONE|pulse)" "${work}/${target}.log" | tail -n 1 || true
  grep -E "^stat::(number_of_executed_units|peak_rss_mb|new_units_added)" "${work}/${target}.log" || true
done
exit "${failed}"
