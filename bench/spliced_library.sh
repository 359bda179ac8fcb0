#!/usr/bin/env bash
# A motion library for part-level experiments (issue 13): the shipped clips plus the walk with
# the arms of other clips (modskill-motion splice), written to DIR for a server's --motions DIR.
#
#   bench/spliced_library.sh DIR [--timing clip|stretch] [SOURCE...]
#
# SOURCE: library clip names (default: punch, jog, run, kick, dance_a, jump, spinkick,
# stealthy_walk, cartwheel of DeepMimic); each becomes walk_with_<name without deepmimic_>_arms.
# --timing clip (default) plays each source's first 1.23 s at its own speed under the walk's legs.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${MODSKILL_BUILD_DIR:-build}"
(($#)) || { sed -n 2,9p "$0" >&2; exit 2; }
OUT="$1"; shift
TIMING=clip
SOURCES=()
while (($#)); do
  case "$1" in
    --timing) TIMING="$2"; shift 2 ;;
    *) SOURCES+=("$1"); shift ;;
  esac
done
((${#SOURCES[@]})) || SOURCES=(deepmimic_punch deepmimic_jog deepmimic_run deepmimic_kick deepmimic_dance_a
                               deepmimic_jump deepmimic_spinkick deepmimic_stealthy_walk deepmimic_cartwheel)
mkdir -p "$OUT"
cp data/motions/*.msclip "$OUT/"
for source in "${SOURCES[@]}"; do
  "$BUILD/server/modskill-motion" splice deepmimic_walk "$source" --parts R_Arm,L_Arm --timing "$TIMING" \
      --name "walk_with_${source#deepmimic_}_arms" --out "$OUT"
done
