#!/bin/sh
# demo.sh: the README's main-job command. Installs the build dependencies,
# builds frepmill and runs it on the bundled demo (deploy/demo: a pocket,
# contour, circular pocket, holes and chamfer program for three tools in a
# 100x60x30 mm block). Outputs go to demo-output/.
set -eu
cd "$(dirname "$0")/.."

deploy/install-deps.sh build

jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build/release -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build build/release -j "$jobs"

out=demo-output
mkdir -p "$out"
frepmill=build/release/daemon/frepmill

"$frepmill" motions deploy/demo/pocket.ngc --tools deploy/demo/tools.json >"$out/motions.jsonl"
echo "demo: $(wc -l <"$out/motions.jsonl") motions of deploy/demo/pocket.ngc written to $out/motions.jsonl"
