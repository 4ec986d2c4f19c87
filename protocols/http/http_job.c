/* http_job.c: the job request of POST /v1/jobs: JSON parsing with jansson,
 * validation of every key into the canonical form the daemon stores, and
 * the clear errors a client gets back (syntax errors with their line and
 * column). Also base64 for uploaded STL stocks. */
#include <ctype.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "http_server.h"
#include "toolpaths/gcode/gcode.h"

int fm_http_error_set(fm_http_error *err, int status, const char *code, const char *fmt, ...)
{
    if (!err) return status;
    memset(err, 0, sizeof *err);
    err->status = status;
    snprintf(err->code, sizeof err->code, "%s", code);
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(err->message, sizeof err->message, fmt, ap);
    va_end(ap);
    return status;
}

/* ------------------------------------------------------------- base64 -- */

static int base64_value(unsigned char c)
{
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
}

int fm_http_base64_decode(const char *in, size_t len, uint8_t **out, size_t *out_len)
{
    *out = NULL;
    *out_len = 0;
    uint8_t *buf = malloc(len / 4 * 3 + 4);
    if (!buf) return -1;
    size_t n = 0;
    uint32_t acc = 0;
    int bits = 0, padding = 0;
    for (size_t i = 0; i < len; i++) {
        unsigned char c = (unsigned char)in[i];
        if (c == '\n' || c == '\r') continue;
        if (c == '=') {
            padding++;
            continue;
        }
        int v = base64_value(c);
        if (v < 0 || padding) { /* a character after padding is not base64 */
            free(buf);
            return -1;
        }
        acc = (acc << 6) | (uint32_t)v;
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            buf[n++] = (uint8_t)(acc >> bits);
        }
    }
    /* Leftover bits must be the zero padding of a short final group. */
    if (padding > 2 || bits >= 6 || (acc & ((1u << bits) - 1)) != 0) {
        free(buf);
        return -1;
    }
    *out = buf;
    *out_len = n;
    return 0;
}

/* ---------------------------------------------------------- validation -- */

static int only_keys(json_t *obj, const char *const *keys, const char *where, fm_http_error *err)
{
    const char *key;
    json_t *value;
    json_object_foreach(obj, key, value) {
        int known = 0;
        for (const char *const *k = keys; *k; k++)
            if (!strcmp(key, *k)) known = 1;
        if (!known) {
            char list[256] = "";
            for (const char *const *k = keys; *k; k++) {
                strncat(list, k == keys ? "" : ", ", sizeof list - strlen(list) - 1);
                strncat(list, *k, sizeof list - strlen(list) - 1);
            }
            fm_http_error_set(err, 400, "unknown_key", "%s: unknown key \"%s\" (known: %s)", where,
                              key, list);
            return 0;
        }
    }
    (void)value;
    return 1;
}

static int text_ok(json_t *v, const char *where, size_t max, fm_http_error *err)
{
    if (!json_is_string(v)) {
        fm_http_error_set(err, 400, "bad_type", "%s must be a string", where);
        return 0;
    }
    size_t n = json_string_length(v);
    if (n == 0) {
        fm_http_error_set(err, 400, "bad_value", "%s is empty", where);
        return 0;
    }
    if (n > max) {
        fm_http_error_set(err, 413, "too_large", "%s is %zu bytes; at most %zu", where, n, max);
        return 0;
    }
    if (memchr(json_string_value(v), '\0', n)) {
        fm_http_error_set(err, 400, "bad_value", "%s contains a NUL character", where);
        return 0;
    }
    return 1;
}

static int stock_ok(json_t *stock, fm_http_error *err)
{
    if (json_is_string(stock)) {
        if (!text_ok(stock, "stock", 4096, err)) return 0;
        const char *s = json_string_value(stock);
        /* Only shapes: a network client must never name a file on the
         * server (a .vdb or .hf path); models come inline. */
        if (strncmp(s, "box:", 4) != 0 && strncmp(s, "cylinder:", 9) != 0) {
            fm_http_error_set(err, 400, "bad_stock",
                              "stock \"%.64s\": expected \"box:X0,Y0,Z0,X1,Y1,Z1\", "
                              "\"cylinder:X,Y,Z0,Z1,R\", {\"hyperfun\": TEXT} or "
                              "{\"stl_base64\": TEXT}",
                              s);
            return 0;
        }
        return 1;
    }
    if (!json_is_object(stock) || json_object_size(stock) != 1) {
        fm_http_error_set(err, 400, "bad_stock",
                          "stock must be a spec string or an object with exactly one of "
                          "\"hyperfun\" and \"stl_base64\"");
        return 0;
    }
    static const char *const keys[] = {"hyperfun", "stl_base64", NULL};
    if (!only_keys(stock, keys, "stock", err)) return 0;
    json_t *hf = json_object_get(stock, "hyperfun");
    if (hf) return text_ok(hf, "stock.hyperfun", FM_HTTP_JOB_MAX_TEXT, err);
    json_t *stl = json_object_get(stock, "stl_base64");
    if (!text_ok(stl, "stock.stl_base64", FM_HTTP_JOB_MAX_TEXT, err)) return 0;
    uint8_t *bytes;
    size_t n;
    if (fm_http_base64_decode(json_string_value(stl), json_string_length(stl), &bytes, &n) != 0) {
        fm_http_error_set(err, 400, "bad_stock", "stock.stl_base64 is not valid base64");
        return 0;
    }
    free(bytes);
    if (n < 84) {
        fm_http_error_set(err, 400, "bad_stock",
                          "stock.stl_base64 decodes to %zu bytes, too short for an STL file", n);
        return 0;
    }
    return 1;
}

static int number_in(json_t *v, const char *where, double lo, double hi, double *out,
                     fm_http_error *err)
{
    if (!json_is_number(v)) {
        fm_http_error_set(err, 400, "bad_type", "%s must be a number", where);
        return 0;
    }
    double d = json_number_value(v);
    if (!isfinite(d) || d < lo || d > hi) {
        fm_http_error_set(err, 400, "bad_value", "%s = %g is outside [%g, %g]", where, d, lo, hi);
        return 0;
    }
    if (out) *out = d;
    return 1;
}

static int program_ok(json_t *program, fm_http_error *err)
{
    if (!json_is_object(program) || json_object_size(program) != 1) {
        fm_http_error_set(err, 400, "bad_program",
                          "program must be an object with exactly one of \"gcode\" (text) and "
                          "\"trajectory\" (object)");
        return 0;
    }
    static const char *const keys[] = {"gcode", "trajectory", NULL};
    if (!only_keys(program, keys, "program", err)) return 0;
    json_t *g = json_object_get(program, "gcode");
    if (g) return text_ok(g, "program.gcode", FM_HTTP_JOB_MAX_TEXT, err);
    if (!json_is_object(json_object_get(program, "trajectory"))) {
        fm_http_error_set(err, 400, "bad_type", "program.trajectory must be an object");
        return 0;
    }
    return 1;
}

static int fixtures_ok(json_t *fixtures, fm_http_error *err)
{
    if (!json_is_array(fixtures)) {
        fm_http_error_set(err, 400, "bad_type", "fixtures must be an array");
        return 0;
    }
    if (json_array_size(fixtures) > 64) {
        fm_http_error_set(err, 413, "too_large", "%zu fixtures; at most 64",
                          json_array_size(fixtures));
        return 0;
    }
    size_t i;
    json_t *f;
    json_array_foreach(fixtures, i, f) {
        char where[64];
        snprintf(where, sizeof where, "fixtures[%zu]", i);
        static const char *const keys[] = {"hyperfun", "stl_base64", "name", NULL};
        json_t *hf = json_is_object(f) ? json_object_get(f, "hyperfun") : NULL;
        json_t *stl = json_is_object(f) ? json_object_get(f, "stl_base64") : NULL;
        if (!hf == !stl) {
            fm_http_error_set(err, 400, "bad_fixture",
                              "%s must be {\"hyperfun\": TEXT} or {\"stl_base64\": TEXT}", where);
            return 0;
        }
        if (!only_keys(f, keys, where, err)) return 0;
        if (!text_ok(hf ? hf : stl, where, FM_HTTP_JOB_MAX_TEXT, err)) return 0;
        if (stl) {
            uint8_t *bytes;
            size_t n;
            if (fm_http_base64_decode(json_string_value(stl), json_string_length(stl), &bytes, &n)) {
                fm_http_error_set(err, 400, "bad_fixture", "%s.stl_base64 is not valid base64",
                                  where);
                return 0;
            }
            free(bytes);
        }
        json_t *name = json_object_get(f, "name");
        if (name && !text_ok(name, where, 128, err)) return 0;
    }
    return 1;
}

static int options_ok(json_t *options, fm_http_error *err)
{
    if (!json_is_object(options)) {
        fm_http_error_set(err, 400, "bad_type", "options must be an object");
        return 0;
    }
    static const char *const keys[] = {"name",    "band",  "batch",   "rapid_rate",
                                       "memory_budget_mb", "threads", "check", "color",
                                       "dialect", "calculator_input", NULL};
    if (!only_keys(options, keys, "options", err)) return 0;
    json_t *v;
    /* The members of a check object are the daemon's to validate (they
     * are lib/check's options); here only its shape. */
    if ((v = json_object_get(options, "check")) && !json_is_object(v) && !json_is_boolean(v)) {
        fm_http_error_set(err, 400, "bad_type",
                          "options.check must be false (no collision check) or an object");
        return 0;
    }
    if ((v = json_object_get(options, "name")) && !text_ok(v, "options.name", 128, err)) return 0;
    if ((v = json_object_get(options, "color")) &&
        (!json_is_string(v) ||
         (strcmp(json_string_value(v), "tool") && strcmp(json_string_value(v), "none")))) {
        fm_http_error_set(err, 400, "bad_value",
                          "options.color must be \"tool\" (colour the meshes by the tool that "
                          "cut last) or \"none\"");
        return 0;
    }
    fm_gcode_dialect dialect;
    if ((v = json_object_get(options, "dialect")) &&
        (!json_is_string(v) || !fm_gcode_dialect_parse(json_string_value(v), &dialect))) {
        fm_http_error_set(err, 400, "bad_value",
                          "options.dialect must be \"linuxcnc\" or \"fanuc\" (the program's G-code "
                          "dialect; without it the server's setting)");
        return 0;
    }
    if ((v = json_object_get(options, "calculator_input")) && !json_is_boolean(v)) {
        fm_http_error_set(err, 400, "bad_type",
                          "options.calculator_input must be true (Fanuc: X5 is 5 mm) or false");
        return 0;
    }
    if ((v = json_object_get(options, "band")) &&
        (!number_in(v, "options.band", 2, 32, NULL, err))) return 0;
    if (v && !json_is_integer(v)) {
        fm_http_error_set(err, 400, "bad_type", "options.band must be an integer");
        return 0;
    }
    if ((v = json_object_get(options, "batch")) &&
        !number_in(v, "options.batch", -1, 1000, NULL, err)) return 0;
    if ((v = json_object_get(options, "rapid_rate")) &&
        !number_in(v, "options.rapid_rate", 1e-3, 1e7, NULL, err)) return 0;
    if ((v = json_object_get(options, "memory_budget_mb")) &&
        !number_in(v, "options.memory_budget_mb", 1, 1e9, NULL, err)) return 0;
    if ((v = json_object_get(options, "threads")) &&
        (!number_in(v, "options.threads", 0, 1024, NULL, err))) return 0;
    if (v && !json_is_integer(v)) {
        fm_http_error_set(err, 400, "bad_type", "options.threads must be an integer");
        return 0;
    }
    return 1;
}

static json_t *job_validate(json_t *job, fm_http_error *err)
{
    if (!json_is_object(job)) {
        fm_http_error_set(err, 400, "bad_job", "the job must be a JSON object");
        return NULL;
    }
    static const char *const keys[] = {"stock", "voxel", "tools", "program", "fixtures",
                                       "options", NULL};
    if (!only_keys(job, keys, "job", err)) return NULL;
    static const char *const required[] = {"stock", "tools", "program"};
    for (int i = 0; i < 3; i++)
        if (!json_object_get(job, required[i])) {
            fm_http_error_set(err, 400, "missing_key", "the job has no \"%s\"", required[i]);
            return NULL;
        }
    if (!stock_ok(json_object_get(job, "stock"), err)) return NULL;
    double voxel = 0.1;
    json_t *v = json_object_get(job, "voxel");
    if (v && !number_in(v, "voxel", 0.001, 100, &voxel, err)) return NULL;
    if (!json_is_object(json_object_get(job, "tools"))) {
        fm_http_error_set(err, 400, "bad_type", "tools must be the JSON tool table (an object)");
        return NULL;
    }
    if (!program_ok(json_object_get(job, "program"), err)) return NULL;
    json_t *fixtures = json_object_get(job, "fixtures");
    if (fixtures && !fixtures_ok(fixtures, err)) return NULL;
    json_t *options = json_object_get(job, "options");
    if (options && !options_ok(options, err)) return NULL;

    /* The canonical form: every key present, defaults filled in. */
    json_t *out = json_object();
    json_object_set(out, "stock", json_object_get(job, "stock"));
    json_object_set_new(out, "voxel", json_real(voxel));
    json_object_set(out, "tools", json_object_get(job, "tools"));
    json_object_set(out, "program", json_object_get(job, "program"));
    json_object_set_new(out, "fixtures", fixtures ? json_incref(fixtures) : json_array());
    json_object_set_new(out, "options", options ? json_incref(options) : json_object());
    return out;
}

json_t *fm_http_job_parse(const char *text, size_t len, fm_http_error *err)
{
    if (len > FM_HTTP_JOB_MAX_TEXT * 2) {
        fm_http_error_set(err, 413, "too_large", "the job is %zu bytes; at most %zu", len,
                          FM_HTTP_JOB_MAX_TEXT * 2);
        return NULL;
    }
    json_error_t jerr;
    /* JSON_REJECT_DUPLICATES: two "program" keys are a mistake, not a choice. */
    json_t *job = json_loadb(text, len, JSON_REJECT_DUPLICATES, &jerr);
    if (!job) {
        fm_http_error_set(err, 400, "bad_json", "the job is not valid JSON: %s", jerr.text);
        if (err) {
            err->line = jerr.line > 0 ? jerr.line : 0;
            err->column = jerr.column > 0 ? jerr.column : 0;
        }
        return NULL;
    }
    json_t *out = job_validate(job, err);
    json_decref(job);
    return out;
}
