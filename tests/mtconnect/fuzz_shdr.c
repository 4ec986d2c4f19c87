/* fuzz_shdr.c: libFuzzer target of the SHDR reader: the input is fed in
 * pieces whose sizes the input's first byte picks, with small limits so
 * that the bounds are reached; every handler checks what it is given. */
#include <stdint.h>
#include <stdlib.h>
#include <string.h>

#include "protocols/mtconnect/mtconnect.h"

static void fz_obs(void *ctx, const fm_shdr_observation *o)
{
    (void)ctx;
    if (!o->key || !o->value || !o->native_code || !o->message || !o->key[0]) abort();
}
static void fz_asset(void *ctx, const fm_shdr_asset *a)
{
    (void)ctx;
    if (!a->command || !a->id || !a->type || !a->body || strlen(a->body) < a->size) abort();
}
static void fz_command(void *ctx, const char *text, long pong)
{
    (void)ctx;
    if (!text || pong == 0) abort();
}
static void fz_malformed(void *ctx, uint64_t line, size_t column, const char *why)
{
    (void)ctx;
    if (!line || !column || !why[0]) abort();
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    if (!size) return 0;
    size_t piece = 1 + data[0] % 64;
    fm_shdr_limits limits = {256, 1024, 32};
    fm_shdr_handlers h = {NULL, NULL, fz_obs, fz_asset, fz_command, fz_malformed};
    fm_shdr_reader *r = fm_shdr_reader_new(data[0] & 0x80 ? &limits : NULL, &h);
    if (!r) return 0;
    for (size_t at = 1; at < size; at += piece) {
        size_t n = size - at < piece ? size - at : piece;
        fm_shdr_reader_feed(r, (const char *)data + at, n);
    }
    fm_shdr_reader_finish(r);
    fm_shdr_reader_free(r);
    return 0;
}
