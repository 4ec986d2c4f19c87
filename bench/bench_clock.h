/* bench_clock.h: the two clocks every benchmark reads, in seconds: wall
 * time (monotonic) and the process's CPU time (user + system, every
 * thread), which is the figure that holds on a loaded machine. */
#ifndef FM_BENCH_CLOCK_H
#define FM_BENCH_CLOCK_H

#include <time.h>

static inline double bench_wall_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_MONOTONIC, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

static inline double bench_cpu_s(void)
{
    struct timespec ts;
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return (double)ts.tv_sec + 1e-9 * (double)ts.tv_nsec;
}

#endif
