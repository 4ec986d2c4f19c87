#!/bin/sh
# test.sh: the README's test command (and CI's: .ci/run). Installs what the
# tests need, then builds frepmill and runs every test. Steps (FM_TEST_STEPS,
# default "release sanitize fuzz"):
#   release   an optimized GCC build (the README's build) and every test but
#             the fuzz targets: unit, valgrind, heavy, timing and the
#             integration tests, each at the full size its tolerance is
#             argued for (the only build where all of them run at that size
#             in CI's budget);
#   sanitize  one clang build with ASan + UBSan and libFuzzer's coverage
#             (-DFM_SANITIZE=ON -DFM_FUZZ=ON): the integration tests and the
#             unit tests again under the sanitizers, but for those labelled
#             timing or heavy (minutes of CPU there; they ran in release);
#             tests whose cost is their grid take a coarser one there
#             (FM_TEST_INSTRUMENTED, tests/README.md);
#   fuzz      (after sanitize) each fuzz target for FM_FUZZ_SECONDS (30) from
#             its committed corpus, two at a time, with a seed that changes
#             with the commit (printed; FM_FUZZ_SEED=N reruns it);
#   asan      (on demand) a GCC build with AddressSanitizer + UBSan: the unit
#             tests again (but those labelled timing).
# `deploy/test.sh full` (nightly size, over CI's 25 minutes): the same steps
# with FM_TEST_FULL_SIZE=1, so that the sanitizer build too runs every test
# at full size, its heavy tests included.
# With CI=true no test may skip: tests that miss a tool fail themselves, and
# any test ctest still reports as skipped fails the run here.
set -eu
cd "$(dirname "$0")/.."

full=0
if [ "${1:-}" = full ]; then
    full=1
    FM_TEST_FULL_SIZE=1
    export FM_TEST_FULL_SIZE
elif [ $# -gt 0 ]; then
    echo "test.sh: unknown argument '$1' (none, or full)" >&2
    exit 2
fi

deploy/install-deps.sh test

jobs=$(nproc 2>/dev/null || echo 2)
# CI's budget is 25 minutes on 2 cores (tests/README.md, the CI time budget).
steps=${FM_TEST_STEPS:-release sanitize fuzz}
in_ci=0
case "${CI:-}" in
[Tt][Rr][Uu][Ee] | 1) in_ci=1 ;;
esac

step_start=0
step() {
    step_start=$(date +%s)
    echo "=== test.sh: $* ($(date '+%H:%M:%S'), load $(cut -d' ' -f1-3 /proc/loadavg 2>/dev/null || echo '?'))"
}
step_done() {
    echo "=== test.sh: $1 took $(($(date +%s) - step_start)) s"
}

# run_ctest BUILD_DIR [CTEST_ARGS...]: ctest with its output kept, so that
# under CI=true a skipped test fails the run even if it skipped by itself.
run_ctest() {
    dir=$1
    shift
    log="$dir/ctest.log"
    rc=0
    { ctest --test-dir "$dir" --output-on-failure -j "$jobs" "$@" || echo $? >"$log.rc"; } | tee "$log"
    if [ -f "$log.rc" ]; then
        rc=$(cat "$log.rc")
        rm -f "$log.rc"
    fi
    if [ "$in_ci" = 1 ] && grep -q '\*\*\*Skipped\|Not Run' "$log"; then
        echo "test.sh: CI=true and these tests did not run:" >&2
        grep '\*\*\*Skipped\|Not Run' "$log" >&2
        rc=1
    fi
    [ "$rc" = 0 ] || exit "$rc"
}

# generator BUILD_DIR: Ninja for a new build folder (deploy/install-deps.sh
# installs it): its compiles do not wait for the libraries they link to, so
# both cores stay busy; a folder configured before keeps its generator.
generator() {
    if [ ! -f "$1/CMakeCache.txt" ] && command -v ninja >/dev/null 2>&1; then
        echo "-GNinja"
    fi
}

sanitize_env() {
    ASAN_OPTIONS=detect_leaks=1:abort_on_error=1:detect_stack_use_after_return=0
    UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1
    export ASAN_OPTIONS UBSAN_OPTIONS
}

for s in $steps; do
    case "$s" in
    release)
        step "optimized build"
        cmake -S . -B build/release $(generator build/release) -DCMAKE_BUILD_TYPE=RelWithDebInfo
        cmake --build build/release -j "$jobs"
        step_done "optimized build"
        step "the optimized build's tests (all but the fuzz targets; integration tests at full size)"
        run_ctest build/release -LE fuzz
        step_done "optimized tests"
        ;;
    asan)
        step "GCC build with ASan + UBSan"
        cmake -S . -B build/asan $(generator build/asan) -DCMAKE_BUILD_TYPE=Debug -DFM_SANITIZE=ON -DFM_BENCH=OFF
        cmake --build build/asan -j "$jobs"
        step_done "ASan build"
        step "unit tests under ASan + UBSan"
        sanitize_env
        run_ctest build/asan -L unit -LE timing
        step_done "ASan unit tests"
        ;;
    sanitize)
        step "clang build with ASan + UBSan and the fuzz targets"
        CC=clang CXX=clang++ cmake -S . -B build/sanitize $(generator build/sanitize) -DCMAKE_BUILD_TYPE=Debug -DFM_SANITIZE=ON \
            -DFM_FUZZ=ON -DFM_BENCH=OFF
        cmake --build build/sanitize -j "$jobs"
        step_done "sanitizer build"
        sanitize_env
        if [ "$full" = 1 ]; then
            step "unit, heavy and integration tests under ASan + UBSan, at full size"
            run_ctest build/sanitize -L 'unit|integration|heavy' -LE timing
        else
            step "unit and integration tests under ASan + UBSan (coarser grids: FM_TEST_INSTRUMENTED)"
            run_ctest build/sanitize -L 'unit|integration' -LE 'timing|heavy'
        fi
        step_done "sanitizer tests"
        ;;
    fuzz)
        step "each fuzz target from its corpus, two at a time"
        [ -d build/sanitize ] || {
            echo "test.sh: the fuzz step needs the sanitize step's build" >&2
            exit 2
        }
        sanitize_env
        echo "test.sh: fuzz seed $(sh tests/support/run_fuzz.sh --seed); a failing input is printed" \
            "and kept in build/sanitize/fuzz-artifacts/"
        run_ctest build/sanitize -L fuzz -j 2
        step_done "fuzzing"
        ;;
    *)
        echo "test.sh: unknown step '$s' (release, asan, sanitize, fuzz)" >&2
        exit 2
        ;;
    esac
done
echo "=== test.sh: all passed"
