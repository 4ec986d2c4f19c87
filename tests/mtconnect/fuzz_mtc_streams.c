/* fuzz_mtc_streams.c: libFuzzer target of the reader of an agent's Streams
 * documents (live mode's mtconnect:// source): any bytes are read as a
 * document; observations must come in sequence order with their strings
 * set, and a refusal must say why. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "protocols/mtconnect/mtconnect.h"

typedef struct seen {
    uint64_t last;
    size_t count;
} seen;

static void fz_observation(void *ctx, const fm_mtc_observation *o)
{
    seen *s = ctx;
    if (!o->value || (s->count && o->sequence < s->last)) abort();
    if (o->name) (void)strlen(o->name);
    if (o->data_item_id) (void)strlen(o->data_item_id);
    s->last = o->sequence;
    s->count++;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    seen s = {0, 0};
    uint64_t next = 7;
    char why[256] = "";
    int rc = fm_mtc_streams_read((const char *)data, size, fz_observation, &s, &next, why, sizeof why);
    if (rc != 0 && (!why[0] || s.count)) abort();
    return 0;
}
