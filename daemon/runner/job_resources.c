/* job_resources.c: the process's resource use (peak memory) for reports
 * and benchmarks; the clocks are lib/core's (fm_clock_*). */
#include <sys/resource.h>

#include "job_internal.h"

size_t fm_job_peak_rss(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
    return (size_t)ru.ru_maxrss * 1024u; /* Linux reports kilobytes */
}
