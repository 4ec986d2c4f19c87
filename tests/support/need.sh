#!/bin/sh
# need.sh NEED... -- COMMAND [ARG...]: how CMake registers a test that needs
# programs or files from outside the repository (fm_tool_test). Runs COMMAND
# when every NEED is present (a program on PATH, or an absolute path that
# exists); otherwise skips (77) naming what is missing, or with CI=true fails.
# The test is registered whatever the build machine has; the check is made
# when it runs.
. "${0%/*}/skip.sh" # no dirname: PATH may lack coreutils

missing=""
while [ $# -gt 0 ] && [ "$1" != "--" ]; do
    case "$1" in
    /*) [ -e "$1" ] || missing="$missing $1" ;;
    *) command -v "$1" >/dev/null 2>&1 || missing="$missing $1" ;;
    esac
    shift
done
if [ $# -lt 2 ]; then
    echo "usage: need.sh NEED... -- COMMAND [ARG...]" >&2
    exit 2
fi
shift
[ -z "$missing" ] || skip "not installed:$missing"
exec "$@"
