/* fuzz_mtc_query.c: libFuzzer target of the agent's request parsing: the
 * input is a query string (and, after a NUL, a path given on its own to the
 * XPath subset's parser); a parsed query's numbers must be in their ranges. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "protocols/mtconnect/mtconnect.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    const char *text = (const char *)data;
    const char *nul = memchr(text, '\0', size);
    size_t qlen = nul ? (size_t)(nul - text) : size;
    fm_mtc_query q;
    fm_error err;
    fm_error_clear(&err);
    if (fm_mtc_query_parse(text, qlen, &q, &err) == FM_OK) {
        if (q.has_count && q.count == 0) abort();
        if (q.interval_ms < 0 || q.heartbeat_ms < 10 || q.heartbeat_ms > 600000) abort();
        if (memchr(q.path, '\0', sizeof q.path) == NULL) abort();
        fm_mtc_path path;
        if (q.has_path) fm_mtc_path_parse(q.path, &path, &err);
    } else if (!err.message[0] || !err.reason[0]) {
        abort();
    }
    if (nul) {
        size_t rest = size - qlen - 1;
        char *path_text = malloc(rest + 1);
        if (!path_text) return 0;
        memcpy(path_text, nul + 1, rest);
        path_text[rest] = '\0';
        fm_mtc_path path;
        if (fm_mtc_path_parse(path_text, &path, &err) == FM_OK && (path.count < 1 || path.count > FM_MTC_PATH_MAX_ALTS))
            abort();
        free(path_text);
    }
    return 0;
}
