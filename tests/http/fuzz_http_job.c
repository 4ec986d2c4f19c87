/* fuzz_http_job.c: libFuzzer target for the job request parser (JSON with
 * jansson, validation into the canonical form). The canonical form must
 * parse again to an equal value. */
#include <stdlib.h>
#include <string.h>

#include "protocols/http/http_server.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fm_http_error err;
    json_t *job = fm_http_job_parse((const char *)data, size, &err);
    if (job) {
        char *text = json_dumps(job, JSON_COMPACT);
        json_t *again = text ? fm_http_job_parse(text, strlen(text), &err) : NULL;
        if (!again || !json_equal(job, again)) abort();
        json_decref(again);
        free(text);
        json_decref(job);
    }
    return 0;
}
