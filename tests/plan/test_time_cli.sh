#!/bin/sh
# test_time_cli.sh: `frepmill time` against closed forms, its feed-only
# default, its JSON and its errors; the machine file's "dynamics" member is
# read by the other commands too.
# usage: test_time_cli.sh FREPMILL
set -u
frepmill=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { # description, condition status
    if [ "$2" -eq 0 ]; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}
near() { # value expected tolerance
    awk -v v="$1" -v e="$2" -v t="$3" 'BEGIN { d = v - e; if (d < 0) d = -d; exit !(v != "" && d <= t) }'
}

cat >"$dir/m.json" <<'M'
{"name": "test", "limits": {"x": [-500, 500]},
 "dynamics": {"axes": {"x": {"max_velocity": 100, "max_acceleration": 500},
                       "y": {"max_velocity": 100, "max_acceleration": 500},
                       "z": {"max_velocity": 100, "max_acceleration": 500}},
              "tool_change_s": 4}}
M
# 100 mm at F1200 (20 mm/s), 500 mm/s^2: 100/20 + 20/500 = 5.04 s; then a
# tool change (4 s) and 10 mm at F600 from rest to rest: 1 + 10/500 = 1.02 s
printf 'G21 G90\nG1 X100 F1200\nT2 M6\nG1 X110 F600\nM2\n' >"$dir/p.ngc"
"$frepmill" time "$dir/p.ngc" --machine "$dir/m.json" >"$dir/out" 2>"$dir/err"
check "time runs" $?
t=$(sed -n 's/.*cycle time \([0-9.]*\) s, feed-only \([0-9.]*\) s.*/\1/p' "$dir/out")
f=$(sed -n 's/.*cycle time \([0-9.]*\) s, feed-only \([0-9.]*\) s.*/\2/p' "$dir/out")
near "$t" 10.06 0.0005
check "cycle time $t s = 5.04 + 4 + 1.02" $?
near "$f" 6.0 0.0005
check "feed-only $f s = 5 + 1" $?
# the tool change's time counts to the first motion after it
grep -q "tool 0: 5.040 s, feed-only 5.000 s" "$dir/out" && grep -q "tool 2: 5.020 s, feed-only 1.000 s" "$dir/out"
check "per tool" $?
"$frepmill" time "$dir/p.ngc" --machine "$dir/m.json" --json >"$dir/j" 2>&1
check "--json runs" $?
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert abs(d['cycle_time_s']-10.06)<5e-4 and d['planned'] and d['tool_changes']==1 and d['blocks'][0]['line']==2, d" "$dir/j"
check "--json: cycle_time_s, planned, tool_changes, the longest block first" $?

# no dynamics: the feed-only time, said so
printf '{"name": "old"}\n' >"$dir/old.json"
"$frepmill" time "$dir/p.ngc" --machine "$dir/old.json" >"$dir/out" 2>&1
check "time without dynamics runs" $?
grep -q "cycle time 6.000 s, feed-only 6.000 s (no dynamics" "$dir/out"
check "without dynamics the time is feed-only and says so" $?

# a wrong member names itself; check and motions read the same file
printf '{"dynamics": {"axes": {"x": {"max_velocity": -1}}}}\n' >"$dir/bad.json"
"$frepmill" time "$dir/p.ngc" --machine "$dir/bad.json" >"$dir/out" 2>"$dir/err"
[ $? -eq 2 ] && grep -q "dynamics.axes.x.max_velocity" "$dir/err"
check "a negative velocity is refused, by name" $?
"$frepmill" motions "$dir/p.ngc" --machine "$dir/bad.json" >/dev/null 2>"$dir/err"
[ $? -eq 2 ] && grep -q "dynamics.axes.x.max_velocity" "$dir/err"
check "motions refuses it too" $?
"$frepmill" motions "$dir/p.ngc" --machine "$dir/m.json" >/dev/null 2>&1
check "motions reads a machine file with dynamics" $?
"$frepmill" time "$dir/nothere.ngc" --machine "$dir/m.json" >/dev/null 2>&1
[ $? -eq 4 ] || [ $? -eq 2 ]
check "a missing program is an error" $?
# the report's cycle_time_s beside the feed-only program_time_s: by flags
# (--machine) and from a job document whose machine carries the dynamics
printf '{"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 6, "flute_length": 20, "length": 40}]}\n' >"$dir/tools.json"
printf 'G21 G90\nT1 M6\nG1 X100 F1200\nM2\n' >"$dir/s.ngc"
"$frepmill" simulate "$dir/s.ngc" --stock box:0,20,-10,10,30,-5 --tools "$dir/tools.json" --voxel 0.5 \
    --machine "$dir/m.json" --report "$dir/r.json" >/dev/null 2>&1
check "simulate with a machine with dynamics runs" $?
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert abs(d['cycle_time_s']-5.04)<1e-6 and abs(d['program_time_s']-5.0)<1e-6 and d['cycle_time_planned'] is True, d" "$dir/r.json"
check "report: cycle_time_s 5.04 (planned) beside program_time_s 5.0 (feed-only)" $?
"$frepmill" simulate "$dir/s.ngc" --stock box:0,20,-10,10,30,-5 --tools "$dir/tools.json" --voxel 0.5 \
    --machine "$dir/old.json" --report "$dir/r0.json" >/dev/null 2>&1
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert d['cycle_time_s']==d['program_time_s'] and d['cycle_time_planned'] is False, d" "$dir/r0.json"
check "report without dynamics: cycle_time_s is the feed-only figure, not planned" $?
cat >"$dir/job.json" <<JOB
{"stock": "box:0,20,-10,10,30,-5", "voxel": 0.5, "tools": $(cat "$dir/tools.json"),
 "program": {"gcode": "G21 G90\\nT1 M6\\nG1 X100 F1200\\nM2\\n"},
 "machine": {"dynamics": {"axes": {"x": {"max_velocity": 100, "max_acceleration": 500}}}}}
JOB
"$frepmill" simulate --job "$dir/job.json" --report "$dir/rj.json" >/dev/null 2>"$dir/errj"
check "a job document with the machine's dynamics runs ($(tail -1 "$dir/errj"))" $?
python3 -c "import json,sys; d=json.load(open(sys.argv[1])); assert abs(d['cycle_time_s']-5.04)<1e-6 and d['cycle_time_planned'] is True, d" "$dir/rj.json"
check "job document: cycle_time_s 5.04" $?
exit $fail
