#!/bin/sh
# test_budget_cli.sh: `frepmill simulate` warns on stderr and in its report
# when a swept volume's search ran out of budget (a flat tool's helix with
# --sweep-evaluations 8), and says nothing with the default budget.
# usage: test_budget_cli.sh FREPMILL
set -u
frepmill=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { # description, condition status
    if [ "$2" -eq 0 ]; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}

printf '{"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 6, "flute_length": 20, "length": 40}]}\n' \
    >"$dir/tools.json"
# line 4 is the helix
printf 'G21 G90 T1 M6 S10000 M3\nG0 X52.5 Y30 Z5\nG1 Z0 F300\nG3 X52.5 Y30 Z-10 I-2.5 J0 P4 F600\nG0 Z5\nM2\n' \
    >"$dir/helix.ngc"

"$frepmill" simulate "$dir/helix.ngc" --stock box:45,25,-12,60,35,0 --tools "$dir/tools.json" \
    --voxel 0.2 --batch -1 --sweep-evaluations 8 --report "$dir/r.json" 2>"$dir/err"
check "simulate with a small budget runs" $?
grep -q '^frepmill simulate: warning: [1-9][0-9]* voxels may be under-cut by up to [0-9.]* mm (first at line 4)' "$dir/err"
check "stderr warns with a count and the helix's line" $?
n=$(sed -n 's/.*warning: \([0-9]*\) voxels.*/\1/p' "$dir/err")
grep -q "\"voxels_uncertain\": $n," "$dir/r.json" && grep -q '"uncertain_line": 4' "$dir/r.json"
check "the report has the same count ($n) and line" $?

"$frepmill" simulate "$dir/helix.ngc" --stock box:45,25,-12,60,35,0 --tools "$dir/tools.json" \
    --voxel 0.2 --batch -1 --report "$dir/r0.json" 2>"$dir/err0"
check "simulate with the default budget runs" $?
! grep -q 'warning' "$dir/err0"
check "no warning with the default budget" $?
grep -q '"voxels_uncertain": 0,' "$dir/r0.json" && grep -q '"uncertain_line": null' "$dir/r0.json"
check "the report counts 0" $?

"$frepmill" simulate "$dir/helix.ngc" --stock box:45,25,-12,60,35,0 --tools "$dir/tools.json" \
    --sweep-evaluations 0 2>"$dir/err1"
[ $? -eq 2 ] && grep -q -- '--sweep-evaluations 0: not a valid value' "$dir/err1"
check "--sweep-evaluations 0 is refused" $?
exit $fail
