#!/usr/bin/env bash
# Viewer page size and load time as the clip count grows: modskill-motion view writes one page
# holding the shipped library REPEATS times over (20 clips each), then headless Chromium (software
# WebGL, as in CI) opens it LOADS times at the first and at the last clip and reports the page's
# own load time (<body data-load-ms>, from script start to the first drawn frame). Medians.
# A last row is one 10-minute clip: CMU take 01_01 (22.9 s) repeated to 600 s as a BVH.
#
#   bench/viewer_page_bench.sh [BUILD_DIR=build] [REPEATS...=1 5 15]
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="${1:-$repo/build}"
shift || true
repeats=("$@")
[[ ${#repeats[@]} -gt 0 ]] || repeats=(1 5 15)
loads=3
browser_bin=$(command -v chromium || command -v chromium-browser) || { echo "no chromium (apt-get install chromium)"; exit 77; }
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
mapfile -t library < <(cd "$repo/data/motions" && ls *.msclip | sed 's/\.msclip$//')

load_ms() {  # page clip -> the page's data-load-ms
  timeout 120 "$browser_bin" --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader \
    --use-angle=swiftshader --no-first-run --user-data-dir="$work/profile" --window-size=900,600 \
    --dump-dom "file://$1#clip=$2" 2>/dev/null | grep -o 'data-load-ms="[0-9.]*"' | grep -o '[0-9.]*'
}
median() { sort -n | awk '{v[NR]=$1} END {print v[int((NR+1)/2)]}'; }

printf '| clips | page size (MB) | write (s) | load, first clip (ms) | load, last clip (ms) |\n|---|---|---|---|---|\n'
for r in "${repeats[@]}"; do
  clips=()
  for ((i = 0; i < r; ++i)); do clips+=("${library[@]}"); done
  page="$work/page_$r.html"
  start=$(date +%s.%N)
  "$build/server/modskill-motion" view "${clips[@]}" --html "$page" > /dev/null
  end=$(date +%s.%N)
  size=$(stat -c %s "$page")
  first=$(for ((k = 0; k < loads; ++k)); do load_ms "$page" 0; done | median)
  last=$(for ((k = 0; k < loads; ++k)); do load_ms "$page" $((${#clips[@]} - 1)); done | median)
  printf '| %d | %.1f | %.2f | %s | %s |\n' "${#clips[@]}" "$(echo "$size / 1048576" | bc -l)" \
    "$(echo "$end - $start" | bc -l)" "$first" "$last"
done

# One 10-minute clip: the take's motion lines repeated to 72,000 frames at 120 fps (the importer
# resamples to 30 fps: 18,000 frames), under the importer's 600 s limit.
source_bvh="$repo/data/motions/source/cmu/01_01.bvh"
long_bvh="$work/cmu_01_01_10min.bvh"
awk -v want=72000 '
  /^Frames:/ { print "Frames: " want; next }
  /^Frame Time:/ { print; motion = 1; next }
  !motion { print; next }
  { lines[n++] = $0 }
  END { for (i = 0; i < want; ++i) print lines[i % n] }' "$source_bvh" > "$long_bvh"
page="$work/page_long.html"
start=$(date +%s.%N)
"$build/server/modskill-motion" view "$long_bvh" --html "$page" > /dev/null
end=$(date +%s.%N)
size=$(stat -c %s "$page")
first=$(for ((k = 0; k < loads; ++k)); do load_ms "$page" 0; done | median)
printf '| 1 (10 min, 18,000 frames) | %.1f | %.2f | %s | - |\n' "$(echo "$size / 1048576" | bc -l)" \
  "$(echo "$end - $start" | bc -l)" "$first"
