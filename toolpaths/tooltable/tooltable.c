/* tooltable.c: JSON and LinuxCNC .tbl tool tables -> fm_tool_table, with a
 * clear error for every field that is missing, mistyped or out of range;
 * the loader that tells every format apart by content, and what the other
 * readers (fusion.c, freecad.c, camotics.c, comments.c) share. */
#include "tooltable.h"
#include "tooltable_internal.h"

#include <ctype.h>
#include <stdarg.h>
#include <errno.h>
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static const char *shape_names[] = {"flat", "ball", "bull", "vbit", "drill",
                                    "tapered", "dovetail", "lollipop", "hyperfun"};
#define NSHAPES ((int)(sizeof shape_names / sizeof shape_names[0]))

/* ------------------------------------------------------------------ */
/* JSON                                                                */

typedef struct jctx {
    const char *name;
    fm_error *err;
    double unit;
    int index;  /* position in "tools" */
    int number; /* T number once known, else -1 */
} jctx;

static fm_status tool_fail(jctx *c, const char *field, const char *fmt, const char *detail)
{
    char where[64];
    if (c->number >= 0) snprintf(where, sizeof where, "tool %d (tools[%d])", c->number, c->index);
    else snprintf(where, sizeof where, "tools[%d]", c->index);
    return fm_error_at(c->err, FM_ERR_INPUT, c->name, 0, 0, "%s: field \"%s\": %s%s", where, field,
                       fmt, detail ? detail : "");
}

/* A number field: required or default; scaled by the table's unit when it
 * is a length; checked against [lo, hi] (hi < lo: no upper bound). */
static fm_status get_num(jctx *c, json_t *tool, const char *field, int required, double def,
                         int is_length, double lo, int lo_open, double hi, double *out)
{
    json_t *v = json_object_get(tool, field);
    if (!v) {
        if (required) return tool_fail(c, field, "missing; expected a number", NULL);
        *out = is_length ? def * c->unit : def; /* defaults are given in the table's unit */
        return FM_OK;
    }
    if (!json_is_number(v)) return tool_fail(c, field, "not a number", NULL);
    double x = json_number_value(v);
    char detail[96];
    if (!isfinite(x)) return tool_fail(c, field, "not a finite number", NULL);
    if (lo_open ? !(x > lo) : !(x >= lo)) {
        snprintf(detail, sizeof detail, " (got %g)", x);
        return tool_fail(c, field, lo_open ? (lo == 0 ? "must be positive" : "below its range")
                                           : (lo == 0 ? "must not be negative" : "below its range"),
                         detail);
    }
    if (hi >= lo && x > hi) {
        snprintf(detail, sizeof detail, " (got %g, at most %g)", x, hi);
        return tool_fail(c, field, "too large", detail);
    }
    *out = is_length ? x * c->unit : x;
    return FM_OK;
}

static int allowed(const char *key, const char *const *list)
{
    for (; *list; list++)
        if (!strcmp(key, *list)) return 1;
    return 0;
}

static fm_status parse_tool(jctx *c, json_t *t, fm_tool_spec *s)
{
    static const char *const fields[] = {
        "number", "shape", "diameter", "flute_length", "length", "shank_diameter", "holder",
        "center_cutting", "corner_radius", "angle", "tip_diameter", "point_angle",
        "taper_angle", "tip_radius", "neck_diameter", "file", "bound_radius", "length_offset",
        "radius_offset", "radius_wear", "comment", NULL};
    fm_status st;
    memset(s, 0, sizeof *s);
    c->number = -1;
    if (!json_is_object(t))
        return fm_error_at(c->err, FM_ERR_INPUT, c->name, 0, 0,
                           "tools[%d]: expected an object {\"number\": ..., \"shape\": ...}",
                           c->index);
    json_t *num = json_object_get(t, "number");
    if (!num) return tool_fail(c, "number", "missing; expected the T number", NULL);
    if (!json_is_integer(num) || json_integer_value(num) < 1 || json_integer_value(num) > 99999)
        return tool_fail(c, "number", "expected an integer from 1 to 99999", NULL);
    s->number = (int)json_integer_value(num);
    c->number = s->number;
    const char *key;
    json_t *val;
    json_object_foreach(t, key, val) {
        if (!allowed(key, fields))
            return tool_fail(c, key, "unknown field; expected one of number, shape, diameter, "
                             "flute_length, length, shank_diameter, holder, center_cutting, "
                             "corner_radius, angle, tip_diameter, point_angle, taper_angle, "
                             "tip_radius, neck_diameter, file, bound_radius, length_offset, "
                             "radius_offset, radius_wear, comment", NULL);
    }
    json_t *shape = json_object_get(t, "shape");
    if (!shape) return tool_fail(c, "shape", "missing; expected flat, ball, bull, vbit, drill, "
                                 "tapered, dovetail, lollipop or hyperfun", NULL);
    if (!json_is_string(shape)) return tool_fail(c, "shape", "expected a string", NULL);
    int k = -1;
    for (int i = 0; i < NSHAPES; i++)
        if (!strcmp(json_string_value(shape), shape_names[i])) k = i;
    if (k < 0) {
        char d[192];
        snprintf(d, sizeof d, " \"%.40s\"; expected flat, ball, bull, vbit, drill, tapered, "
                 "dovetail, lollipop or hyperfun", json_string_value(shape));
        return tool_fail(c, "shape", "unknown shape", d);
    }
    s->shape = (fm_tool_shape)k;
    if ((st = get_num(c, t, "diameter", 1, 0, 1, 0, 1, -1, &s->diameter))) return st;
    if ((st = get_num(c, t, "flute_length", 1, 0, 1, 0, 1, -1, &s->flute_length))) return st;
    if ((st = get_num(c, t, "length", 1, 0, 1, 0, 1, -1, &s->length))) return st;
    if (s->flute_length > s->length + 1e-9)
        return tool_fail(c, "flute_length", "longer than the tool's length (stick-out)", NULL);
    if ((st = get_num(c, t, "shank_diameter", 0, s->diameter / c->unit, 1, 0, 1, -1,
                      &s->shank_diameter)))
        return st;
    if ((st = get_num(c, t, "length_offset", 0, 0, 1, -1e9, 0, 1e9, &s->length_offset))) return st;
    if ((st = get_num(c, t, "radius_offset", 0, 0, 1, 0, 0, 1e6, &s->radius_offset))) return st;
    if ((st = get_num(c, t, "radius_wear", 0, 0, 1, -1e6, 0, 1e6, &s->radius_wear))) return st;
    json_t *cc = json_object_get(t, "center_cutting");
    s->center_cutting = 1;
    if (cc) {
        if (!json_is_boolean(cc)) return tool_fail(c, "center_cutting", "expected true or false", NULL);
        s->center_cutting = json_is_true(cc);
    }
    double r = s->diameter / 2;
    switch (s->shape) {
    case FM_TOOL_BULL:
        if ((st = get_num(c, t, "corner_radius", 1, 0, 1, 0, 1, -1, &s->corner_radius))) return st;
        if (s->corner_radius > r + 1e-12)
            return tool_fail(c, "corner_radius", "larger than the tool radius (diameter / 2)", NULL);
        break;
    case FM_TOOL_VBIT:
        if ((st = get_num(c, t, "angle", 1, 0, 0, 0, 1, 180, &s->angle))) return st;
        if (s->angle >= 180) return tool_fail(c, "angle", "expected an included angle below 180", NULL);
        if ((st = get_num(c, t, "tip_diameter", 0, 0, 1, 0, 0, -1, &s->tip_diameter))) return st;
        if (s->tip_diameter >= s->diameter)
            return tool_fail(c, "tip_diameter", "not smaller than the diameter", NULL);
        break;
    case FM_TOOL_DRILL:
        if ((st = get_num(c, t, "point_angle", 1, 0, 0, 0, 1, 180, &s->point_angle))) return st;
        if (s->point_angle >= 180)
            return tool_fail(c, "point_angle", "expected an included angle below 180", NULL);
        break;
    case FM_TOOL_TAPERED:
        if ((st = get_num(c, t, "taper_angle", 1, 0, 0, 0, 1, 90, &s->taper_angle))) return st;
        if (s->taper_angle >= 90)
            return tool_fail(c, "taper_angle", "expected an angle per side below 90", NULL);
        if ((st = get_num(c, t, "tip_radius", 0, 0, 1, 0, 0, -1, &s->tip_radius))) return st;
        if (s->tip_radius > r)
            return tool_fail(c, "tip_radius", "larger than the tool radius (diameter / 2)", NULL);
        break;
    case FM_TOOL_DOVETAIL:
        if ((st = get_num(c, t, "angle", 1, 0, 0, 0, 1, 90, &s->angle))) return st;
        if (s->angle >= 90) return tool_fail(c, "angle", "expected an angle below 90", NULL);
        /* a dovetail has a neck too */
        __attribute__((fallthrough));
    case FM_TOOL_LOLLIPOP:
        if ((st = get_num(c, t, "neck_diameter", 1, 0, 1, 0, 1, -1, &s->neck_diameter))) return st;
        if (s->neck_diameter >= s->diameter)
            return tool_fail(c, "neck_diameter", "not smaller than the diameter", NULL);
        break;
    case FM_TOOL_HYPERFUN: {
        json_t *f = json_object_get(t, "file");
        if (!f) return tool_fail(c, "file", "missing; expected the HyperFun model's path", NULL);
        if (!json_is_string(f) || !json_string_value(f)[0])
            return tool_fail(c, "file", "expected a non-empty string", NULL);
        if (strlen(json_string_value(f)) >= sizeof s->hyperfun_file)
            return tool_fail(c, "file", "path longer than 255 characters", NULL);
        snprintf(s->hyperfun_file, sizeof s->hyperfun_file, "%s", json_string_value(f));
        if ((st = get_num(c, t, "bound_radius", 1, 0, 1, 0, 1, -1, &s->bound_radius))) return st;
        break;
    }
    default: break;
    }
    json_t *cm = json_object_get(t, "comment");
    if (cm) {
        if (!json_is_string(cm)) return tool_fail(c, "comment", "expected a string", NULL);
        snprintf(s->comment, sizeof s->comment, "%s", json_string_value(cm));
    }
    json_t *h = json_object_get(t, "holder");
    if (h) {
        if (!json_is_array(h)) return tool_fail(c, "holder", "expected an array of segments", NULL);
        if (json_array_size(h) > FM_TOOL_MAX_HOLDER)
            return tool_fail(c, "holder", "more than 8 segments", NULL);
        size_t i;
        json_t *seg;
        json_array_foreach(h, i, seg) {
            char field[64];
            static const char *const sf[] = {"diameter", "diameter_top", "length", NULL};
            if (!json_is_object(seg)) {
                snprintf(field, sizeof field, "holder[%zu]", i);
                return tool_fail(c, field, "expected {\"diameter\": ..., \"length\": ...}", NULL);
            }
            json_object_foreach(seg, key, val) {
                if (!allowed(key, sf)) {
                    snprintf(field, sizeof field, "holder[%zu].%.30s", i, key);
                    return tool_fail(c, field, "unknown field; expected diameter, diameter_top, "
                                     "length", NULL);
                }
            }
            fm_holder_segment *hs = &s->holder[i];
            snprintf(field, sizeof field, "holder[%zu].diameter", i);
            json_t *d = json_object_get(seg, "diameter");
            /* reuse get_num on the segment object with a readable field name */
            jctx sub = *c;
            fm_status s2;
            if (!d) return tool_fail(c, field, "missing; expected a number", NULL);
            if ((s2 = get_num(&sub, seg, "diameter", 1, 0, 1, 0, 1, -1, &hs->diameter)))
                return tool_fail(c, field, "must be a positive number", NULL);
            if ((s2 = get_num(&sub, seg, "length", 1, 0, 1, 0, 1, -1, &hs->length))) {
                snprintf(field, sizeof field, "holder[%zu].length", i);
                return tool_fail(c, field, "missing or not a positive number", NULL);
            }
            if ((s2 = get_num(&sub, seg, "diameter_top", 0, hs->diameter / c->unit, 1, 0, 0, -1,
                              &hs->diameter_top))) {
                snprintf(field, sizeof field, "holder[%zu].diameter_top", i);
                return tool_fail(c, field, "not a non-negative number", NULL);
            }
        }
        s->holder_count = (int)json_array_size(h);
    }
    return FM_OK;
}

/* frepmill's own JSON form, already parsed. */
static fm_status frepmill_from_json(json_t *root, const char *name, fm_tool_table *out,
                                    fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    out->count = 0;
    out->tools = NULL;
    if (!name) name = "";
    fm_status st = FM_OK;
    jctx c = {name, err, 1.0, 0, -1};
    if (!json_is_object(root)) {
        st = fm_error_at(err, FM_ERR_INPUT, name, 0, 0,
                         "expected an object {\"units\": ..., \"tools\": [...]}");
        goto done;
    }
    const char *key;
    json_t *val;
    json_object_foreach(root, key, val) {
        if (strcmp(key, "units") && strcmp(key, "tools") && strcmp(key, "comment")) {
            st = fm_error_at(err, FM_ERR_INPUT, name, 0, 0,
                             "unknown top-level field \"%.40s\"; expected units, tools", key);
            goto done;
        }
    }
    json_t *units = json_object_get(root, "units");
    if (units) {
        const char *u = json_is_string(units) ? json_string_value(units) : "";
        if (!strcmp(u, "mm")) c.unit = 1.0;
        else if (!strcmp(u, "inch") || !strcmp(u, "in")) c.unit = 25.4;
        else {
            st = fm_error_at(err, FM_ERR_INPUT, name, 0, 0,
                             "field \"units\": expected \"mm\" or \"inch\"");
            goto done;
        }
    }
    json_t *tools = json_object_get(root, "tools");
    if (!json_is_array(tools)) {
        st = fm_error_at(err, FM_ERR_INPUT, name, 0, 0,
                         "field \"tools\": %s; expected an array of tools",
                         tools ? "not an array" : "missing");
        goto done;
    }
    size_t n = json_array_size(tools);
    if (n > FM_TOOLTABLE_MAX_TOOLS) {
        st = fm_error_at(err, FM_ERR_LIMIT, name, 0, 0, "more than %d tools",
                         FM_TOOLTABLE_MAX_TOOLS);
        goto done;
    }
    out->tools = calloc(n ? n : 1, sizeof *out->tools);
    if (!out->tools) {
        st = fm_error_set(err, FM_ERR_LIMIT, "out of memory for %zu tools", n);
        goto done;
    }
    for (size_t i = 0; i < n; i++) {
        c.index = (int)i;
        if ((st = parse_tool(&c, json_array_get(tools, i), &out->tools[i]))) goto done;
        for (size_t j = 0; j < i; j++)
            if (out->tools[j].number == out->tools[i].number) {
                st = fm_error_at(err, FM_ERR_INPUT, name, 0, 0,
                                 "tools[%zu]: duplicate tool number %d (also tools[%zu])", i,
                                 out->tools[i].number, j);
                goto done;
            }
        out->count = i + 1;
    }
done:
    if (st) fm_tool_table_free(out);
    return st;
}


fm_status fm_tooltable_parse_json(const char *text, size_t len, const char *name,
                                  fm_tool_table *out, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    out->count = 0;
    out->tools = NULL;
    if (!name) name = "";
    if (len > FM_TOOLTABLE_MAX_BYTES)
        return fm_error_at(err, FM_ERR_LIMIT, name, 0, 0, "tool table larger than %u bytes",
                           FM_TOOLTABLE_MAX_BYTES);
    json_error_t je;
    json_t *root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &je);
    if (!root)
        return fm_error_at(err, FM_ERR_INPUT, name, je.line > 0 ? je.line : 0,
                           je.column > 0 ? je.column : 0, "invalid JSON: %s", je.text);
    fm_status st = frepmill_from_json(root, name, out, err);
    json_decref(root);
    return st;
}

/* ------------------------------------------------------------------ */
/* LinuxCNC .tbl                                                       */

int tt_has_word(const char *comment, const char *word)
{
    size_t n = strlen(word);
    for (const char *p = comment; (p = strstr(p, word)); p++) {
        int before = p == comment || !isalnum((unsigned char)p[-1]);
        int after = !isalnum((unsigned char)p[n]);
        if (before && after) return 1;
    }
    return 0;
}

fm_status fm_tooltable_parse_tbl(const char *text, size_t len, const char *name,
                                 fm_tool_table *out, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    out->count = 0;
    out->tools = NULL;
    if (!name) name = "";
    if (len > FM_TOOLTABLE_MAX_BYTES)
        return fm_error_at(err, FM_ERR_LIMIT, name, 0, 0, "tool table larger than %u bytes",
                           FM_TOOLTABLE_MAX_BYTES);
    size_t cap = 0;
    int line = 0;
    size_t i = 0;
    fm_status st = FM_OK;
    while (i < len) {
        line++;
        size_t e = i;
        while (e < len && text[e] != '\n') e++;
        fm_tool_spec s;
        memset(&s, 0, sizeof s);
        s.number = -1;
        s.center_cutting = 1;
        int have_d = 0;
        size_t p = i;
        while (p < e) {
            char ch = text[p];
            if (ch == ' ' || ch == '\t' || ch == '\r') { p++; continue; }
            if (ch == ';') {
                size_t n = e - p - 1;
                while (n && (text[p + 1 + n - 1] == '\r' || text[p + 1 + n - 1] == ' ')) n--;
                if (n >= sizeof s.comment) n = sizeof s.comment - 1;
                memcpy(s.comment, text + p + 1, n);
                s.comment[n] = '\0';
                break;
            }
            int col = (int)(p - i) + 1;
            char w = (char)toupper((unsigned char)ch);
            if (!strchr("TPXYZABCUVWDIJQ", w)) {
                st = fm_error_at(err, FM_ERR_INPUT, name, line, col,
                                 "unexpected '%c'; expected T, P, X..W, D, I, J, Q words or "
                                 "';' comment", ch);
                goto fail;
            }
            p++;
            char buf[64];
            size_t k = 0;
            while (p < e && k < sizeof buf - 1 &&
                   (isdigit((unsigned char)text[p]) || text[p] == '.' || text[p] == '+' ||
                    text[p] == '-' || text[p] == 'e' || text[p] == 'E'))
                buf[k++] = text[p++];
            buf[k] = '\0';
            char *end;
            errno = 0;
            double v = strtod(buf, &end);
            if (!k || *end || !isfinite(v)) {
                st = fm_error_at(err, FM_ERR_INPUT, name, line, col,
                                 "%c word without a valid number; expected e.g. %c1.5", w, w);
                goto fail;
            }
            switch (w) {
            case 'T':
                if (v < 1 || v > 99999 || floor(v) != v) {
                    st = fm_error_at(err, FM_ERR_INPUT, name, line, col,
                                     "T%g: expected a tool number from 1 to 99999", v);
                    goto fail;
                }
                s.number = (int)v;
                break;
            case 'D':
                if (v <= 0) {
                    st = fm_error_at(err, FM_ERR_INPUT, name, line, col,
                                     "D%g: expected a positive diameter", v);
                    goto fail;
                }
                s.diameter = v;
                have_d = 1;
                break;
            case 'Z': s.length_offset = v; break;
            default: break; /* pocket, other axis offsets, lathe data: not needed */
            }
        }
        if (s.number < 0) {
            /* blank and comment-only lines are fine; a tool line needs T */
            int blank = 1;
            for (size_t q = i; q < e && text[q] != ';'; q++)
                if (!isspace((unsigned char)text[q])) blank = 0;
            if (!blank) {
                st = fm_error_at(err, FM_ERR_INPUT, name, line, 1,
                                 "tool line without a T word; expected T<number>");
                goto fail;
            }
            i = e + 1;
            continue;
        }
        if (!have_d) {
            st = fm_error_at(err, FM_ERR_INPUT, name, line, 1,
                             "tool %d without a D word; expected its diameter D", s.number);
            goto fail;
        }
        char lower[128];
        size_t n = strlen(s.comment);
        for (size_t q = 0; q <= n; q++) lower[q] = (char)tolower((unsigned char)s.comment[q]);
        s.shape = FM_TOOL_FLAT;
        if (tt_has_word(lower, "ball")) s.shape = FM_TOOL_BALL;
        else if (tt_has_word(lower, "bull")) {
            s.shape = FM_TOOL_BULL;
            s.corner_radius = s.diameter / 4;
        } else if (tt_has_word(lower, "vbit") || tt_has_word(lower, "v-bit") || tt_has_word(lower, "chamfer")) {
            s.shape = FM_TOOL_VBIT;
            s.angle = 90;
        } else if (tt_has_word(lower, "drill")) {
            s.shape = FM_TOOL_DRILL;
            s.point_angle = 118;
        }
        /* a .tbl says nothing about lengths: assume a common stick-out */
        s.flute_length = 3 * s.diameter;
        s.length = 4 * s.diameter;
        s.shank_diameter = s.diameter;
        for (size_t q = 0; q < out->count; q++)
            if (out->tools[q].number == s.number) {
                st = fm_error_at(err, FM_ERR_INPUT, name, line, 1,
                                 "duplicate tool number %d (already defined)", s.number);
                goto fail;
            }
        if (out->count >= FM_TOOLTABLE_MAX_TOOLS) {
            st = fm_error_at(err, FM_ERR_LIMIT, name, line, 1, "more than %d tools",
                             FM_TOOLTABLE_MAX_TOOLS);
            goto fail;
        }
        if (out->count == cap) {
            size_t nc = cap ? cap * 2 : 16;
            fm_tool_spec *nt = realloc(out->tools, nc * sizeof *nt);
            if (!nt) {
                st = fm_error_set(err, FM_ERR_LIMIT, "out of memory");
                goto fail;
            }
            out->tools = nt;
            cap = nc;
        }
        out->tools[out->count++] = s;
        i = e + 1;
    }
    return FM_OK;
fail:
    fm_tool_table_free(out);
    return st;
}

/* ------------------------------------------------------------------ */
/* What the readers share                                              */

void tt_warn(const tt_reader *r, const char *fmt, ...)
{
    if (!r->opt || !r->opt->warning) return;
    char msg[768];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    r->opt->warning(r->opt->warning_user, msg);
}

void tt_copy(char *dst, size_t size, const char *src)
{
    snprintf(dst, size, "%s", src ? src : "");
}

int tt_same(const char *a, const char *b)
{
    for (; *a && *b; a++, b++)
        if (tolower((unsigned char)*a) != tolower((unsigned char)*b)) return 0;
    return *a == *b;
}

fm_status tt_validate(const tt_reader *r, const fm_tool_spec *s, const char *where)
{
    fm_error e;
    fm_error_clear(&e);
    if (fm_tool_validate(s, &e) == FM_OK) return FM_OK;
    return fm_error_at(r->err, FM_ERR_INPUT, r->name, 0, 0, "%s: %s", where, e.message);
}

fm_status tt_push(const tt_reader *r, fm_tool_table *t, size_t *cap, const fm_tool_spec *s,
                  const char *where)
{
    for (size_t i = 0; i < t->count; i++)
        if (t->tools[i].number == s->number)
            return fm_error_at(r->err, FM_ERR_INPUT, r->name, 0, 0,
                               "%s: duplicate tool number %d (also \"%.60s\")", where, s->number,
                               t->tools[i].comment);
    if (t->count >= FM_TOOLTABLE_MAX_TOOLS)
        return fm_error_at(r->err, FM_ERR_LIMIT, r->name, 0, 0, "more than %d tools",
                           FM_TOOLTABLE_MAX_TOOLS);
    if (t->count == *cap) {
        size_t nc = *cap ? *cap * 2 : 16;
        fm_tool_spec *nt = realloc(t->tools, nc * sizeof *nt);
        if (!nt) return fm_error_set(r->err, FM_ERR_LIMIT, "out of memory");
        t->tools = nt;
        *cap = nc;
    }
    t->tools[t->count++] = *s;
    return FM_OK;
}

fm_status tt_read_file(const char *path, size_t max, char **text, size_t *len, fm_error *err)
{
    return fm_file_read(path, "tool table", max, text, len, err);
}

/* ------------------------------------------------------------------ */
/* Telling the formats apart                                           */

typedef enum tt_format {
    TT_FREPMILL = 0,
    TT_FUSION,
    TT_FREECAD_BIT,
    TT_FREECAD_LIBRARY,
    TT_CAMOTICS
} tt_format;

/* By the keys: Fusion's "data"; FreeCAD's "shape" + "parameter" (a bit) or
 * "version" + "tools" [{"nr", "path"}] (a library); CAMotics' "tools" as an
 * object (a project) or an object of numbered tools; everything else is
 * frepmill's form (whose parser names what is wrong). */
static tt_format json_format(json_t *root)
{
    if (!json_is_object(root)) return TT_FREPMILL;
    if (json_object_get(root, "data")) return TT_FUSION;
    if (json_object_get(root, "shape") && json_object_get(root, "parameter")) return TT_FREECAD_BIT;
    json_t *tools = json_object_get(root, "tools");
    if (json_is_object(tools)) return TT_CAMOTICS;
    if (json_is_array(tools)) {
        json_t *first = json_array_get(tools, 0);
        if (json_object_get(root, "version") || json_object_get(first, "nr"))
            return TT_FREECAD_LIBRARY;
        return TT_FREPMILL;
    }
    if (!tools && json_object_size(root) > 0) {
        const char *key;
        json_t *v;
        json_object_foreach(root, key, v) {
            if (!key[0] || strspn(key, "0123456789") != strlen(key) || !json_is_object(v) ||
                !json_object_get(v, "shape"))
                return TT_FREPMILL;
        }
        return TT_CAMOTICS;
    }
    return TT_FREPMILL;
}

/* A JSON document in any of the formats; dir as parse_any's. */
static fm_status json_any(json_t *root, const char *name, const char *dir,
                          const fm_tooltable_options *opt, fm_tool_table *out, fm_error *err)
{
    out->count = 0;
    out->tools = NULL;
    if (!name) name = "";
    tt_reader r = {name, opt, err};
    fm_status st;
    switch (json_format(root)) {
    case TT_FUSION: st = tt_fusion_json(&r, root, out); break;
    case TT_FREECAD_LIBRARY: st = tt_freecad_library(&r, root, dir, out); break;
    case TT_CAMOTICS: st = tt_camotics(&r, root, out); break;
    case TT_FREECAD_BIT: {
        fm_tool_spec s;
        size_t cap = 0;
        tt_warn(&r, "%s: a single FreeCAD tool bit: taken as tool 1", name);
        st = tt_freecad_bit(&r, root, 1, &s, "bit");
        if (!st) st = tt_push(&r, out, &cap, &s, "bit");
        if (st) fm_tool_table_free(out);
        break;
    }
    default: st = frepmill_from_json(root, name, out, err); break;
    }
    return st;
}

fm_status fm_tooltable_from_json_with(json_t *root, const char *name,
                                      const fm_tooltable_options *opt, fm_tool_table *out,
                                      fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    return json_any(root, name, NULL, opt, out, err);
}

fm_status fm_tooltable_from_json(json_t *root, const char *name, fm_tool_table *out,
                                 fm_error *err)
{
    return fm_tooltable_from_json_with(root, name, NULL, out, err);
}

/* Content in memory; dir: the folder of the file it came from (NULL: not a
 * file). */
static fm_status parse_any(const char *data, size_t len, const char *name, const char *dir,
                           const fm_tooltable_options *opt, fm_tool_table *out, fm_error *err)
{
    out->count = 0;
    out->tools = NULL;
    if (!name) name = "";
    tt_reader r = {name, opt, err};
    if (len > FM_TOOLTABLE_MAX_BYTES)
        return fm_error_at(err, FM_ERR_LIMIT, name, 0, 0, "tool table larger than %u bytes",
                           FM_TOOLTABLE_MAX_BYTES);
    if (len >= 4 && !memcmp(data, "PK\x03\x04", 4)) return tt_fusion_zip(&r, data, len, out);
    size_t p = 0;
    while (p < len && isspace((unsigned char)data[p])) p++;
    if (p >= len || data[p] != '{') return fm_tooltable_parse_tbl(data, len, name, out, err);
    json_error_t je;
    json_t *root = json_loadb(data, len, JSON_REJECT_DUPLICATES, &je);
    if (!root)
        return fm_error_at(err, FM_ERR_INPUT, name, je.line > 0 ? je.line : 0,
                           je.column > 0 ? je.column : 0, "invalid JSON: %s", je.text);
    fm_status st = json_any(root, name, dir, opt, out, err);
    json_decref(root);
    return st;
}

fm_status fm_tooltable_parse(const char *data, size_t len, const char *name,
                             const fm_tooltable_options *opt, fm_tool_table *out, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    return parse_any(data, len, name, NULL, opt, out, err);
}

fm_status fm_tooltable_load_with(const char *path, const fm_tooltable_options *opt,
                                 fm_tool_table *out, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    out->count = 0;
    out->tools = NULL;
    char *text;
    size_t len;
    fm_status st = tt_read_file(path, FM_TOOLTABLE_MAX_BYTES, &text, &len, err);
    if (st) return st;
    char dir[1024];
    const char *slash = strrchr(path, '/');
    if (!slash) tt_copy(dir, sizeof dir, ".");
    else if (slash == path) tt_copy(dir, sizeof dir, "/");
    else snprintf(dir, sizeof dir, "%.*s", (int)(slash - path), path);
    st = parse_any(text, len, path, dir, opt, out, err);
    free(text);
    return st;
}

fm_status fm_tooltable_load(const char *path, fm_tool_table *out, fm_error *err)
{
    return fm_tooltable_load_with(path, NULL, out, err);
}
