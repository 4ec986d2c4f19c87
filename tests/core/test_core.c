/* test_core.c: the error record's formatting and the checked size
 * arithmetic that budgets rely on. */
#include "core/core.h"
#include "test.h"

#include <stdint.h>

int main(void)
{
    fm_error err;
    char buf[600];

    CHECK(fm_error_at(&err, FM_ERR_INPUT, "part.ngc", 12, 7, "expected %s, found '%c'", "a number", 'Q') ==
          FM_ERR_INPUT);
    CHECK(strcmp(fm_error_format(&err, buf, sizeof buf),
                 "part.ngc:12:7: expected a number, found 'Q'") == 0);

    fm_error_at(&err, FM_ERR_INPUT, "", 3, 9, "bad word");
    CHECK(strcmp(fm_error_format(&err, buf, sizeof buf), "3:9: bad word") == 0);

    fm_error_set(&err, FM_ERR_LIMIT, "needs %d MB", 512);
    CHECK(err.line == 0 && err.column == 0 && err.file[0] == '\0');
    CHECK(strcmp(fm_error_format(&err, buf, sizeof buf), "needs 512 MB") == 0);

    /* A message longer than the record is cut, never overflowed. */
    char longname[1000];
    memset(longname, 'a', sizeof longname - 1);
    longname[sizeof longname - 1] = '\0';
    fm_error_at(&err, FM_ERR_IO, longname, 1, 1, "%s", longname);
    CHECK(strlen(err.file) == sizeof err.file - 1);
    CHECK(strlen(err.message) == sizeof err.message - 1);
    char small[16];
    CHECK(strlen(fm_error_format(&err, small, sizeof small)) == sizeof small - 1);

    /* NULL records are allowed: the code still comes back. */
    CHECK(fm_error_set(NULL, FM_ERR_IO, "x") == FM_ERR_IO);

    size_t out = 0;
    CHECK(fm_size_mul(1u << 20, 1u << 10, &out) && out == (size_t)1 << 30);
    CHECK(!fm_size_mul(SIZE_MAX / 2 + 1, 2, &out));
    CHECK(fm_size_mul(0, SIZE_MAX, &out) && out == 0);
    CHECK(fm_size_add(SIZE_MAX - 1, 1, &out) && out == SIZE_MAX);
    CHECK(!fm_size_add(SIZE_MAX, 1, &out));

    fm_error_clear(&err);
    CHECK(err.code == FM_OK && err.message[0] == '\0');
    return test_summary("core");
}
