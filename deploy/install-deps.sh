#!/bin/sh
# install-deps.sh: install what frepmill needs from Debian 12's archive,
# idempotently (packages already present are not touched; apt-get update
# runs only when something is missing). Usage:
#   deploy/install-deps.sh build   compilers and libraries to build frepmill
#   deploy/install-deps.sh test    build + what the tests use (valgrind, rs274, mbpoll, python3,
#                                  chromium; and the viewer's npm packages, deploy/install-viewer.sh)
#   deploy/install-deps.sh dev     test + clang with libFuzzer for the fuzz targets
set -eu

group=${1:-build}

build_pkgs="build-essential cmake pkg-config libopenvdb-dev libboost-iostreams-dev libtbb-dev libhiredis-dev \
libblosc-dev libdraco-dev libmodbus-dev libmicrohttpd-dev libjansson-dev libstb-dev curl"
test_pkgs="valgrind python3 linuxcnc-uspace mbpoll draco curl chromium redis-server"
dev_pkgs="clang libclang-rt-14-dev"

case "$group" in
build) pkgs=$build_pkgs ;;
test) pkgs="$build_pkgs $test_pkgs" ;;
dev) pkgs="$build_pkgs $test_pkgs $dev_pkgs" ;;
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

# The viewer's three.js and the browser test's playwright-core, from npm
# (idempotent); without npm the browser test skips.
viewer_deps() {
    case "$group" in
    test | dev)
        "$(dirname "$0")/install-viewer.sh" --dev ||
            echo "install-deps.sh: viewer/node_modules not installed; tests/viewer will skip" >&2
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
