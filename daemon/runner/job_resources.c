/* job_resources.c: the process's resource use (peak memory) for reports
 * and benchmarks, and giving freed heap pages back between cuts; the
 * clocks are lib/core's (fm_clock_*). */
#include <sys/resource.h>
#ifdef __GLIBC__
#include <malloc.h>
#endif

#include "job_internal.h"

size_t fm_job_peak_rss(void)
{
    struct rusage ru;
    if (getrusage(RUSAGE_SELF, &ru) != 0) return 0;
    return (size_t)ru.ru_maxrss * 1024u; /* Linux reports kilobytes */
}

void job_release_free_memory(void)
{
#ifdef __GLIBC__
    malloc_trim(0);
#endif
}
