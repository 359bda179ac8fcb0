#!/bin/bash
# Clean-clone build time and test count, two commits side by side: each commit is cloned into a
# scratch directory, configured, and built with ccache off, both builds at the same time with
# -j1 each, so that both see the same machine load (the figure to compare is the ratio); then
# ctest -N counts each one's tests.
#
#   bench/clean_build_time.sh BEFORE_COMMIT [AFTER_COMMIT=HEAD]
set -euo pipefail
before=${1:?usage: bench/clean_build_time.sh BEFORE_COMMIT [AFTER_COMMIT]}
after=${2:-HEAD}
repo=$(git -C "$(dirname "$0")/.." rev-parse --show-toplevel)
scratch=$(mktemp -d)
trap 'rm -rf "$scratch"' EXIT

build_one() {  # name commit -> writes $scratch/name.result
  local name=$1 commit=$2 dir=$scratch/$1
  git clone -q "$repo" "$dir/src"
  git -C "$dir/src" checkout -q "$commit"
  cmake -S "$dir/src" -B "$dir/build" > "$dir/configure.log" 2>&1
  local start end
  start=$(date +%s)
  if ! CCACHE_DISABLE=1 make -C "$dir/build" -j1 > "$dir/build.log" 2>&1; then
    echo "$name ($commit): build failed" > "$dir.result"; tail -20 "$dir/build.log" >> "$dir.result"; return
  fi
  end=$(date +%s)
  local tests files lines
  tests=$(cd "$dir/build" && ctest -N | sed -n 's/^Total Tests: //p')
  files=$(git -C "$dir/src" ls-files '*.cc' '*.h' | wc -l)
  lines=$(git -C "$dir/src" ls-files -z '*.cc' '*.h' | (cd "$dir/src" && xargs -0 cat) | wc -l)
  echo "$name $(git -C "$dir/src" rev-parse --short HEAD): clean build $((end - start)) s (-j1, ccache off), $tests tests, $files C++ files, $lines lines" > "$dir.result"
}

build_one before "$before" &
build_one after "$after" &
wait
cat "$scratch/before.result" "$scratch/after.result"
