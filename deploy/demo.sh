#!/bin/sh
# demo.sh: the README's main-job command. Installs what it needs, builds
# frepmill, then
#  1. runs `frepmill simulate` on the bundled demo (deploy/demo: a pocket,
#     contour, circular pocket, holes and chamfer program for three tools in
#     a 100x60x30 mm block) at 0.1 mm and leaves the stock as .drc, .stl,
#     .vdb, a picture (.png) and a JSON report in demo-output/, then again
#     compared with the part it is meant to make (deploy/demo/part.hf): a
#     picture coloured by deviation and the report's "design" figures;
#  2. starts the daemon, frepmilld, with the same demo job submitted and
#     prints the viewer's URL. On a terminal it runs until you stop it
#     (Ctrl-C); without one (scripts, CI) it stops once the demo job is done,
#     unless FM_DEMO_SERVE=1.
set -eu
cd "$(dirname "$0")/.."

deploy/install-deps.sh build
if [ -x deploy/install-viewer.sh ]; then
    deploy/install-viewer.sh
fi

jobs=$(nproc 2>/dev/null || echo 2)
cmake -S . -B build/release -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build build/release -j "$jobs"

out=demo-output
mkdir -p "$out"
frepmill=build/release/daemon/frepmill
frepmilld=build/release/daemon/frepmilld

echo "== frepmill simulate: deploy/demo/pocket.ngc at 0.1 mm"
"$frepmill" simulate deploy/demo/pocket.ngc --stock box:0,0,-30,100,60,0 \
    --tools deploy/demo/tools.json --voxel 0.1 \
    --out "$out/pocket.drc" --out "$out/pocket.stl" --out "$out/pocket.vdb" \
    --png "$out/pocket.png" --report "$out/report.json"
echo "demo: outputs in $out/: pocket.drc pocket.stl pocket.vdb pocket.png report.json"

echo "== frepmill simulate: the same job compared with the part it is meant to make (deploy/demo/part.hf)"
"$frepmill" simulate deploy/demo/pocket.ngc --stock box:0,0,-30,100,60,0 \
    --tools deploy/demo/tools.json --voxel 0.1 --design deploy/demo/part.hf --color deviation \
    --png "$out/pocket-deviation.png" --report "$out/deviation.json"
echo "demo: deviation picture $out/pocket-deviation.png (green within 0.05 mm, red gouge, blue excess)," \
    "figures in $out/deviation.json"

if [ ! -x "$frepmilld" ]; then
    exit 0
fi

echo "== frepmilld: the same job in the daemon"
state="$out/frepmilld-state"
log="$out/frepmilld.log"
rm -f "$state/http.addr"
"$frepmilld" --demo --state-dir "$state" --listen 127.0.0.1:8470 --modbus-listen off \
    >"$out/frepmilld.out" 2>"$log" &
pid=$!
trap 'kill -TERM "$pid" 2>/dev/null; wait "$pid" 2>/dev/null' INT TERM

url=""
i=0
while [ $i -lt 100 ] && [ -z "$url" ]; do
    if ! kill -0 "$pid" 2>/dev/null; then
        echo "demo: frepmilld did not start (is port 8470 taken?); see $log" >&2
        exit 1
    fi
    url=$(sed -n 's/^frepmilld: viewer at //p' "$out/frepmilld.out" 2>/dev/null | head -n 1)
    [ -n "$url" ] || sleep 0.1
    i=$((i + 1))
done
if [ -z "$url" ]; then
    echo "demo: frepmilld printed no viewer URL; see $log" >&2
    kill -TERM "$pid"
    exit 1
fi
echo "demo: viewer at $url"

if [ -t 0 ] || [ "${FM_DEMO_SERVE:-0}" = 1 ]; then
    echo "demo: frepmilld runs until you stop it (Ctrl-C)"
    wait "$pid"
    exit 0
fi

# Without a terminal: follow the job to its end, then stop the daemon.
base=${url%%/#*}
job=${url##*#job=}
state_now=""
i=0
while [ $i -lt 1200 ]; do
    state_now=$(curl -s "$base/v1/jobs/$job" | sed -n 's/.*"state": *"\([a-z]*\)".*/\1/p')
    case "$state_now" in done | failed | cancelled) break ;; esac
    sleep 0.5
    i=$((i + 1))
done
echo "demo: daemon job $job is $state_now: $(curl -s "$base/v1/jobs/$job" | head -c 600)"
kill -TERM "$pid"
wait "$pid" || true
[ "$state_now" = done ]
