/* test_core_file_alloc.c: the file reader under allocation counting and
 * failure (tests/support/alloc_fail.h): a file over the budget is refused
 * with no allocation at all, and a failed allocation is FM_ERR_LIMIT with
 * nothing left allocated. */
#include "core/core.h"
#include "support/alloc_fail.h"
#include "test.h"

#include <stdio.h>
#include <stdlib.h>
#include <unistd.h>

int main(void)
{
    char path[] = "/tmp/fm_core_alloc_XXXXXX";
    int fd = mkstemp(path);
    if (fd < 0) return test_skip("cannot create a file in /tmp");
    const char text[] = "T1 M6\nG0 X0 Y0\n";
    CHECK(write(fd, text, sizeof text - 1) == (ssize_t)(sizeof text - 1));
    close(fd);
    char *data = NULL;
    size_t size = 0;
    fm_error err;

    /* over the budget: no allocation */
    const long live = alloc_fail_live();
    alloc_fail_arm(0);
    fm_status st = fm_file_read(path, NULL, sizeof text - 2, &data, &size, &err);
    CHECK(alloc_fail_disarm() == 0);
    CHECK(st == FM_ERR_LIMIT);

    /* within it: one allocation, the buffer */
    alloc_fail_arm(0);
    st = fm_file_read(path, NULL, 1000, &data, &size, &err);
    CHECK(alloc_fail_disarm() == 1);
    CHECK(st == FM_OK && size == sizeof text - 1);
    free(data);

    /* that allocation failing: a limit, nothing allocated, nothing left */
    alloc_fail_arm(1);
    st = fm_file_read(path, NULL, 1000, &data, &size, &err);
    alloc_fail_disarm();
    CHECK(alloc_fail_hit());
    CHECK(st == FM_ERR_LIMIT && data == NULL);
    CHECK_STR_CONTAINS(err.message, "out of memory reading");
    CHECK(alloc_fail_live() == live);

    /* a file that grows while read (/proc says 0 bytes): each allocation
     * failing in turn leaves nothing allocated */
    for (long n = 1;; n++) {
        alloc_fail_arm(n);
        st = fm_file_read("/proc/self/status", NULL, 1 << 20, &data, &size, &err);
        alloc_fail_disarm();
        if (!alloc_fail_hit()) {
            CHECK(st == FM_OK && n > 1);
            free(data);
            break;
        }
        CHECK(st == FM_ERR_LIMIT && data == NULL);
        CHECK(alloc_fail_live() == live);
    }
    unlink(path);
    return test_summary("core_file_alloc");
}
