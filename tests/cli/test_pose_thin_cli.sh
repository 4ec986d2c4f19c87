#!/bin/sh
# test_pose_thin_cli.sh: `frepmill simulate` messages of this stop's options:
# --pose-at without --machine and with a bad value (exit 2, what is wrong),
# and the thin-wall warning on stderr for a wall of half a voxel (its figures
# are tested in tests/simulate/test_thin_wall.c).
# usage: test_pose_thin_cli.sh FREPMILL
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
printf '{"units": "mm", "rotary": [{"axis": "c", "around": [0, 0, 1], "carries": "table"}]}\n' >"$dir/m.json"
printf 'G21 G90 T1 M6 S1000 M3\nG0 X10 Y-5 Z5\nG1 Z-2 F600\nG1 Y25\nG0 Z5\nM2\n' >"$dir/slot.ngc"

"$frepmill" simulate "$dir/slot.ngc" --stock box:0,0,-10,40,20,0 --tools "$dir/tools.json" --pose-at 3 2>"$dir/err1"
[ $? -eq 2 ] && grep -q -- '--pose-at needs --machine' "$dir/err1"
check "--pose-at without --machine: exit 2, says so" $?
"$frepmill" simulate "$dir/slot.ngc" --stock box:0,0,-10,40,20,0 --tools "$dir/tools.json" \
    --machine "$dir/m.json" --pose-at soon 2>"$dir/err2"
[ $? -eq 2 ] && grep -q -- '--pose-at soon: expected seconds of program time (>= 0) or end' "$dir/err2"
check "--pose-at soon: exit 2, names the value" $?

# Two slots 0.1 mm apart at 0.2 mm voxels: a wall thinner than a voxel.
# Whether a column of voxel centres falls inside it depends on where the
# grid's centres lie, so the wall is placed in each of four quarter-voxel
# positions: at least one holds no centre.
warned=0
for off in 0.00 0.05 0.10 0.15; do
    x1=$(awk "BEGIN { print 20 + $off - 3 }")
    x2=$(awk "BEGIN { print 20 + $off + 0.1 + 3 }")
    printf 'G21 G90 T1 M6 S1000 M3\nG0 X%s Y-5 Z5\nG1 Z-5 F600\nG1 Y25\nG0 Z5\nG0 X%s Y-5\nG1 Z-5\nG1 Y25\nG0 Z5\nM2\n' \
        "$x1" "$x2" >"$dir/wall.ngc"
    "$frepmill" simulate "$dir/wall.ngc" --stock box:0,0,-10,40,20,0 --tools "$dir/tools.json" --voxel 0.2 \
        --report "$dir/w.json" 2>"$dir/err3" || { echo "FAIL: simulate wall $off"; fail=1; }
    if grep -q '^frepmill simulate: warning: 1 wall thinner than a voxel, the largest at (20\.' "$dir/err3" &&
        grep -q '"walls": 1,' "$dir/w.json"; then warned=1; fi
done
[ $warned -eq 1 ]
check "a half-voxel wall gives the warning on stderr and in the report" $?

exit $fail
