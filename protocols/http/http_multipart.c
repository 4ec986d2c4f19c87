/* http_multipart.c: a bounded multipart/form-data parser (RFC 7578) for
 * large job uploads, and the assembly of a job from its parts. It works on
 * a body already read whole (the server caps its size), never copies part
 * data, and refuses anything it does not understand rather than guessing.
 * Written here instead of using libmicrohttpd's PostProcessor, which has
 * open CVEs in Debian 12's version. */
#include <ctype.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <strings.h>

#include "http_server.h"

#define MULTIPART_MAX_BOUNDARY 70
#define MULTIPART_MAX_HEADERS 8192

static const char *find_bytes(const char *hay, size_t hay_len, const char *needle,
                              size_t needle_len)
{
    if (needle_len == 0 || hay_len < needle_len) return NULL;
    const char *end = hay + hay_len - needle_len;
    for (const char *p = hay; p <= end; p++) {
        p = memchr(p, needle[0], (size_t)(end - p) + 1);
        if (!p) return NULL;
        if (!memcmp(p, needle, needle_len)) return p;
    }
    return NULL;
}

/* The value of parameter name (e.g. boundary, name, filename) in a header
 * value like `form-data; name="job"; filename="a.ngc"`, unquoted, into out.
 * 1 if found. */
static int header_param(const char *value, size_t len, const char *name, char *out, size_t size)
{
    size_t name_len = strlen(name);
    size_t i = 0;
    while (i < len) {
        /* Skip to the next parameter after a ';'. */
        while (i < len && value[i] != ';') {
            if (value[i] == '"') { /* skip quoted text, which may contain ';' */
                i++;
                while (i < len && value[i] != '"') i += value[i] == '\\' ? 2 : 1;
            }
            i++;
        }
        if (i >= len) return 0;
        i++;
        while (i < len && (value[i] == ' ' || value[i] == '\t')) i++;
        if (len - i > name_len && !strncasecmp(value + i, name, name_len) &&
            value[i + name_len] == '=') {
            i += name_len + 1;
            size_t n = 0;
            if (i < len && value[i] == '"') {
                i++;
                while (i < len && value[i] != '"') {
                    if (value[i] == '\\' && i + 1 < len) i++;
                    if (n + 1 >= size) return 0;
                    out[n++] = value[i++];
                }
                if (i >= len) return 0; /* unterminated quote */
            } else {
                while (i < len && value[i] != ';' && value[i] != ' ' && value[i] != '\t') {
                    if (n + 1 >= size) return 0;
                    out[n++] = value[i++];
                }
            }
            out[n] = '\0';
            return 1;
        }
    }
    return 0;
}

/* Parse one part's header block [p, end) into part. */
static int part_headers(const char *p, const char *end, fm_http_part *part, fm_http_error *err)
{
    int has_disposition = 0;
    while (p < end) {
        const char *eol = memchr(p, '\n', (size_t)(end - p));
        const char *line_end = eol ? eol : end;
        size_t n = (size_t)(line_end - p);
        if (n > 0 && p[n - 1] == '\r') n--;
        const char *colon = memchr(p, ':', n);
        if (!colon) {
            fm_http_error_set(err, 400, "bad_multipart", "a part header line has no ':'");
            return 0;
        }
        size_t name_len = (size_t)(colon - p);
        const char *v = colon + 1;
        size_t vlen = n - name_len - 1;
        while (vlen && (*v == ' ' || *v == '\t')) v++, vlen--;
        if (name_len == 19 && !strncasecmp(p, "Content-Disposition", 19)) {
            if (vlen < 9 || strncasecmp(v, "form-data", 9) != 0) {
                fm_http_error_set(err, 400, "bad_multipart",
                                  "a part's Content-Disposition is not form-data");
                return 0;
            }
            if (!header_param(v, vlen, "name", part->name, sizeof part->name)) {
                fm_http_error_set(err, 400, "bad_multipart",
                                  "a part has no name (or one over %zu characters)",
                                  sizeof part->name - 1);
                return 0;
            }
            if (!header_param(v, vlen, "filename", part->filename, sizeof part->filename))
                part->filename[0] = '\0';
            has_disposition = 1;
        } else if (name_len == 12 && !strncasecmp(p, "Content-Type", 12)) {
            if (vlen >= sizeof part->content_type) vlen = sizeof part->content_type - 1;
            memcpy(part->content_type, v, vlen);
            part->content_type[vlen] = '\0';
        }
        p = eol ? eol + 1 : end;
    }
    if (!has_disposition) {
        fm_http_error_set(err, 400, "bad_multipart", "a part has no Content-Disposition header");
        return 0;
    }
    return 1;
}

int fm_http_multipart_parse(const char *content_type, const char *body, size_t len,
                            fm_http_part *parts, int max_parts, fm_http_error *err)
{
    if (!content_type || strncasecmp(content_type, "multipart/form-data", 19) != 0) {
        fm_http_error_set(err, 400, "bad_multipart", "the Content-Type is not multipart/form-data");
        return -1;
    }
    char boundary[MULTIPART_MAX_BOUNDARY + 1];
    if (!header_param(content_type, strlen(content_type), "boundary", boundary, sizeof boundary) ||
        !boundary[0]) {
        fm_http_error_set(err, 400, "bad_multipart",
                          "the Content-Type has no boundary of 1 to %d characters",
                          MULTIPART_MAX_BOUNDARY);
        return -1;
    }
    /* Delimiters are "--boundary"; inside the body each follows a CRLF. */
    char delim[MULTIPART_MAX_BOUNDARY + 5];
    int dlen = snprintf(delim, sizeof delim, "\r\n--%s", boundary);
    const char *end = body + len;
    const char *p;
    if (len >= (size_t)dlen - 2 && !memcmp(body, delim + 2, (size_t)dlen - 2)) {
        p = body + dlen - 2;
    } else {
        const char *first = find_bytes(body, len, delim, (size_t)dlen);
        if (!first) {
            fm_http_error_set(err, 400, "bad_multipart", "the body has no boundary line");
            return -1;
        }
        p = first + dlen;
    }
    int count = 0;
    for (;;) {
        /* p is just after a delimiter: "--" ends the body, CRLF starts a part. */
        if (end - p >= 2 && p[0] == '-' && p[1] == '-') return count;
        while (p < end && (*p == ' ' || *p == '\t')) p++; /* transport padding */
        if (end - p >= 2 && p[0] == '\r' && p[1] == '\n') {
            p += 2;
        } else {
            fm_http_error_set(err, 400, "bad_multipart",
                              "a boundary line is not followed by CRLF or \"--\"");
            return -1;
        }
        size_t window = (size_t)(end - p);
        if (window > MULTIPART_MAX_HEADERS + 4) window = MULTIPART_MAX_HEADERS + 4;
        const char *blank = find_bytes(p, window, "\r\n\r\n", 4);
        const char *headers_end;
        const char *data;
        if (window >= 2 && p[0] == '\r' && p[1] == '\n') { /* no headers at all */
            headers_end = p;
            data = p + 2;
        } else if (blank) {
            headers_end = blank;
            data = blank + 4;
        } else {
            fm_http_error_set(err, 400, "bad_multipart",
                              "a part's headers do not end within %d bytes",
                              MULTIPART_MAX_HEADERS);
            return -1;
        }
        if (count == max_parts) {
            fm_http_error_set(err, 413, "too_many_parts", "more than %d parts", max_parts);
            return -1;
        }
        fm_http_part *part = &parts[count];
        memset(part, 0, sizeof *part);
        if (!part_headers(p, headers_end, part, err)) return -1;
        const char *next = find_bytes(data, (size_t)(end - data), delim, (size_t)dlen);
        if (!next) {
            fm_http_error_set(err, 400, "bad_multipart",
                              "the body ends inside part \"%s\" (no closing boundary)",
                              part->name);
            return -1;
        }
        part->data = data;
        part->size = (size_t)(next - data);
        count++;
        p = next + dlen;
    }
}

static int has_suffix(const char *s, const char *suffix)
{
    size_t n = strlen(s), m = strlen(suffix);
    return n >= m && !strcasecmp(s + n - m, suffix);
}

json_t *fm_http_job_from_multipart(const fm_http_part *parts, int count, fm_http_error *err)
{
    const fm_http_part *job = NULL, *program = NULL, *tools = NULL;
    for (int i = 0; i < count; i++) {
        const fm_http_part *p = &parts[i];
        const fm_http_part **slot = !strcmp(p->name, "job") || !strcmp(p->name, "spec") ? &job
                                    : !strcmp(p->name, "program")                       ? &program
                                    : !strcmp(p->name, "tools")                         ? &tools
                                                                                        : NULL;
        if (!slot) {
            fm_http_error_set(err, 400, "bad_multipart",
                              "unknown part \"%s\" (known: job, program, tools)", p->name);
            return NULL;
        }
        if (*slot) {
            fm_http_error_set(err, 400, "bad_multipart", "part \"%s\" given twice", p->name);
            return NULL;
        }
        *slot = p;
    }
    if (!job) {
        fm_http_error_set(err, 400, "bad_multipart", "no \"job\" part with the JSON job");
        return NULL;
    }
    json_error_t jerr;
    json_t *root = json_loadb(job->data, job->size, JSON_REJECT_DUPLICATES, &jerr);
    if (!root || !json_is_object(root)) {
        fm_http_error_set(err, 400, "bad_json", "the job part is not a JSON object%s%s",
                          root ? "" : ": ", root ? "" : jerr.text);
        if (!root && err) {
            err->line = jerr.line > 0 ? jerr.line : 0;
            err->column = jerr.column > 0 ? jerr.column : 0;
        }
        json_decref(root);
        return NULL;
    }
    if (tools) {
        json_t *t = json_loadb(tools->data, tools->size, JSON_REJECT_DUPLICATES, &jerr);
        if (!t) {
            fm_http_error_set(err, 400, "bad_json", "the tools part is not valid JSON: %s",
                              jerr.text);
            if (err) {
                err->line = jerr.line > 0 ? jerr.line : 0;
                err->column = jerr.column > 0 ? jerr.column : 0;
            }
            json_decref(root);
            return NULL;
        }
        json_object_set_new(root, "tools", t);
    }
    if (program) {
        json_t *prog;
        if (has_suffix(program->filename, ".json")) {
            json_t *t = json_loadb(program->data, program->size, JSON_REJECT_DUPLICATES, &jerr);
            if (!t) {
                fm_http_error_set(err, 400, "bad_json",
                                  "the program part (a trajectory) is not valid JSON: %s",
                                  jerr.text);
                if (err) {
                    err->line = jerr.line > 0 ? jerr.line : 0;
                    err->column = jerr.column > 0 ? jerr.column : 0;
                }
                json_decref(root);
                return NULL;
            }
            prog = json_pack("{s:o}", "trajectory", t);
        } else {
            json_t *text = memchr(program->data, '\0', program->size)
                               ? NULL
                               : json_stringn(program->data, program->size);
            if (!text) {
                fm_http_error_set(err, 400, "bad_program",
                                  "the program part is not UTF-8 text without NUL characters");
                json_decref(root);
                return NULL;
            }
            prog = json_pack("{s:o}", "gcode", text);
        }
        json_object_set_new(root, "program", prog);
    }
    /* Validated by the service, like a JSON body: both forms obey the same
     * rules. */
    return root;
}
