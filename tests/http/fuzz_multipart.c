/* fuzz_multipart.c: libFuzzer target for the multipart/form-data parser and
 * the job assembly. The first line of the input is the Content-Type, the
 * rest the body; every part found must lie inside the body. */
#include <stdlib.h>
#include <string.h>

#include "protocols/http/http_server.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *text = (const char *)data;
    const char *nl = memchr(text, '\n', size);
    if (!nl || nl - text > 512) return 0;
    char type[513];
    memcpy(type, text, (size_t)(nl - text));
    type[nl - text] = '\0';
    const char *body = nl + 1;
    size_t len = size - (size_t)(body - text);
    /* A copy of exactly len bytes, so that any read past the end is caught. */
    char *copy = malloc(len ? len : 1);
    if (!copy) return 0;
    memcpy(copy, body, len);
    fm_http_part parts[FM_HTTP_MAX_PARTS];
    fm_http_error err;
    int n = fm_http_multipart_parse(type, copy, len, parts, FM_HTTP_MAX_PARTS, &err);
    for (int i = 0; i < n; i++)
        if (parts[i].data < copy || parts[i].data + parts[i].size > copy + len) abort();
    if (n > 0) json_decref(fm_http_job_from_multipart(parts, n, &err));
    free(copy);
    return 0;
}
