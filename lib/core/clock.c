/* clock.c: the clocks in seconds, and a real-time deadline for condition
 * waits (pthread_cond_timedwait measures against CLOCK_REALTIME unless the
 * condition was made otherwise). */
#include "core/core.h"

#include <time.h>

static double seconds_of(clockid_t id)
{
    struct timespec ts;
    clock_gettime(id, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

double fm_clock_monotonic_s(void) { return seconds_of(CLOCK_MONOTONIC); }

double fm_clock_wall_s(void) { return seconds_of(CLOCK_REALTIME); }

double fm_clock_cpu_s(void) { return seconds_of(CLOCK_PROCESS_CPUTIME_ID); }

void fm_clock_deadline(struct timespec *out, double seconds)
{
    clock_gettime(CLOCK_REALTIME, out);
    if (!(seconds > 0)) return;
    /* whole seconds apart from the fraction, so that a long wait keeps
     * its nanoseconds exact */
    const time_t whole = (time_t)seconds;
    out->tv_sec += whole;
    out->tv_nsec += (long)((seconds - (double)whole) * 1e9);
    if (out->tv_nsec >= 1000000000L) {
        out->tv_sec++;
        out->tv_nsec -= 1000000000L;
    }
}
