# skip.sh: sourced by the shell tests (and by need.sh). A test that cannot run
# because something outside the repository is missing calls `skip WHY`: it
# exits 77 (ctest: skipped) saying why, or, when the environment has CI=true,
# fails with status 1, since CI never skips (tests/README.md).

fm_in_ci() {
    case "${CI:-}" in
    [Tt][Rr][Uu][Ee] | 1) return 0 ;;
    esac
    return 1
}

skip() {
    if fm_in_ci; then
        echo "FAILED: $* (CI=true: a test may not skip; deploy/install-deps.sh test installs what tests need)" >&2
        exit 1
    fi
    echo "SKIPPED: $*"
    exit 77
}
