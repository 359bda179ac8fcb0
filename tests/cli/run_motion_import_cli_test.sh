#!/usr/bin/env bash
# modskill-motion import and inspect as a user runs them: the DeepMimic walk on the default
# (window) floor and on `--floor stance`, inspect's stance-feet line, and a bad --floor refused
# before anything is written.  Usage: run_motion_import_cli_test.sh BUILD_DIR
set -euo pipefail
motion="$1/server/modskill-motion"
walk="$(dirname "$0")/../../data/motions/source/deepmimic/humanoid3d_walk.txt"
out="$(mktemp -d)"
trap 'rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }
clearance() { sed -n 's/.*floor clearance mean \([0-9.]*\) .*/\1/p' "$1"; }

"$motion" import "$walk" --out "$out/window" > /dev/null
"$motion" import "$walk" --out "$out/stance" --floor stance > /dev/null
"$motion" inspect "$out/window/deepmimic_walk.msclip" > "$out/window.txt"
"$motion" inspect "$out/stance/deepmimic_walk.msclip" > "$out/stance.txt"
grep -q "stance feet .*deg (toe up > 0)" "$out/window.txt" || fail "no stance-feet line: $(cat "$out/window.txt")"
# The window floor leaves the walk 12 mm up on average; pinned to the stance foot, about 1 mm.
/usr/bin/env awk -v w="$(clearance "$out/window.txt")" -v s="$(clearance "$out/stance.txt")" \
    'BEGIN { exit !(w >= 0.008 && s <= 0.003) }' || fail "clearance window $(clearance "$out/window.txt"), stance $(clearance "$out/stance.txt")"
# inspect takes the same flag: the source file inspected on the stance floor matches the import.
"$motion" inspect "$walk" --floor stance > "$out/source.txt"
[ "$(clearance "$out/source.txt")" = "$(clearance "$out/stance.txt")" ] || fail "inspect --floor stance differs from import"

if "$motion" import "$walk" --out "$out/bad" --floor flat 2> "$out/err.txt"; then fail "--floor flat accepted"; fi
grep -q -- "--floor 'flat': expected window or stance" "$out/err.txt" || fail "message: $(cat "$out/err.txt")"
[ ! -e "$out/bad" ] || fail "--floor flat created $(ls -A "$out/bad")"
echo "modskill-motion import --floor: ok"
