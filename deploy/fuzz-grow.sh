#!/bin/sh
# fuzz-grow.sh [SECONDS] [NAME...]: grow the committed fuzz corpora. Each
# fuzz target (all, or those NAMEd: gcode, hf, job_doc...) runs SECONDS
# (default 60) one at a time, niced, from its committed corpus plus a
# scratch corpus kept in the build folder between runs, with a seed from
# the clock; then what the scratch holds that adds coverage is merged into
# the committed corpus (libFuzzer -merge=1 on edges: minimized, no input over
# 64 KiB). Review and commit what it adds (git status tests/); CI fuzzes
# from it (deploy/test.sh, step fuzz). A crash stops it: the input is kept
# in BUILD/fuzz-artifacts (tests/README.md, "Fuzzing").
# Builds the fuzz targets first in FM_FUZZ_BUILD (default build/sanitize,
# the CI sanitizer build: clang, ASan + UBSan, -DFM_FUZZ=ON).
set -eu
cd "$(dirname "$0")/.."
seconds=${1:-60}
[ $# -gt 0 ] && shift
build=${FM_FUZZ_BUILD:-build/sanitize}

if [ ! -f "$build/CMakeCache.txt" ]; then
    CC=clang CXX=clang++ cmake -S . -B "$build" -DCMAKE_BUILD_TYPE=Debug -DFM_SANITIZE=ON -DFM_FUZZ=ON \
        -DFM_BENCH=OFF
fi
grep -q '^FM_FUZZ:BOOL=ON' "$build/CMakeCache.txt" || {
    echo "fuzz-grow.sh: $build is not a -DFM_FUZZ=ON build" >&2
    exit 2
}

# The fuzz tests' commands as ctest has them (run_fuzz.sh TARGET SECONDS
# ARTIFACTS CORPUS OPTIONS...), one a line, tab-separated.
list=$(mktemp)
trap 'rm -f "$list"' EXIT INT TERM
ctest --test-dir "$build" -L fuzz --show-only=json-v1 | python3 -c '
import json, sys
wanted = sys.argv[1:]
for t in json.load(sys.stdin)["tests"]:
    name = t["name"][len("fuzz_"):]
    if not wanted or name in wanted:
        print("\t".join(t["command"][1:]))
' "$@" >"$list"
[ -s "$list" ] || {
    echo "fuzz-grow.sh: no fuzz target named $*" >&2
    exit 2
}

targets=$(cut -f2 "$list" | xargs -n1 basename | tr '\n' ' ')
# shellcheck disable=SC2086 # one word a target
nice cmake --build "$build" -j "$(nproc 2>/dev/null || echo 2)" --target $targets

ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0
UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
FM_FUZZ_GROW=$(pwd)/$build/fuzz-scratch
FM_FUZZ_SEED=${FM_FUZZ_SEED:-0}
export ASAN_OPTIONS UBSAN_OPTIONS FM_FUZZ_GROW FM_FUZZ_SEED

tab=$(printf '\t')
while IFS="$tab" read -r script target _seconds artifacts corpus options; do
    # shellcheck disable=SC2046 # the options are separate words
    nice sh "$script" "$target" "$seconds" "$artifacts" "$corpus" $(echo "$options" | tr '\t' ' ') </dev/null
done <"$list"
echo "fuzz-grow.sh: the corpora now (commit what was added):"
git status --short -- tests
