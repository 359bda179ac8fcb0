#!/usr/bin/env bash
# modskill-server's physics flags as a user gives them: a bad --pd_gain_scale, --pd_mode or --substeps is
# refused with exit 2 and a message naming the flag before anything listens; a good one is
# announced in the server's listening line.  Usage: run_server_flags_cli_test.sh BUILD_DIR
set -euo pipefail
server="$1/server/modskill-server"
out="$(mktemp -d)"
pid=""
trap '[ -n "$pid" ] && kill "$pid" 2> /dev/null; rm -rf "$out"' EXIT
fail() { echo "FAIL: $*" >&2; exit 1; }

for bad in 0 -1 101 nan inf; do
  rc=0
  timeout 20 "$server" --port 0 --pd_gain_scale "$bad" > "$out/log.txt" 2>&1 || rc=$?
  [ "$rc" = 2 ] || fail "--pd_gain_scale $bad: exit $rc, log: $(cat "$out/log.txt")"
  grep -q -- "--pd_gain_scale: .* must be finite, in (0, 100]" "$out/log.txt" || fail "message: $(cat "$out/log.txt")"
  grep -q "listening" "$out/log.txt" && fail "--pd_gain_scale $bad: the server listened"
done
rc=0
timeout 20 "$server" --port 0 --pd_mode explicit > "$out/log.txt" 2>&1 || rc=$?
[ "$rc" = 2 ] && grep -q "pd_mode" "$out/log.txt" || fail "--pd_mode explicit: exit $rc, log: $(cat "$out/log.txt")"
for bad in 0 -2 101; do
  rc=0
  timeout 20 "$server" --port 0 --substeps "$bad" > "$out/log.txt" 2>&1 || rc=$?
  [ "$rc" = 2 ] || fail "--substeps $bad: exit $rc, log: $(cat "$out/log.txt")"
  grep -q -- "--substeps: $bad outside \[1, 100\]" "$out/log.txt" || fail "message: $(cat "$out/log.txt")"
done

"$server" --port 0 --threads 1 --pd_gain_scale 0.6 --substeps 2 > "$out/log.txt" 2>&1 &
pid=$!
for _ in $(seq 100); do grep -q "listening on" "$out/log.txt" && break; sleep 0.2; done
grep -q "position_implicit PD at 0.6 x PHC's gains, 60 Hz physics" "$out/log.txt" || fail "listening line: $(cat "$out/log.txt")"
echo "modskill-server physics flags: ok"
