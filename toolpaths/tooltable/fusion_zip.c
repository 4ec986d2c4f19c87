/* fusion_zip.c: Fusion 360's .tools file, a zip archive holding the library
 * as tools.json, read from memory with libzip. A zip is a parser of its own
 * (docs/tooltable.md): at most TT_ZIP_MAX_ENTRIES entries, names checked
 * (no absolute path, no "..", no NUL or backslash: nothing is written to disk,
 * but an archive that tries is refused), one tools.json of at most
 * TT_ZIP_MAX_BYTES whatever its header claims, no encryption. */
#include "tooltable_internal.h"

#include <stdlib.h>
#include <string.h>
#include <zip.h>

static fm_status zfail(const tt_reader *r, fm_status code, const char *what, const char *detail)
{
    return fm_error_at(r->err, code, r->name, 0, 0, "Fusion .tools archive: %s%s", what,
                       detail ? detail : "");
}

/* An entry name that would escape a folder if extracted. */
static int unsafe_name(const char *n)
{
    if (!n[0] || n[0] == '/' || strchr(n, '\\') || strchr(n, ':')) return 1;
    for (const char *p = n; *p;) {
        const char *e = strchr(p, '/');
        size_t len = e ? (size_t)(e - p) : strlen(p);
        if (len == 2 && p[0] == '.' && p[1] == '.') return 1;
        if (!e) break;
        p = e + 1;
    }
    return 0;
}

fm_status tt_fusion_zip(const tt_reader *r, const void *data, size_t len, fm_tool_table *out)
{
    out->count = 0;
    out->tools = NULL;
    if (len > TT_ZIP_MAX_BYTES)
        return zfail(r, FM_ERR_LIMIT, "larger than the tool table limit", NULL);
    zip_error_t ze;
    zip_error_init(&ze);
    zip_source_t *src = zip_source_buffer_create(data, len, 0, &ze);
    if (!src) {
        zip_error_fini(&ze);
        return zfail(r, FM_ERR_LIMIT, "out of memory", NULL);
    }
    zip_t *z = zip_open_from_source(src, ZIP_RDONLY | ZIP_CHECKCONS, &ze);
    if (!z) {
        char detail[160];
        snprintf(detail, sizeof detail, " (%s)", zip_error_strerror(&ze));
        zip_source_free(src);
        zip_error_fini(&ze);
        return zfail(r, FM_ERR_INPUT, "not a readable zip", detail);
    }
    zip_error_fini(&ze);
    fm_status st = FM_OK;
    char *buf = NULL;
    zip_file_t *f = NULL;
    zip_int64_t n = zip_get_num_entries(z, 0), found = -1;
    if (n > TT_ZIP_MAX_ENTRIES) {
        char detail[64];
        snprintf(detail, sizeof detail, " (%lld; at most %d)", (long long)n, TT_ZIP_MAX_ENTRIES);
        st = zfail(r, FM_ERR_LIMIT, "too many entries", detail);
        goto done;
    }
    for (zip_int64_t i = 0; i < n; i++) {
        const char *name = zip_get_name(z, (zip_uint64_t)i, ZIP_FL_ENC_RAW);
        if (!name) {
            st = zfail(r, FM_ERR_INPUT, "an entry without a name", NULL);
            goto done;
        }
        if (unsafe_name(name)) {
            char detail[160];
            snprintf(detail, sizeof detail, " \"%.100s\": absolute, \"..\" or drive paths are refused",
                     name);
            st = zfail(r, FM_ERR_INPUT, "entry name", detail);
            goto done;
        }
        if (!strcmp(name, "tools.json")) {
            if (found >= 0) {
                st = zfail(r, FM_ERR_INPUT, "two entries named tools.json", NULL);
                goto done;
            }
            found = i;
        }
    }
    if (found < 0) {
        st = zfail(r, FM_ERR_INPUT, "no entry tools.json (the library a .tools file holds)", NULL);
        goto done;
    }
    zip_stat_t zs;
    zip_stat_init(&zs);
    if (zip_stat_index(z, (zip_uint64_t)found, 0, &zs) != 0) {
        st = zfail(r, FM_ERR_INPUT, "tools.json: unreadable entry header", NULL);
        goto done;
    }
    if ((zs.valid & ZIP_STAT_ENCRYPTION_METHOD) && zs.encryption_method != ZIP_EM_NONE) {
        st = zfail(r, FM_ERR_INPUT, "tools.json is encrypted", NULL);
        goto done;
    }
    if ((zs.valid & ZIP_STAT_COMP_METHOD) && !zip_compression_method_supported(zs.comp_method, 0)) {
        st = zfail(r, FM_ERR_INPUT, "tools.json: unsupported compression method", NULL);
        goto done;
    }
    if ((zs.valid & ZIP_STAT_SIZE) && zs.size > TT_ZIP_MAX_BYTES) {
        st = zfail(r, FM_ERR_LIMIT, "tools.json larger than the tool table limit", NULL);
        goto done;
    }
    f = zip_fopen_index(z, (zip_uint64_t)found, 0);
    if (!f) {
        st = zfail(r, FM_ERR_INPUT, "tools.json cannot be opened: ", zip_strerror(z));
        goto done;
    }
    /* read whatever the data inflates to, never more than the limit: the
     * header's size is not trusted */
    size_t cap = 1 << 16, got = 0;
    buf = malloc(cap);
    for (;;) {
        if (!buf) {
            st = zfail(r, FM_ERR_LIMIT, "out of memory", NULL);
            goto done;
        }
        if (got == cap) {
            if (cap > TT_ZIP_MAX_BYTES) {
                st = zfail(r, FM_ERR_LIMIT, "tools.json inflates beyond the tool table limit", NULL);
                goto done;
            }
            char *nb = realloc(buf, cap * 2);
            if (!nb) free(buf);
            buf = nb;
            cap *= 2;
            continue;
        }
        zip_int64_t k = zip_fread(f, buf + got, cap - got);
        if (k < 0) {
            st = zfail(r, FM_ERR_INPUT, "tools.json: ", zip_file_strerror(f));
            goto done;
        }
        if (k == 0) break;
        got += (size_t)k;
    }
    json_error_t je;
    json_t *root = json_loadb(buf, got, JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        st = fm_error_at(r->err, FM_ERR_INPUT, r->name, je.line > 0 ? je.line : 0,
                         je.column > 0 ? je.column : 0, "tools.json: invalid JSON: %s", je.text);
        goto done;
    }
    if (!json_is_object(root) || !json_is_array(json_object_get(root, "data")))
        st = zfail(r, FM_ERR_INPUT, "tools.json is not a Fusion tool library ({\"data\": [...]})",
                   NULL);
    else st = tt_fusion_json(r, root, out);
    json_decref(root);
done:
    free(buf);
    if (f) zip_fclose(f);
    zip_discard(z); /* frees src too */
    return st;
}
