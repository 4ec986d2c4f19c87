#!/bin/sh
# test_mesh_cli.sh: `frepmill mesh` on models whose volume is known in
# closed form, and its errors.
# usage: test_mesh_cli.sh FREPMILL
set -u
frepmill=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
fail=0
check() { # description, condition status
    if [ "$2" -eq 0 ]; then echo "ok: $1"; else echo "FAIL: $1"; fail=1; fi
}

# A HyperFun sphere of radius 10 (R^2 - r^2, not a distance: the command
# normalizes it) and a block cut by the bounds.
printf 'sphere(x[3], a[1])\n{\n  array c[3];\n  c = [1, 2, 3];\n  sphere = hfSphere(x, c, 10);\n}\n' >"$dir/sphere.hf"
"$frepmill" mesh "$dir/sphere.hf" --bounds -15,-15,-15,15,15,15 --voxel 0.2 --out "$dir/s.stl" \
    --png "$dir/s.png" 2>"$dir/err"
check "sphere meshes" $?
vol=$(sed -n 's/.*volume \([0-9.]*\) mm3.*/\1/p' "$dir/err")
awk -v v="$vol" 'BEGIN { e = 4 / 3 * 3.14159265358979 * 1000; exit !(v > 0 && (v - e) / e < 0.005 && (e - v) / e < 0.005) }'
check "sphere volume $vol within 0.5% of 4188.79" $?
tris=$(sed -n 's/.*: \([0-9]*\) triangles.*/\1/p' "$dir/err")
size=$(wc -c <"$dir/s.stl")
[ "$size" -eq $((84 + 50 * tris)) ]
check "binary STL holds the $tris triangles reported" $?
[ -s "$dir/s.png" ] && [ "$(head -c 4 "$dir/s.png" | od -An -c | tr -d ' ')" = "211PNG" ]
check "picture is a PNG" $?

# The bounds close an unbounded model: a half-space z <= 0 inside
# [-5,5]x[-5,5]x[-5,5] is the box [-5,5]x[-5,5]x[-5,0].
printf 'half(x[3], a[1])\n{\n  half = -x[3];\n}\n' >"$dir/half.hf"
# Sharp edges lose about 0.7 h^2 mm3 per mm of edge in the mesh (corners are
# cut), hence the fine voxel for a 0.5% bound.
"$frepmill" mesh "$dir/half.hf" --bounds -5,-5,-5,5,5,5 --voxel 0.1 --out "$dir/h.obj" 2>"$dir/err"
check "half-space meshes" $?
vol=$(sed -n 's/.*volume \([0-9.]*\) mm3.*/\1/p' "$dir/err")
awk -v v="$vol" 'BEGIN { exit !(v > 497.5 && v < 502.5) }'
check "bounded half-space volume $vol within 0.5% of 500" $?

# Errors: position in the model, missing options, bad bounds.
printf 'bad(x[3], a[1])\n{\n  bad = hfSpere(x, 1);\n}\n' >"$dir/bad.hf"
"$frepmill" mesh "$dir/bad.hf" --bounds 0,0,0,1,1,1 --voxel 0.1 --out "$dir/b.stl" 2>"$dir/err"
[ $? -eq 2 ] && grep -q "bad.hf:3:9" "$dir/err" && grep -q "hfSphere" "$dir/err"
check "unknown function: exit 2, file:line:column and a suggestion ($(cat "$dir/err"))" $?
"$frepmill" mesh "$dir/sphere.hf" --voxel 0.1 --out "$dir/b.stl" 2>"$dir/err"
[ $? -eq 2 ] && grep -q "no --bounds" "$dir/err"
check "missing --bounds is bad input" $?
"$frepmill" mesh "$dir/sphere.hf" --bounds 1,0,0,0,1,1 --voxel 0.1 --out "$dir/b.stl" 2>"$dir/err"
[ $? -eq 2 ] && grep -q "lower value first" "$dir/err"
check "inverted bounds are bad input" $?
"$frepmill" mesh "$dir/sphere.hf" --bounds 0,0,0,1,1,1 --voxel 0.1 --out "$dir/b.xyz" 2>"$dir/err"
[ $? -eq 2 ] && grep -q "unknown format" "$dir/err"
check "unknown output format is bad input" $?
"$frepmill" mesh "$dir/sphere.hf" --bounds -2000,-2000,-2000,2000,2000,2000 --voxel 0.001 \
    --out "$dir/b.stl" 2>"$dir/err"
[ $? -eq 3 ]
check "a grid over the memory budget is a resource limit ($(cat "$dir/err"))" $?
exit $fail
