#!/bin/sh
# test_job_cli.sh: `frepmill simulate --job FILE` reads the job document of
# POST /v1/jobs (daemon/runner/job_doc.h) with the same parser. One slot, a
# 6 mm flat end mill 2 mm deep from (10,20) to (50,20), removes
# (40 * 6 + pi * 3^2) * 2 = 536.55 mm3 (closed form) from a document with a
# box stock (without the check: options.check false), exactly what the same
# job given by flags removes; a document with an inline HyperFun block
# (written to a private folder, removed after; the check on by default, so
# the report has findings) removes exactly what the same .hf file does. Flags the document gives are refused beside --job, and a JSON syntax
# error names the file, line and column.
# usage: test_job_cli.sh FREPMILL
set -u
frepmill=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { # description, condition status
    if [ "$2" -eq 0 ]; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}
removed() { sed -n 's/.*"removed_volume_mm3": \([0-9.e+-]*\).*/\1/p' "$1" | head -1; }
near() { # value, want, relative tolerance
    awk -v v="$1" -v w="$2" -v t="$3" 'BEGIN { d = v - w; if (d < 0) d = -d; exit !(v != "" && d <= t * w) }'
}

tools='{"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 6, "flute_length": 20, "length": 40}]}'
printf '%s\n' "$tools" >"$dir/tools.json"
program='G21 G17 G90\nT1 M6\nG00 Z5\nG00 X10 Y20\nG01 Z-2 F300\nG01 X50 F600\nG00 Z5\nM2\n'
printf "$program" >"$dir/slot.ngc"
want=$(awk 'BEGIN { printf "%.4f", (40 * 6 + 3.14159265358979 * 9) * 2 }')

"$frepmill" simulate "$dir/slot.ngc" --stock box:0,0,-10,60,40,0 --tools "$dir/tools.json" \
    --voxel 0.1 --report "$dir/flags.json" 2>"$dir/err0"
check "the job by flags runs" $?

cat >"$dir/job.json" <<JOB
{"stock": "box:0,0,-10,60,40,0", "voxel": 0.1, "tools": $tools,
 "program": {"gcode": "$(printf "$program" | sed 's/$/\\n/' | tr -d '\n')"},
 "options": {"check": false}}
JOB
"$frepmill" simulate --job "$dir/job.json" --report "$dir/r1.json" 2>"$dir/err1"
check "--job with a box stock runs ($(cat "$dir/err1" | tail -1))" $?
r1=$(removed "$dir/r1.json")
near "$r1" "$want" 0.005
check "--job removed $r1 mm3 = closed form $want (0.5 %)" $?
[ "$r1" = "$(removed "$dir/flags.json")" ]
check "and exactly what the flags' job removed ($(removed "$dir/flags.json"))" $?
! grep -q '"findings"' "$dir/r1.json"
check "options.check false: no check, no findings in the report" $?

hf='block(x[3], a[1])\n{\n  array corner[3];\n  corner = [0, 0, -10];\n  block = hfBlock(x, corner, 60, 40, 10);\n}\n'
printf "$hf" >"$dir/block.hf"
"$frepmill" simulate "$dir/slot.ngc" --stock "$dir/block.hf" --tools "$dir/tools.json" \
    --voxel 0.2 --check --report "$dir/flags2.json" 2>"$dir/err6"
check "the HyperFun stock's job by flags runs" $?
cat >"$dir/job2.json" <<JOB
{"stock": {"hyperfun": "$hf"},
 "voxel": 0.2, "tools": $tools,
 "program": {"gcode": "$(printf "$program" | sed 's/$/\\n/' | tr -d '\n')"}}
JOB
mkdir "$dir/tmp"
TMPDIR="$dir/tmp" "$frepmill" simulate --job "$dir/job2.json" --report "$dir/r2.json" 2>"$dir/err2"
check "--job with an inline HyperFun stock runs ($(tail -1 "$dir/err2"))" $?
r2=$(removed "$dir/r2.json")
[ -n "$r2" ] && [ "$r2" = "$(removed "$dir/flags2.json")" ]
check "it removed what the same .hf file removes by flags ($r2 = $(removed "$dir/flags2.json") mm3)" $?
grep -q '"findings": \[' "$dir/r2.json"
check "the check runs by default (the report has findings)" $?
[ -z "$(ls -A "$dir/tmp")" ]
check "its private model folder is removed" $?

"$frepmill" simulate --job "$dir/job.json" --stock box:0,0,-10,60,40,0 2>"$dir/err3"
[ $? -eq 2 ] && grep -q -- '--stock: the job file gives it' "$dir/err3"
check "--stock beside --job is refused ($(cat "$dir/err3"))" $?
"$frepmill" simulate "$dir/slot.ngc" --job "$dir/job.json" 2>"$dir/err4"
[ $? -eq 2 ] && grep -q -- 'PROGRAM: the job file gives it' "$dir/err4"
check "a PROGRAM beside --job is refused" $?

printf '{"stock": "box:0,0,-10,60,40,0",\n "voxel": 0.1,,\n}\n' >"$dir/bad.json"
"$frepmill" simulate --job "$dir/bad.json" 2>"$dir/err5"
[ $? -eq 2 ] && grep -q "bad.json:2:" "$dir/err5"
check "a syntax error names the file and line ($(cat "$dir/err5"))" $?
exit $fail
