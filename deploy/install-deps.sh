#!/bin/sh
# install-deps.sh: install what frepmill needs from Debian 12's archive,
# idempotently (packages already present are not touched; apt-get update
# runs only when something is missing). Usage:
#   deploy/install-deps.sh build   compilers and libraries to build frepmill
#   deploy/install-deps.sh test    build + everything the tests use: valgrind, rs274, mbpoll, xmllint,
#                                  python3, chromium, clang with libFuzzer (the sanitizer and fuzz
#                                  runs of deploy/test.sh), and from npm the viewer's packages
#                                  (deploy/install-viewer.sh --dev) and the Node Modbus client of the
#                                  Modbus tests (tests/modbus/node_modules): no test downloads
#   deploy/install-deps.sh dev     the same as test
set -eu

group=${1:-build}

build_pkgs="build-essential cmake ninja-build pkg-config libopenvdb-dev libboost-iostreams-dev libtbb-dev libhiredis-dev \
libblosc-dev libdraco-dev libmodbus-dev libmicrohttpd-dev libjansson-dev libxml2-dev libzip-dev libstb-dev curl"
test_pkgs="valgrind python3 linuxcnc-uspace mbpoll draco curl chromium redis-server clang libclang-rt-14-dev \
libxml2-utils"

case "$group" in
build) pkgs=$build_pkgs ;;
test | dev) pkgs="$build_pkgs $test_pkgs" ;;
*) echo "install-deps.sh: unknown group '$group' (build, test or dev)" >&2; exit 2 ;;
esac

missing=""
for p in $pkgs; do
    if ! dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed"; then
        missing="$missing $p"
    fi
done

# The viewer's JavaScript comes from the npm registry: Node.js and npm from
# Debian when the machine has no npm of its own.
if ! command -v npm >/dev/null 2>&1; then
    missing="$missing nodejs npm"
fi

# From npm (idempotent: nothing is done when node_modules matches the lock
# file): the viewer's three.js and the browser test's playwright-core, and
# the Node Modbus client (modbus-serial) of tests/modbus and tests/daemon.
# Tests never download; without these they skip, and under CI=true (where no
# test may skip) a failed install stops here.
npm_test_deps() {
    here=$(cd "$(dirname "$0")" && pwd)
    "$here/install-viewer.sh" --dev || return 1
    cd "$here/../tests/modbus"
    lock_sum=$(sha256sum package-lock.json | cut -d' ' -f1)
    stamp=node_modules/.frepmill-installed
    if [ -f "$stamp" ] && [ "$(cat "$stamp")" = "$lock_sum" ] &&
        [ -f node_modules/modbus-serial/package.json ]; then
        return 0
    fi
    echo "install-deps.sh: npm ci in tests/modbus" >&2
    # Exactly the locked versions; serialport (optional) and install scripts
    # are not needed for Modbus/TCP.
    npm ci --omit=optional --ignore-scripts --no-audit --no-fund || return 1
    echo "$lock_sum" >"$stamp"
}

viewer_deps() {
    case "$group" in
    test | dev)
        if ! (npm_test_deps); then
            case "${CI:-}" in
            [Tt][Rr][Uu][Ee] | 1)
                echo "install-deps.sh: the npm packages the tests need could not be installed" >&2
                exit 1
                ;;
            esac
            echo "install-deps.sh: npm packages not installed; tests/viewer and the Node Modbus tests will skip" >&2
        fi
        ;;
    esac
}

if [ -z "$missing" ]; then
    viewer_deps
    exit 0
fi

if [ "$(id -u)" -eq 0 ]; then
    sudo=""
elif command -v sudo >/dev/null 2>&1; then
    sudo="sudo"
else
    echo "install-deps.sh: these packages are missing and I am not root:$missing" >&2
    exit 1
fi

echo "install-deps.sh: installing$missing" >&2
export DEBIAN_FRONTEND=noninteractive
$sudo apt-get update -q
# shellcheck disable=SC2086
$sudo apt-get install -y -q --no-install-recommends $missing
viewer_deps
