/* test.h: the few assertion macros the unit tests share. A failed check
 * prints where and why and the program exits non-zero at the end; checks
 * keep running so that one run shows every failure. */
#ifndef FM_TEST_H
#define FM_TEST_H

#include <math.h>
#include <stdio.h>
#include <string.h>

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

static inline int test_summary(const char *name)
{
    printf("%s: %d checks, %d failed\n", name, fm_test_checks, fm_test_failures);
    return fm_test_failures ? 1 : 0;
}

#endif
