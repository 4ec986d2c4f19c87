"""fm_skip.py: the Python tests' side of the skip rule (tests/README.md). A test
that cannot run because something outside the repository is missing calls
skip(why): exit 77 (ctest: skipped) saying why, or, when the environment has
CI=true, exit 1, since CI never skips."""
import os
import sys


def in_ci():
    return os.environ.get("CI", "").lower() in ("true", "1")


def skip(why):
    if in_ci():
        print("FAILED: %s (CI=true: a test may not skip; deploy/install-deps.sh test installs what "
              "tests need)" % why, file=sys.stderr)
        sys.exit(1)
    print("SKIPPED: %s" % why)
    sys.exit(77)
