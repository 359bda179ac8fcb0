#!/usr/bin/env bash
# The HTML viewer in a real browser. First, without one, modskill-motion view's bad input (an
# unknown clip, a missing file, an unwritable --html) must be an error naming it with no page
# left behind. Then it writes a page for shipped clips (a library name and an .msclip file),
# opens it from disk in headless Chromium (no server, no network) at two frames, and checks
# that the canvas is not blank, that the character moved between the frames
# (compare_screenshots.py), that the page drew the frame it was asked for and logged no
# JavaScript error (<body data-status="ok">), and, as a control, that an error is seen. Last, a
# rollout page from modskill-client against a live server (both characters drawn) and its
# filmstrip PNG (tools/filmstrip.sh).
#
#   tests/viewer/run_viewer_browser_test.sh BUILD_DIR
#
# Exits 77 (skipped) when no Chromium is installed (deploy/setup.sh installs Debian's chromium)
# or /usr/bin/python3 lacks matplotlib.
set -u

PYTHON=/usr/bin/python3
if [ $# -ne 1 ]; then
  echo "usage: $0 BUILD_DIR" >&2
  exit 2
fi
BUILD_DIR=$(cd "$1" && pwd) || { echo "viewer_browser_test: no build directory '$1'" >&2; exit 2; }
HERE=$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)
MOTION="$BUILD_DIR/server/modskill-motion"

if [ ! -x "$MOTION" ]; then
  echo "viewer_browser_test: $MOTION missing (build the modskill-motion target)" >&2
  exit 2
fi

WORK=$(mktemp -d "${TMPDIR:-/tmp}/modskill_viewer_test.XXXXXX")
trap 'rm -rf "$WORK"' EXIT
REPO_DIR=$(cd "$HERE/../.." && pwd)

# Bad input, before any browser: a clear error naming it, and no page left behind.
cli_failures=0
expect_error() {  # expect_error WHAT_THE_MESSAGE_NAMES OUT.html ARGS...
  local named=$1 out=$2
  shift 2
  if "$MOTION" view "$@" --html "$out" > "$WORK/cli.log" 2>&1; then
    echo "FAIL: modskill-motion view $* succeeded"; cli_failures=$((cli_failures + 1))
  elif ! grep -qF -- "$named" "$WORK/cli.log"; then
    echo "FAIL: the error does not name '$named':"; cat "$WORK/cli.log"; cli_failures=$((cli_failures + 1))
  elif [ -e "$out" ]; then
    echo "FAIL: $out written despite the error"; cli_failures=$((cli_failures + 1))
  fi
}
expect_error no_such_clip "$WORK/bad1.html" deepmimic_walk no_such_clip
expect_error "$WORK/missing.bvh" "$WORK/bad2.html" "$WORK/missing.bvh"
expect_error "$WORK/no_dir/page.html" "$WORK/no_dir/page.html" deepmimic_walk
if ((cli_failures)); then exit 1; fi

PAGE="$WORK/walk.html"
# A library clip by name and a clip file, in one page.
"$MOTION" view deepmimic_walk "$REPO_DIR/data/motions/deepmimic_jump.msclip" --html "$PAGE" \
  || { echo "FAIL: modskill-motion view"; exit 1; }

BROWSER=""
for candidate in chromium chromium-browser google-chrome; do
  if command -v "$candidate" >/dev/null 2>&1; then BROWSER=$(command -v "$candidate"); break; fi
done
if [ -z "$BROWSER" ]; then
  echo "viewer_browser_test: SKIPPED: no chromium found (apt-get install chromium; deploy/setup.sh does)"
  exit 77
fi
if ! "$PYTHON" -c 'import matplotlib.image, numpy' >/dev/null 2>&1; then
  echo "viewer_browser_test: SKIPPED: $PYTHON cannot import matplotlib (apt-get install python3-matplotlib)"
  exit 77
fi
# A profile of our own per run, software WebGL (no GPU in CI), no first-run work.
browser() {
  timeout 120 "$BROWSER" --headless --no-sandbox --disable-gpu --enable-unsafe-swiftshader \
    --use-angle=swiftshader --no-first-run --no-default-browser-check --disable-extensions \
    --user-data-dir="$WORK/profile" --window-size=900,600 --enable-logging=stderr --v=0 "$@"
}

failures=0
fail() { echo "FAIL: $*"; failures=$((failures + 1)); }

for frame in 0 30; do
  browser --screenshot="$WORK/frame$frame.png" "file://$PAGE#clip=deepmimic_walk&frame=$frame" \
    > "$WORK/screenshot$frame.log" 2>&1
  [ -s "$WORK/frame$frame.png" ] || { cat "$WORK/screenshot$frame.log"; fail "no screenshot of frame $frame"; }
  if grep -E 'Uncaught|CONSOLE.*(Error|error)' "$WORK/screenshot$frame.log"; then
    fail "frame $frame: the page logged a JavaScript error"
  fi
done
if [ -s "$WORK/frame0.png" ] && [ -s "$WORK/frame30.png" ]; then
  "$PYTHON" "$HERE/compare_screenshots.py" "$WORK/frame0.png" "$WORK/frame30.png" || fail "screenshots"
fi

body_tag() { browser --dump-dom "$1" 2>"$WORK/dom.log" | grep -o '<body[^>]*>' | head -1; }

tag=$(body_tag "file://$PAGE#clip=deepmimic_walk&frame=30")
echo "frame 30: $tag"
[[ "$tag" == *'data-status="ok"'* ]] || fail "frame 30: status not ok: $tag"
[[ "$tag" == *'data-clip="deepmimic_walk"'* && "$tag" == *'data-frame="30"'* ]] || fail "frame 30 not shown: $tag"

# The control: a clip the page does not hold must show as an error, or the checks above prove nothing.
tag=$(body_tag "file://$PAGE#clip=no_such_clip")
echo "unknown clip: $tag"
[[ "$tag" == *'data-status="error: '*'no_such_clip'* ]] || fail "an error in the page went unseen: $tag"

# A rollout's page (modskill-client rollout --html against a live server, the shipped walk
# policy): both characters drawn and moving, and its filmstrip (tools/filmstrip.sh).
SERVER="$BUILD_DIR/server/modskill-server" CLIENT="$BUILD_DIR/client/modskill-client"
if [ -x "$SERVER" ] && [ -x "$CLIENT" ]; then
  port=$("$PYTHON" -c 'import socket; s = socket.socket(); s.bind(("127.0.0.1", 0)); print(s.getsockname()[1])')
  "$SERVER" --port "$port" --bind 127.0.0.1 --threads 1 --no_generative > "$WORK/server.log" 2>&1 &
  server_pid=$!
  trap 'kill -TERM $server_pid 2>/dev/null; wait $server_pid 2>/dev/null; rm -rf "$WORK"' EXIT
  ROLLOUT="$WORK/rollout.html"
  if ! "$CLIENT" --server "127.0.0.1:$port" --timeout_s 30 rollout --clip deepmimic_walk \
      --checkpoint "$REPO_DIR/data/policies/walk_small/policy.pt" --html "$ROLLOUT" > "$WORK/rollout.log" 2>&1; then
    cat "$WORK/rollout.log"; fail "modskill-client rollout --html"
  else
    for frame in 0 30; do
      browser --screenshot="$WORK/rollout$frame.png" "file://$ROLLOUT#clip=deepmimic_walk&frame=$frame&mode=side" \
        > "$WORK/rollout_screenshot$frame.log" 2>&1
    done
    "$PYTHON" "$HERE/compare_screenshots.py" --simulated "$WORK/rollout0.png" "$WORK/rollout30.png" \
      || fail "rollout page screenshots"
    tag=$(body_tag "file://$ROLLOUT#clip=deepmimic_walk&frame=30")
    [[ "$tag" == *'data-status="ok"'* ]] || fail "rollout page: status not ok: $tag"
    if "$REPO_DIR/tools/filmstrip.sh" "$ROLLOUT" deepmimic_walk "$WORK/strip.png" --poses 6 --mode side \
        > "$WORK/filmstrip.log" 2>&1; then
      "$PYTHON" "$HERE/check_filmstrip.py" "$WORK/strip.png" || fail "filmstrip"
    else
      cat "$WORK/filmstrip.log"; fail "tools/filmstrip.sh"
    fi
    # The control: a clip the page does not hold is an error, and no PNG is written.
    if "$REPO_DIR/tools/filmstrip.sh" "$ROLLOUT" no_such_clip "$WORK/bad.png" > "$WORK/bad.log" 2>&1 \
        || [ -e "$WORK/bad.png" ] || ! grep -q no_such_clip "$WORK/bad.log"; then
      cat "$WORK/bad.log"; fail "filmstrip of an unknown clip was not a clear error"
    fi
  fi
else
  fail "missing $SERVER or $CLIENT (build the modskill-server and modskill-client targets)"
fi

if ((failures)); then
  echo "viewer_browser_test: $failures failure(s); the page and screenshots were in $WORK"
  exit 1
fi
echo "viewer_browser_test: OK"
