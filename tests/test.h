/* test.h: the few assertion macros the unit tests share. A failed check
 * prints where and why and the program exits non-zero at the end; checks
 * keep running so that one run shows every failure. */
#ifndef FM_TEST_H
#define FM_TEST_H

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

/* FM_TEST_INSTRUMENTED: 1 in a build with AddressSanitizer (FM_SANITIZE or
 * FM_FUZZ), where the code runs several times slower. A test whose cost is
 * the size of its grid may use a coarser one when test_coarse() says so (in
 * that build, unless FM_TEST_FULL_SIZE=1: deploy/test.sh full): it still
 * asserts its figures, and CI runs the fine grid in the optimized build
 * (deploy/test.sh's release step runs every test there). */
#ifndef FM_TEST_INSTRUMENTED
#if defined(__SANITIZE_ADDRESS__)
#define FM_TEST_INSTRUMENTED 1
#elif defined(__has_feature)
#if __has_feature(address_sanitizer)
#define FM_TEST_INSTRUMENTED 1
#endif
#endif
#endif
#ifndef FM_TEST_INSTRUMENTED
#define FM_TEST_INSTRUMENTED 0
#endif

static inline int test_coarse(void)
{
    const char *full = getenv("FM_TEST_FULL_SIZE");
    return FM_TEST_INSTRUMENTED && !(full && !strcmp(full, "1"));
}

static int fm_test_failures;
static int fm_test_checks;

#define CHECK(cond)                                                          \
    do {                                                                     \
        fm_test_checks++;                                                    \
        if (!(cond)) {                                                       \
            fm_test_failures++;                                              \
            fprintf(stderr, "%s:%d: CHECK failed: %s\n", __FILE__, __LINE__, \
                    #cond);                                                  \
        }                                                                    \
    } while (0)

#define CHECK_NEAR(a, b, tol)                                                  \
    do {                                                                       \
        double fm_a_ = (a), fm_b_ = (b), fm_t_ = (tol);                        \
        fm_test_checks++;                                                      \
        if (!(fabs(fm_a_ - fm_b_) <= fm_t_)) {                                 \
            fm_test_failures++;                                                \
            fprintf(stderr, "%s:%d: CHECK_NEAR failed: %s = %.12g, %s = %.12g, " \
                    "tolerance %.3g\n", __FILE__, __LINE__, #a, fm_a_, #b,     \
                    fm_b_, fm_t_);                                             \
        }                                                                      \
    } while (0)

#define CHECK_STR_CONTAINS(haystack, needle)                                   \
    do {                                                                       \
        const char *fm_h_ = (haystack), *fm_n_ = (needle);                     \
        fm_test_checks++;                                                      \
        if (!fm_h_ || !strstr(fm_h_, fm_n_)) {                                 \
            fm_test_failures++;                                                \
            fprintf(stderr, "%s:%d: \"%s\" does not contain \"%s\"\n",         \
                    __FILE__, __LINE__, fm_h_ ? fm_h_ : "(null)", fm_n_);      \
        }                                                                      \
    } while (0)

/* Deterministic random numbers so that failures reproduce. */
static unsigned long long fm_test_rng_state = 0x9E3779B97F4A7C15ULL;
static inline double test_rand01(void)
{
    fm_test_rng_state ^= fm_test_rng_state << 13;
    fm_test_rng_state ^= fm_test_rng_state >> 7;
    fm_test_rng_state ^= fm_test_rng_state << 17;
    return (double)(fm_test_rng_state >> 11) * (1.0 / 9007199254740992.0);
}
static inline double test_uniform(double lo, double hi)
{
    return lo + (hi - lo) * test_rand01();
}

/* Is this a CI run (CI=true or CI=1 in the environment)? */
static inline int test_in_ci(void)
{
    const char *ci = getenv("CI");
    return ci && (!strcmp(ci, "1") || !strcasecmp(ci, "true"));
}

/* A test that cannot run because something outside the repository is
 * missing (a program, LinuxCNC's example files) returns this from main:
 * 77, which ctest reports as skipped, with the reason printed; under CI=true
 * 1, a failure, since CI never skips (tests/README.md). */
static inline int test_skip(const char *why)
{
    if (test_in_ci()) {
        fprintf(stderr, "FAILED: %s (CI=true: a test may not skip; deploy/install-deps.sh test installs what "
                "tests need)\n", why);
        return 1;
    }
    printf("SKIPPED: %s\n", why);
    return 77;
}

static inline int test_summary(const char *name)
{
    printf("%s: %d checks, %d failed\n", name, fm_test_checks, fm_test_failures);
    return fm_test_failures ? 1 : 0;
}

#endif
