/* fuzz_job_doc.c: libFuzzer target for the job document parser
 * (daemon/runner/job_doc.c: JSON with jansson, validation into the run spec
 * and the canonical form), under the strict network rules and the daemon's
 * own. An accepted document's canonical form must parse again to an equal
 * value, and its run spec must hold together. */
#include <stdlib.h>
#include <string.h>

#include "runner/job_doc.h"

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size);

static void one(const uint8_t *data, size_t size, const fm_job_doc_rules *rules)
{
    fm_error err;
    fm_job_doc *doc = NULL;
    if (fm_job_doc_parse((const char *)data, size, rules, &doc, &err) != FM_OK) {
        if (doc || !err.message[0]) abort();
        return;
    }
    const fm_job_spec *s = &doc->spec;
    if (!s->tools || s->tools->count == 0 || !(s->stock.voxel_mm > 0)) abort();
    if (!s->program_text && s->program_kind != FM_PROGRAM_LIVE) abort();
    if (!s->stock_spec == !doc->stock_model.size) abort(); /* exactly one stock */
    if (doc->check.fixture_count < 0 || doc->check.fixture_count > FM_JOB_MAX_FIXTURES) abort();
    if (s->check && s->check != &doc->check) abort();
    char *text = json_dumps(doc->json, JSON_COMPACT);
    fm_job_doc *again = NULL;
    if (!text || fm_job_doc_parse(text, strlen(text), rules, &again, &err) != FM_OK ||
        !json_equal(doc->json, again->json))
        abort();
    fm_job_doc_free(again);
    free(text);
    fm_job_doc_free(doc);
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    static const fm_job_doc_rules own = {.allow_files = 1, .allow_live = 1};
    one(data, size, NULL);
    one(data, size, &own);
    return 0;
}
