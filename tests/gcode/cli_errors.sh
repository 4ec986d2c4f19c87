#!/bin/sh
# cli_errors.sh: `frepmill motions` prints file:line:column: message on stderr
# and exits 2 on a bad program; prints JSON lines and exits 0 on a good one.
set -u
FREPMILL=$1
PROGRAMS=$2
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
printf 'G0 X1\nG0 Y[1/0]\n' > "$tmp/bad.ngc"
"$FREPMILL" motions "$tmp/bad.ngc" > "$tmp/out" 2> "$tmp/err"
rc=$?
[ $rc -eq 2 ] || { echo "expected exit 2, got $rc"; exit 1; }
grep -q "bad.ngc:2:7: '/': division by zero" "$tmp/err" || { cat "$tmp/err"; exit 1; }
"$FREPMILL" motions "$PROGRAMS/arcs_xy.ngc" --tools "$PROGRAMS/tools.tbl" > "$tmp/out" || exit 1
grep -q '"kind":"arc"' "$tmp/out" || exit 1
grep -q '"center":\[' "$tmp/out" || exit 1
"$FREPMILL" motions "$tmp/missing.ngc" 2> "$tmp/err"
[ $? -eq 4 ] || { echo "expected exit 4 for a missing file"; exit 1; }
echo "cli ok"
