#!/usr/bin/env bash
# A PNG "filmstrip" of a viewer page: N evenly spaced poses of one clip in one image, the
# simulated character with its reference (ghost overlay or a second row), made headlessly with
# Debian's chromium from the page itself (#filmstrip=N), so the picture is what the page shows.
#
#   tools/filmstrip.sh PAGE.html CLIP OUT.png [--poses N] [--mode ghost|side|hidden] [--size WxH]
#
# PAGE.html: any viewer page (modskill-motion view, modskill-client rollout --html, eval.html).
set -euo pipefail
usage() { sed -n 2,8p "$0" >&2; exit 2; }
(($# >= 3)) || usage
PAGE=$1 CLIP=$2 OUT=$3
shift 3
POSES=8 MODE=ghost SIZE=1600,420
while (($#)); do
  case "$1" in
    --poses) POSES="$2"; shift 2 ;;
    --mode) MODE="$2"; shift 2 ;;
    --size) SIZE="${2/x/,}"; shift 2 ;;
    *) echo "filmstrip: unknown argument '$1'" >&2; usage ;;
  esac
done
[ -f "$PAGE" ] || { echo "filmstrip: no page '$PAGE'" >&2; exit 1; }
[[ "$POSES" =~ ^[0-9]+$ ]] && ((POSES >= 1 && POSES <= 24)) || { echo "filmstrip: --poses must be 1..24" >&2; exit 2; }
[[ "$MODE" =~ ^(ghost|side|hidden)$ ]] || { echo "filmstrip: --mode must be ghost, side or hidden" >&2; exit 2; }
[[ "$SIZE" =~ ^[0-9]+,[0-9]+$ ]] || { echo "filmstrip: --size must be WIDTHxHEIGHT" >&2; exit 2; }
OUT_DIR=$(dirname "$OUT")
[ -d "$OUT_DIR" ] || { echo "filmstrip: $OUT: the directory $OUT_DIR does not exist" >&2; exit 1; }
BROWSER=""
for candidate in chromium chromium-browser google-chrome; do
  if command -v "$candidate" >/dev/null 2>&1; then BROWSER=$(command -v "$candidate"); break; fi
done
[ -n "$BROWSER" ] || { echo "filmstrip: no chromium (apt-get install chromium; deploy/setup.sh does)" >&2; exit 1; }

WORK=$(mktemp -d "${TMPDIR:-/tmp}/modskill_filmstrip.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
URL="file://$(cd "$(dirname "$PAGE")" && pwd)/$(basename "$PAGE")#clip=$(printf %s "$CLIP" | sed 's/&/%26/g')&filmstrip=$POSES&mode=$MODE"
run_browser() {
  timeout 120 "$BROWSER" --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader --use-angle=swiftshader \
    --no-first-run --no-default-browser-check --disable-extensions --user-data-dir="$WORK/profile" \
    --window-size="$SIZE" --hide-scrollbars "$@"
}
# The page says whether it drew the strip (an unknown clip is an error in <body data-status>).
status=$(run_browser --dump-dom "$URL" 2>/dev/null | grep -o '<body[^>]*>' | head -1 || true)
if [[ "$status" != *'data-status="ok"'* ]]; then
  echo "filmstrip: the page did not draw '$CLIP': ${status:-no page}" >&2
  exit 1
fi
# Written beside OUT first, then renamed: no partial PNG on failure.
run_browser --screenshot="$WORK/strip.png" "$URL" > "$WORK/browser.log" 2>&1 || true
[ -s "$WORK/strip.png" ] || { cat "$WORK/browser.log" >&2; echo "filmstrip: no screenshot" >&2; exit 1; }
cp "$WORK/strip.png" "$OUT.tmp.$$" && mv -f "$OUT.tmp.$$" "$OUT"
echo "wrote $OUT ($POSES poses of $CLIP)"
