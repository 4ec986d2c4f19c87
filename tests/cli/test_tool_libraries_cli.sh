#!/bin/sh
# test_tool_libraries_cli.sh: the tool libraries users already have, through
# `frepmill simulate` and `frepmill check` (docs/tooltable.md). Libraries
# written here from the formats' public descriptions: a Fusion 360 .json and
# the same as a .tools zip, a FreeCAD library of .fctb bits, a CAMotics
# project. Two slots, a 6 mm flat end mill 2 mm deep from (10,20) to (50,20)
# and a 6 mm ball end mill 3 mm deep from (10,32) to (50,32), remove
# (40 * 6 + pi 3^2) * 2 + 40 * pi 3^2 / 2 + (2/3) pi 3^3 = 1158.58 mm3
# (closed form) with every library, exactly what the frepmill JSON table of
# the same tools removes. A Fusion holder met by a deep plunge: its first
# segment's face, 10 mm above the tip (LB), plunged to Z-14 into a stock
# whose top is Z0, is 14 - 10 = 4 mm deep: `frepmill check` reports a
# holder contact on the plunge's line, 4 mm deep. Without a table,
# --tools-from-program takes the tools the program's comments name (Fusion's
# Haas post): the slots remove what the table's tools remove, each guessed
# field warned; a table given as well wins. The report names each tool as
# the library does, with its flutes and presets.
# usage: test_tool_libraries_cli.sh FREPMILL
set -u
frepmill=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { # description, condition status
    if [ "$2" -eq 0 ]; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}
removed() { sed -n 's/.*"removed_volume_mm3": \([0-9.e+-]*\).*/\1/p' "$1" | head -1; }
near() { # value, want, absolute tolerance
    awk -v v="$1" -v w="$2" -v t="$3" 'BEGIN { d = v - w; if (d < 0) d = -d; exit !(v != "" && d <= t) }'
}

cat >"$dir/tools.json" <<'EOF'
{"units": "mm", "tools": [
 {"number": 1, "shape": "flat", "diameter": 6, "flute_length": 20, "length": 40},
 {"number": 2, "shape": "ball", "diameter": 6, "flute_length": 20, "length": 40}]}
EOF
cat >"$dir/lib.json" <<'EOF'
{"data": [
 {"type": "flat end mill", "description": "6 mm flat", "unit": "millimeters",
  "post-process": {"number": 1, "length-offset": 1},
  "geometry": {"DC": 6, "LCF": 20, "LB": 40, "OAL": 60, "SFDM": 6, "NOF": 3},
  "holder": {"unit": "millimeters", "segments": [{"height": 10, "lower-diameter": 25, "upper-diameter": 25}]},
  "start-values": {"presets": [{"name": "alu", "n": 12000, "v_f": 1500}]}},
 {"type": "ball end mill", "description": "6 mm ball", "unit": "millimeters",
  "post-process": {"number": 2, "length-offset": 2},
  "geometry": {"DC": 6, "LCF": 20, "LB": 40}}],
 "version": 13}
EOF
python3 - "$dir" <<'EOF'
import sys, zipfile
d = sys.argv[1]
with zipfile.ZipFile(d + "/lib.tools", "w", zipfile.ZIP_DEFLATED) as z:
    z.write(d + "/lib.json", "tools.json")
EOF
mkdir -p "$dir/Tools/Bit" "$dir/Tools/Library"
cat >"$dir/Tools/Bit/flat.fctb" <<'EOF'
{"version": 2, "name": "6 mm flat", "shape": "endmill.fcstd", "attribute": {},
 "parameter": {"CuttingEdgeHeight": "20.0000 mm", "Diameter": "6.0000 mm", "Length": "40.0000 mm", "ShankDiameter": "6.0000 mm"}}
EOF
cat >"$dir/Tools/Bit/ball.fctb" <<'EOF'
{"version": 2, "name": "6 mm ball", "shape": "ballend.fcstd", "attribute": {},
 "parameter": {"CuttingEdgeHeight": "20 mm", "Diameter": "6 mm", "Length": "40 mm", "ShankDiameter": "6 mm"}}
EOF
cat >"$dir/Tools/Library/mill.fctl" <<'EOF'
{"version": 1, "tools": [{"nr": 1, "path": "flat.fctb"}, {"nr": 2, "path": "ball.fctb"}]}
EOF
cat >"$dir/project.camotics" <<'EOF'
{"units": "metric", "tools": {
  "1": {"number": 1, "units": "metric", "shape": "CYLINDRICAL", "length": 20, "diameter": 6, "description": "6 mm flat"},
  "2": {"number": 2, "units": "metric", "shape": "BALLNOSE", "length": 20, "diameter": 6, "description": "6 mm ball"}},
 "workpiece": {"automatic": true, "margin": 5}, "files": ["slots.ngc"]}
EOF
printf 'G21 G17 G90\nT1 M6\nG00 Z5\nG00 X10 Y20\nG01 Z-2 F300\nG01 X50 F600\nG00 Z5\nT2 M6\nG00 X10 Y32\nG01 Z-3 F300\nG01 X50 F600\nG00 Z5\nM2\n' >"$dir/slots.ngc"
want=$(awk 'BEGIN { pi = 3.14159265358979; printf "%.4f", (40 * 6 + pi * 9) * 2 + 40 * pi * 9 / 2 + 2 / 3 * pi * 27 }')

"$frepmill" simulate "$dir/slots.ngc" --stock box:0,0,-10,60,50,0 --tools "$dir/tools.json" \
    --voxel 0.1 --report "$dir/json.json" 2>"$dir/err"
check "the frepmill JSON table runs ($(tail -1 "$dir/err"))" $?
base=$(removed "$dir/json.json")
near "$base" "$want" "$(awk -v w="$want" 'BEGIN { print 0.005 * w }')"
check "the JSON table removes $base mm3 = closed form $want (0.5 %)" $?
for lib in lib.json lib.tools Tools/Library/mill.fctl project.camotics; do
    "$frepmill" simulate "$dir/slots.ngc" --stock box:0,0,-10,60,50,0 --tools "$dir/$lib" \
        --voxel 0.1 --report "$dir/r.json" 2>"$dir/err"
    check "$lib runs ($(tail -1 "$dir/err"))" $?
    [ -n "$base" ] && [ "$(removed "$dir/r.json")" = "$base" ]
    check "$lib removes $(removed "$dir/r.json") mm3, what the JSON table removes" $?
    [ "$lib" = lib.json ] && cp "$dir/r.json" "$dir/fusion_report.json"
done
# the report names each tool as the library does, with its presets
python3 - "$dir/fusion_report.json" <<'EOF2'
import json, sys
tools = {t["tool"]: t for t in json.load(open(sys.argv[1]))["tools"]}
t1, t2 = tools.get(1, {}), tools.get(2, {})
ok = t1.get("description") == "6 mm flat" and t1.get("flutes") == 3 \
    and t1.get("presets") == [{"name": "alu", "spindle_rpm": 12000, "cutting_speed_m_per_min": 0,
                               "feed_mm_per_min": 1500, "plunge_feed_mm_per_min": 0,
                               "feed_per_tooth_mm": 0}] \
    and t2.get("description") == "6 mm ball" and "presets" not in t2
print("report tools:", tools)
sys.exit(0 if ok else 1)
EOF2
check "the report gives each tool's description, flutes and presets as the library names them" $?

# no table: the tools the program's comments name, as Fusion's Haas post
# writes them (Fanuc dialect); the same slots remove what the table's tools
# remove (the guessed lengths are above the cuts)
printf '%%\nO1001 (SLOTS)\n(T1 D=6. CR=0. - ZMIN=-2. - FLAT END MILL)\n(T2 D=6. CR=3. - ZMIN=-3. - BALL END MILL)\nG21 G17 G90\nT1 M6\nG00 Z5.\nG00 X10. Y20.\nG01 Z-2. F300.\nG01 X50. F600.\nG00 Z5.\nT2 M6\nG00 X10. Y32.\nG01 Z-3. F300.\nG01 X50. F600.\nG00 Z5.\nM30\n%%\n' >"$dir/slots.nc"
"$frepmill" simulate "$dir/slots.nc" --dialect fanuc --stock box:0,0,-10,60,50,0 --tools-from-program \
    --voxel 0.1 --report "$dir/r.json" 2>"$dir/err"
check "--tools-from-program runs ($(tail -1 "$dir/err"))" $?
[ -n "$base" ] && [ "$(removed "$dir/r.json")" = "$base" ]
check "--tools-from-program removes $(removed "$dir/r.json") mm3, what the JSON table removes" $?
grep -q 'warning: .*slots.nc:3: T1 "FLAT END MILL" from the program.s comment, guessed: flute_length 18 mm (3 x D), length 24 mm (flute length + D), shank_diameter = D, no holder' "$dir/err"
check "each guessed field of T1 in a warning" $?
grep -q 'slots.nc:4: T2 "BALL END MILL"' "$dir/err"
check "and of T2" $?
"$frepmill" simulate "$dir/slots.nc" --dialect fanuc --stock box:0,0,-10,60,50,0 --tools-from-program \
    --tools "$dir/tools.json" --voxel 0.1 --report "$dir/r.json" 2>"$dir/err"
check "a table and --tools-from-program run" $?
grep -q 'a tool table is given, it wins' "$dir/err" && ! grep -q 'guessed' "$dir/err"
check "the explicit table wins (warned), no comment read" $?

# the holder: 10 mm of flutes and no shank (LB = LCF), a 16 mm segment 5 mm
# tall, then a 30 mm one
python3 - "$dir" <<'EOF'
import json, sys, zipfile
d = sys.argv[1]
lib = {"data": [{"type": "flat end mill", "description": "6 mm stub", "unit": "millimeters",
                 "post-process": {"number": 1, "length-offset": 1},
                 "geometry": {"DC": 6, "LCF": 10, "LB": 10, "SFDM": 6},
                 "holder": {"segments": [{"height": 5, "lower-diameter": 16, "upper-diameter": 16},
                                         {"height": 20, "lower-diameter": 30, "upper-diameter": 30}]}}],
       "version": 13}
with zipfile.ZipFile(d + "/stub.tools", "w", zipfile.ZIP_DEFLATED) as z:
    z.writestr("tools.json", json.dumps(lib))
EOF
printf 'G21 G90\nT1 M6\nS1000 M3\nG0 Z5\nG0 X25 Y25\nG1 Z-14 F100\nG0 Z30\nM2\n' >"$dir/plunge.ngc"
"$frepmill" check "$dir/plunge.ngc" --stock box:0,0,-30,50,50,0 --tools "$dir/stub.tools" \
    --voxel 0.25 >"$dir/check.json" 2>"$dir/err"
check "frepmill check with the .tools holder reports findings (exit 1)" $([ $? -eq 1 ]; echo $?)
python3 - "$dir/check.json" <<'EOF'
import json, sys
doc = json.load(open(sys.argv[1]))
found = [f for f in doc["findings"] if f["kind"] == "holder_contact"]
ok = len(found) == 1 and found[0]["line"] == 6 and found[0]["part"] == "holder" \
    and abs(found[0]["penetration_mm"] - 4.0) <= 1e-3
print("holder findings:", [(f["line"], f["part"], f["penetration_mm"]) for f in found])
sys.exit(0 if ok else 1)
EOF
check "one holder contact on line 6, 4 mm deep (14 - 10)" $?

# refusals name the file, the entry and the field
sed 's/"millimeters"/"feet"/' "$dir/lib.json" >"$dir/feet.json"
"$frepmill" simulate "$dir/slots.ngc" --stock box:0,0,-10,60,50,0 --tools "$dir/feet.json" \
    --voxel 0.1 2>"$dir/err" >/dev/null
status=$?
grep -q 'feet.json.*data\[0\] (T1 "6 mm flat"): field "unit": "feet" is not a unit' "$dir/err"
check "a wrong unit is refused naming file, entry and field (exit $status: $(tail -1 "$dir/err"))" $?
exit $fail
