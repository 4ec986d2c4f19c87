#!/bin/sh
# run_fuzz.sh TARGET SECONDS ARTIFACT_DIR CORPUS [LIBFUZZER_OPTION...]: one
# libFuzzer target for SECONDS from its seed corpus, as ctest's fuzz tests run
# it (label "fuzz", FM_FUZZ=ON builds; CMakeLists.txt fm_fuzz). The seed
# corpus is copied to a scratch folder first, since libFuzzer adds what it
# finds to the first folder it is given; a folder of .hex files (one frame a
# file, '#' comments: tests/modbus/attacks) is converted to binary inputs.
# A crash, leak, timeout or memory blow-up fails the test; the input that
# did it is kept in ARTIFACT_DIR and printed in hex.
# The random seed is fixed (FM_FUZZ_SEED, default 1), so that a run is the
# same on every machine up to how far it gets in SECONDS: a clean main stays
# clean in CI and a failure reproduces. FM_FUZZ_SEED=0 seeds from the clock,
# for exploring with longer runs (tests/README.md).
set -eu
target=$1 seconds=$2 artifacts=$3 corpus=$4
shift 4
name=$(basename "$target")
work=$(mktemp -d "${TMPDIR:-/tmp}/$name.XXXXXX")
trap 'rm -rf "$work" "$work.log"' EXIT INT TERM
mkdir -p "$artifacts"

if ls "$corpus"/*.hex >/dev/null 2>&1; then
    python3 - "$corpus" "$work" <<'PY'
import os, sys
src, dst = sys.argv[1], sys.argv[2]
for f in sorted(os.listdir(src)):
    if f.endswith(".hex"):
        text = "".join(l.split("#")[0] for l in open(os.path.join(src, f)))
        with open(os.path.join(dst, f[:-4] + ".bin"), "wb") as o:
            o.write(bytes.fromhex("".join(text.split())))
PY
else
    cp -R "$corpus"/. "$work"/
fi
echo "$name: $(ls "$work" | wc -l) seed inputs, $seconds s, seed ${FM_FUZZ_SEED:-1}"

rm -f "$artifacts/$name"-*
rc=0
"$target" -max_total_time="$seconds" -seed="${FM_FUZZ_SEED:-1}" -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$artifacts/$name-" "$@" "$work" >"$work.log" 2>&1 || rc=$?
failed=$rc
for kind in crash leak timeout oom; do
    for f in "$artifacts/$name-$kind"-*; do
        [ -e "$f" ] || continue
        echo "FAILED: $name left $f:"
        od -A d -t x1 -v "$f" | head -n 64
        failed=1
    done
done
if [ "$failed" != 0 ]; then
    tail -n 120 "$work.log"
    echo "FAILED: $name exited with status $rc"
    rm -f "$work.log"
    exit 1
fi
tail -n 12 "$work.log"
rm -f "$work.log"
