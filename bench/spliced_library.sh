#!/usr/bin/env bash
# A motion library for part-level experiments (issue 13): the shipped clips plus one base clip
# with the arms of other clips (modskill-motion splice), written to DIR for a server's
# --motions DIR.
#
#   bench/spliced_library.sh DIR [--base deepmimic_walk] [--timing clip|stretch] [SOURCE...]
#
# SOURCE: library clip names (default: punch, jog, run, kick, dance_a, jump, spinkick,
# stealthy_walk, cartwheel of DeepMimic; the base itself is skipped); each becomes
# <base>_with_<source>_arms, without the "deepmimic_" prefixes (walk_with_punch_arms).
# --timing clip (default) plays each source from its start at its own speed under the base's
# legs (held at its last frame if shorter); stretch plays its whole duration over the base's.
# Run it again with another --base into the same DIR to add that base's splices.
set -euo pipefail
cd "$(dirname "$0")/.."
BUILD="${MODSKILL_BUILD_DIR:-build}"
(($#)) || { sed -n 2,13p "$0" >&2; exit 2; }
OUT="$1"; shift
BASE=deepmimic_walk TIMING=clip
SOURCES=()
while (($#)); do
  case "$1" in
    --base) BASE="$2"; shift 2 ;;
    --timing) TIMING="$2"; shift 2 ;;
    -*) echo "error: unknown flag '$1'" >&2; exit 2 ;;
    *) SOURCES+=("$1"); shift ;;
  esac
done
((${#SOURCES[@]})) || SOURCES=(deepmimic_punch deepmimic_jog deepmimic_run deepmimic_kick deepmimic_dance_a
                               deepmimic_jump deepmimic_spinkick deepmimic_stealthy_walk deepmimic_cartwheel)
mkdir -p "$OUT"
cp -n data/motions/*.msclip "$OUT/"
for source in "${SOURCES[@]}"; do
  [ "$source" != "$BASE" ] || continue
  "$BUILD/server/modskill-motion" splice "$BASE" "$source" --parts R_Arm,L_Arm --timing "$TIMING" \
      --name "${BASE#deepmimic_}_with_${source#deepmimic_}_arms" --out "$OUT"
done
