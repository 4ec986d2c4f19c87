#!/bin/sh
# install-viewer.sh: install the browser viewer's JavaScript dependencies
# (three.js with its Draco decoder; with --dev also playwright-core for the
# browser test) from the npm registry into viewer/node_modules, as pinned by
# viewer/package-lock.json. frepmilld serves them from there: the page loads
# nothing from the internet. Idempotent: nothing is done when node_modules
# already matches the lock file. Usage:
#   deploy/install-viewer.sh          three only (what the daemon serves)
#   deploy/install-viewer.sh --dev    also playwright-core (tests/viewer)
set -eu
cd "$(dirname "$0")/../viewer"

dev=0
case "${1:-}" in
"") ;;
--dev) dev=1 ;;
*) echo "install-viewer.sh: unknown option '$1' (--dev)" >&2; exit 2 ;;
esac

if ! command -v npm >/dev/null 2>&1; then
    echo "install-viewer.sh: npm is not installed; the viewer needs Node.js and npm (Debian: apt-get install npm)" >&2
    exit 1
fi

lock_sum=$(sha256sum package-lock.json | cut -d' ' -f1)
stamp=node_modules/.frepmill-installed
if [ -f "$stamp" ]; then
    read -r have_sum have_dev <"$stamp" || true
    if [ "$have_sum" = "$lock_sum" ] && [ -f node_modules/three/build/three.module.js ] &&
        { [ "$dev" = 0 ] || [ "$have_dev" = 1 ]; }; then
        exit 0
    fi
fi

echo "install-viewer.sh: npm ci in viewer/" >&2
if [ "$dev" = 1 ]; then
    npm ci --no-audit --no-fund
else
    npm ci --no-audit --no-fund --omit=dev
fi
echo "$lock_sum $dev" >"$stamp"
