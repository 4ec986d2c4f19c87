/* bench_clock.h: the two clocks every benchmark reads, in seconds: wall
 * time (monotonic) and the process's CPU time (user + system, every
 * thread), which is the figure that holds on a loaded machine. Both are
 * lib/core's clocks; these names are the benchmarks' own. */
#ifndef FM_BENCH_CLOCK_H
#define FM_BENCH_CLOCK_H

#include "core/core.h"

static inline double bench_wall_s(void) { return fm_clock_monotonic_s(); }

static inline double bench_cpu_s(void) { return fm_clock_cpu_s(); }

#endif
