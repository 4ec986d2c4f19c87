/* alloc_fail_libs.c: the library functions that do not survive an
 * allocation failure, with failure injection paused over them
 * (alloc_fail.h). Linked into the allocation-failure test, these
 * definitions take the place of the libraries' for every caller (the test's
 * own code and the shared libraries, which bind to the executable's
 * symbols), and call the library's own through dlsym(RTLD_NEXT).
 *   - jansson 2.14's JSON readers: lex_save drops strbuffer_append_byte's
 *     failure, after which the lexer asserts (assert(0) in lex_scan_string,
 *     assert(c == d) in lex_unget_unsave) or reads past its buffer
 *     (jansson issue 362, open since 2017).
 *   - c-blosc 1.21's compressor and decompressor (OpenVDB's snapshot codec):
 *     their temporary buffers are used without checking the allocation,
 *     and LZ4 then reads through a null pointer.
 * What the callers do with these functions' results, and every allocation
 * around them, is still failed in turn. */
#define _GNU_SOURCE
#include <dlfcn.h>
#include <jansson.h>
#include <stdio.h>
#include <stdlib.h>

#include "alloc_fail.h"

typedef json_t *(*loadb_fn)(const char *, size_t, size_t, json_error_t *);
typedef json_t *(*loads_fn)(const char *, size_t, json_error_t *);
typedef json_t *(*load_file_fn)(const char *, size_t, json_error_t *);
typedef json_t *(*loadf_fn)(FILE *, size_t, json_error_t *);
typedef int (*blosc_compress_fn)(int, int, size_t, size_t, const void *, void *, size_t, const char *, size_t,
                                 int);
typedef int (*blosc_decompress_fn)(const void *, void *, size_t, int);

static loadb_fn real_loadb;
static loads_fn real_loads;
static load_file_fn real_load_file;
static loadf_fn real_loadf;
static blosc_compress_fn real_blosc_compress;
static blosc_decompress_fn real_blosc_decompress;

static void *real(const char *name)
{
    void *f = dlsym(RTLD_NEXT, name);
    if (!f) {
        fprintf(stderr, "alloc_fail_libs: %s not found in the libraries\n", name);
        abort();
    }
    return f;
}

/* Resolved before main, so that dlsym's own allocations are never armed. */
__attribute__((constructor)) static void resolve(void)
{
    real_loadb = (loadb_fn)real("json_loadb");
    real_loads = (loads_fn)real("json_loads");
    real_load_file = (load_file_fn)real("json_load_file");
    real_loadf = (loadf_fn)real("json_loadf");
    real_blosc_compress = (blosc_compress_fn)real("blosc_compress_ctx");
    real_blosc_decompress = (blosc_decompress_fn)real("blosc_decompress_ctx");
}

json_t *json_loadb(const char *buffer, size_t buflen, size_t flags, json_error_t *error)
{
    alloc_fail_pause();
    json_t *j = real_loadb(buffer, buflen, flags, error);
    alloc_fail_resume();
    return j;
}

json_t *json_loads(const char *input, size_t flags, json_error_t *error)
{
    alloc_fail_pause();
    json_t *j = real_loads(input, flags, error);
    alloc_fail_resume();
    return j;
}

json_t *json_load_file(const char *path, size_t flags, json_error_t *error)
{
    alloc_fail_pause();
    json_t *j = real_load_file(path, flags, error);
    alloc_fail_resume();
    return j;
}

json_t *json_loadf(FILE *input, size_t flags, json_error_t *error)
{
    alloc_fail_pause();
    json_t *j = real_loadf(input, flags, error);
    alloc_fail_resume();
    return j;
}

int blosc_compress_ctx(int clevel, int doshuffle, size_t typesize, size_t nbytes, const void *src, void *dest,
                       size_t destsize, const char *compressor, size_t blocksize, int numinternalthreads);
int blosc_compress_ctx(int clevel, int doshuffle, size_t typesize, size_t nbytes, const void *src, void *dest,
                       size_t destsize, const char *compressor, size_t blocksize, int numinternalthreads)
{
    alloc_fail_pause();
    int r = real_blosc_compress(clevel, doshuffle, typesize, nbytes, src, dest, destsize, compressor, blocksize,
                                numinternalthreads);
    alloc_fail_resume();
    return r;
}

int blosc_decompress_ctx(const void *src, void *dest, size_t destsize, int numinternalthreads);
int blosc_decompress_ctx(const void *src, void *dest, size_t destsize, int numinternalthreads)
{
    alloc_fail_pause();
    int r = real_blosc_decompress(src, dest, destsize, numinternalthreads);
    alloc_fail_resume();
    return r;
}
