#!/bin/sh
# test.sh: the README's test command. Installs what the tests need, builds
# frepmill twice (optimized, and with AddressSanitizer + UBSan) and runs
# every test: all of them in the optimized build (with valgrind runs of the
# kernel tests), the unit tests again under the sanitizers.
set -eu
cd "$(dirname "$0")/.."

deploy/install-deps.sh test

jobs=$(nproc 2>/dev/null || echo 2)

cmake -S . -B build/release -DCMAKE_BUILD_TYPE=RelWithDebInfo
cmake --build build/release -j "$jobs"
ctest --test-dir build/release --output-on-failure -j "$jobs"

cmake -S . -B build/asan -DCMAKE_BUILD_TYPE=Debug -DFM_SANITIZE=ON -DFM_BENCH=OFF
cmake --build build/asan -j "$jobs"
ASAN_OPTIONS=detect_leaks=1:abort_on_error=1 UBSAN_OPTIONS=print_stacktrace=1:halt_on_error=1 \
    ctest --test-dir build/asan --output-on-failure -j "$jobs" -L unit
