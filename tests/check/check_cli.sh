#!/bin/sh
# check_cli.sh FREPMILL: `frepmill check` end to end: exit statuses, the
# findings JSON, and two clean real programs (the demo and LinuxCNC's
# 3D_Chips.ngc; without LinuxCNC's examples the test skips, or fails under
# CI=true: tests/support/skip.sh).
set -u
FM="$1"
. "$(dirname "$0")/../support/skip.sh"
TMP=$(mktemp -d)
trap 'rm -rf "$TMP"' EXIT
fail=0
expect() { # expected-status description command...
    want=$1; what=$2; shift 2
    "$@" > "$TMP/out.json" 2> "$TMP/err.txt"
    got=$?
    if [ "$got" != "$want" ]; then
        echo "FAIL: $what: exit $got, expected $want"; cat "$TMP/err.txt"; fail=1
    fi
}
# a rapid through the stock: one error at line 6
expect 1 "rapid through" "$FM" check rapid_through.ngc --stock box:0,0,-20,50,50,0 --tools tools.json --machine machine.json
grep -q '"kind": "rapid_into_stock"' "$TMP/out.json" || { echo "FAIL: no rapid_into_stock"; fail=1; }
grep -q '"line": 6' "$TMP/out.json" || { echo "FAIL: not at line 6"; cat "$TMP/out.json"; fail=1; }
# --report writes the file instead
expect 1 "report file" "$FM" check rapid_through.ngc --stock box:0,0,-20,50,50,0 --tools tools.json --report "$TMP/r.json"
grep -q '"severity": "error"' "$TMP/r.json" || { echo "FAIL: report file"; fail=1; }
# bad input: 2
expect 2 "no stock" "$FM" check rapid_through.ngc --tools tools.json
echo '{"limits": {"w": [0, 1]}}' > "$TMP/bad.json"
expect 2 "bad machine" "$FM" check rapid_through.ngc --stock box:0,0,-20,50,50,0 --tools tools.json --machine "$TMP/bad.json"
grep -q 'limits.w' "$TMP/err.txt" || { echo "FAIL: machine error names the member"; fail=1; }
echo 'clamp(x[3], a[1]) { clamp = x[1] +; }' > "$TMP/bad.hf"
expect 2 "bad fixture" "$FM" check rapid_through.ngc --stock box:0,0,-20,50,50,0 --tools tools.json --fixture "$TMP/bad.hf"
# a fixture file that cannot be read: I/O, 4
expect 4 "missing fixture" "$FM" check rapid_through.ngc --stock box:0,0,-20,50,50,0 --tools tools.json --fixture "$TMP/none.hf"
# resource limit: 3
expect 3 "budget" "$FM" check rapid_through.ngc --stock box:0,0,-20,50,50,0 --tools tools.json --voxel 0.0001
# the demo is clean
expect 0 "demo" "$FM" check ../../deploy/demo/pocket.ngc --stock box:0,0,-30,100,60,0 --tools ../../deploy/demo/tools.json
grep -q '"findings": \[\]' "$TMP/out.json" || { echo "FAIL: demo findings"; cat "$TMP/out.json"; fail=1; }
CHIPS=/usr/share/linuxcnc/ncfiles/3D_Chips.ngc
if [ ! -f "$CHIPS" ]; then
    [ $fail = 0 ] && skip "$CHIPS is absent (LinuxCNC's examples come with linuxcnc-uspace)"
    exit 1
fi
expect 0 "3D_Chips" "$FM" check "$CHIPS" --stock box:-50,-50,-50,50,50,0 --tools chips_tools.json
cat "$TMP/err.txt"
exit $fail
