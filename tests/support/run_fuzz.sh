#!/bin/sh
# run_fuzz.sh TARGET SECONDS ARTIFACT_DIR CORPUS[:SEEDS...] [LIBFUZZER_OPTION...]:
# one libFuzzer target for SECONDS from its committed corpus (CORPUS, and
# the folders of hand-written seeds SEEDS, read only), as ctest's fuzz tests
# run it (label "fuzz", FM_FUZZ=ON builds; CMakeLists.txt fm_fuzz). The
# inputs are copied to a scratch folder first, since libFuzzer adds what it
# finds to the first folder it is given; .hex files (one frame a file, '#'
# comments: tests/modbus/attacks) are converted to binary inputs.
# A crash, leak, timeout or memory blow-up fails the test; the input that
# did it is kept in ARTIFACT_DIR, printed in hex and base64, with the
# command that replays it.
# The random seed changes with the commit (FM_FUZZ_SEED, default: from
# `git rev-parse HEAD`, else 1), so that each CI run explores further than
# the last while a failure reproduces: the seed is printed, and the saved
# input replays it whatever the seed.
# FM_FUZZ_GROW=DIR (deploy/fuzz-grow.sh): fuzz with DIR/NAME as a scratch
# corpus kept between runs, then merge what it found that adds coverage
# (libFuzzer -merge=1 on edges: the fewest inputs that reach a new edge,
# none over 64 KiB) into CORPUS (tests/README.md, "Fuzzing").
# run_fuzz.sh --seed prints the seed a run from this checkout takes.
set -eu

# The seed: FM_FUZZ_SEED, else the commit's (its hash's first 28 bits, + 1:
# libFuzzer's seed is 32-bit and 0 means "from the clock"), else 1 outside
# a git checkout.
seed=${FM_FUZZ_SEED:-}
from=""
if [ -z "$seed" ]; then
    head=$(git -C "${0%/*}" rev-parse HEAD 2>/dev/null || true)
    if [ -n "$head" ]; then
        seed=$(($(printf '%d' "0x$(echo "$head" | cut -c1-7)") + 1))
        from=" from commit $(echo "$head" | cut -c1-12)"
    else
        seed=1
    fi
fi
if [ "${1:-}" = --seed ]; then
    echo "$seed$from"
    exit 0
fi

target=$1 seconds=$2 artifacts=$3 corpus=$4
shift 4
name=$(basename "$target")
work=$(mktemp -d "${TMPDIR:-/tmp}/$name.XXXXXX")
trap 'rm -rf "$work" "$work.log" "$work.merged" "$work.seeds" "$work.merge.log"' EXIT INT TERM
mkdir -p "$artifacts"

# Each corpus folder into $work: binary inputs as they are, .hex files
# converted.
for dir in $(echo "$corpus" | tr ':' ' '); do
    [ -d "$dir" ] || continue
    python3 - "$dir" "$work" <<'PY'
import os, shutil, sys
src, dst = sys.argv[1], sys.argv[2]
for f in sorted(os.listdir(src)):
    path = os.path.join(src, f)
    if not os.path.isfile(path):
        continue
    if f.endswith(".hex"):
        text = "".join(l.split("#")[0] for l in open(path))
        with open(os.path.join(dst, f[:-4] + ".bin"), "wb") as o:
            o.write(bytes.fromhex("".join(text.split())))
    else:
        shutil.copyfile(path, os.path.join(dst, f))
PY
done
grown=${corpus%%:*}


scratch=""
if [ -n "${FM_FUZZ_GROW:-}" ]; then
    scratch="$FM_FUZZ_GROW/$name"
    mkdir -p "$scratch"
fi
if [ "$seed" = 0 ]; then
    said="seed from the clock (libFuzzer's 'INFO: Seed:' line says which)"
else
    said="seed $seed$from (FM_FUZZ_SEED=$seed reruns this run)"
fi
echo "$name: $(ls "$work" | wc -l) corpus inputs${scratch:+ + $(ls "$scratch" | wc -l) scratch}, $seconds s, $said"

rm -f "$artifacts/$name"-*
rc=0
# shellcheck disable=SC2086 # $scratch is one folder or nothing
"$target" -max_total_time="$seconds" -seed="$seed" -rss_limit_mb=2048 -print_final_stats=1 \
    -artifact_prefix="$artifacts/$name-" "$@" $scratch "$work" >"$work.log" 2>&1 || rc=$?
failed=$rc
for kind in crash leak timeout oom; do
    for f in "$artifacts/$name-$kind"-*; do
        [ -e "$f" ] || continue
        echo "FAILED: $name left $f ($(wc -c <"$f") bytes):"
        od -A d -t x1 -v "$f" | head -n 64
        if [ "$(wc -c <"$f")" -le 65536 ]; then
            echo "as base64 (base64 -d > input):"
            base64 -w 76 "$f"
        fi
        echo "replay: $target $* $f"
        failed=1
    done
done
if [ "$failed" != 0 ]; then
    tail -n 120 "$work.log"
    echo "FAILED: $name exited with status $rc (seed $seed)"
    exit 1
fi
tail -n 12 "$work.log"

[ -n "$scratch" ] || exit 0
# Grow: the scratch inputs that add coverage to the corpus, into the corpus.
# -use_counters=0: coverage is which edges run, not how often, so that the
# committed corpus keeps one input per new edge rather than one per new
# count (a tenth as many files: fuzz_shdr's ten seconds, 54 against 315);
# the fuzzing itself still follows the counts.
mkdir "$work.merged"
cp -R "$work"/. "$work.merged"/
ls "$work.merged" >"$work.seeds"
"$target" -merge=1 -use_counters=0 -rss_limit_mb=2048 "$@" "$work.merged" "$scratch" >"$work.merge.log" 2>&1 || {
    tail -n 40 "$work.merge.log"
    echo "FAILED: $name: the merge into $grown failed"
    exit 1
}
grep 'MERGE-OUTER' "$work.merge.log" | tail -n 2
added=0 big=0
for f in "$work.merged"/*; do
    base=$(basename "$f")
    grep -qxF "$base" "$work.seeds" && continue
    if [ "$(wc -c <"$f")" -gt 65536 ]; then
        big=$((big + 1))
        continue
    fi
    mkdir -p "$grown"
    cp "$f" "$grown/$base"
    added=$((added + 1))
done
echo "$name: $added inputs with new coverage added to $grown, $big over 64 KiB left out"
