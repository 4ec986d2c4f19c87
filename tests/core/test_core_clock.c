/* test_core_clock.c: the clocks against each other and against time(2):
 * the monotonic clock never steps back and measures a sleep, the wall
 * clock is the epoch's, CPU time grows with work, and a deadline lies the
 * asked time ahead on the real-time clock. */
#include "core/core.h"
#include "test.h"

#include <math.h>
#include <time.h>

int main(void)
{
    double last = fm_clock_monotonic_s();
    int backwards = 0;
    for (int i = 0; i < 100000; i++) {
        const double now = fm_clock_monotonic_s();
        if (now < last) backwards++;
        last = now;
    }
    CHECK(backwards == 0);

    /* a 50 ms sleep: at least 50 ms on the monotonic clock, and about as
     * long on the wall clock (no NTP step expected within it) */
    const double m0 = fm_clock_monotonic_s(), w0 = fm_clock_wall_s();
    const struct timespec nap = {0, 50000000L};
    nanosleep(&nap, NULL);
    const double slept = fm_clock_monotonic_s() - m0, wslept = fm_clock_wall_s() - w0;
    CHECK(slept >= 0.05 && slept < 5);
    CHECK_NEAR(wslept, slept, 0.5);

    /* the wall clock counts from the epoch, like time(2) */
    CHECK_NEAR(fm_clock_wall_s(), (double)time(NULL), 1.5);

    /* sleeping costs no CPU; work does */
    const double c0 = fm_clock_cpu_s();
    nanosleep(&nap, NULL);
    CHECK(fm_clock_cpu_s() - c0 < 0.04);
    volatile double sink = 0;
    const double c1 = fm_clock_cpu_s();
    while (fm_clock_cpu_s() - c1 < 0.02) sink += sqrt(sink + 1);
    CHECK(fm_clock_cpu_s() - c1 >= 0.02);

    /* deadlines: the asked seconds ahead, nanoseconds normalized */
    const double asks[] = {0, 0.25, 1.5, 0.9999999999, 3600.75};
    for (size_t i = 0; i < sizeof asks / sizeof asks[0]; i++) {
        struct timespec until;
        const double before = fm_clock_wall_s();
        fm_clock_deadline(&until, asks[i]);
        const double at = (double)until.tv_sec + 1e-9 * (double)until.tv_nsec;
        CHECK(until.tv_nsec >= 0 && until.tv_nsec < 1000000000L);
        CHECK_NEAR(at - before, asks[i], 0.05);
    }
    return test_summary("core_clock");
}
