/* camotics.c: CAMotics tool tables -> fm_tool_table: the "tools" object of
 * a .camotics project ({"units": ..., "tools": {"1": {...}}, ...}) or a tool
 * table alone ({"1": {...}, "2": {...}}). Each tool: number, units, shape
 * (CYLINDRICAL, CONICAL, BALLNOSE, SPHEROID, SNUBNOSE), length, diameter,
 * snub_diameter, description (docs/tooltable.md). */
#include "tooltable_internal.h"

#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#define DEG (3.14159265358979323846 / 180.0)

static fm_status cfail(const tt_reader *r, const char *where, const char *field, const char *what)
{
    return fm_error_at(r->err, FM_ERR_INPUT, r->name, 0, 0, "%s: field \"%s\": %s", where, field,
                       what);
}

/* "mm", "metric" -> 1; "inch", "imperial" -> 25.4; else 0. */
static double unit_of(json_t *u)
{
    const char *s = json_is_string(u) ? json_string_value(u) : "";
    if (tt_same(s, "mm") || tt_same(s, "metric")) return 1.0;
    if (tt_same(s, "inch") || tt_same(s, "in") || tt_same(s, "imperial")) return 25.4;
    return 0;
}

static fm_status length(const tt_reader *r, const char *where, json_t *t, const char *key,
                        double unit, int required, double *out)
{
    json_t *v = json_object_get(t, key);
    if (!v) return required ? cfail(r, where, key, "missing; expected a number") : FM_OK;
    if (!json_is_number(v) || !isfinite(json_number_value(v)))
        return cfail(r, where, key, "not a number");
    if (!(json_number_value(v) > 0)) return cfail(r, where, key, "must be positive");
    *out = json_number_value(v) * unit;
    return FM_OK;
}

static fm_status tool(const tt_reader *r, const char *key, json_t *t, double unit0,
                      fm_tool_spec *s)
{
    char where[160];
    memset(s, 0, sizeof *s);
    s->center_cutting = 1;
    json_t *d = json_object_get(t, "description");
    tt_copy(s->comment, sizeof s->comment, json_is_string(d) ? json_string_value(d) : "");
    snprintf(where, sizeof where, "tools[\"%.20s\"] (\"%.60s\")", key, s->comment);
    if (!json_is_object(t)) return cfail(r, where, key, "expected a tool object");
    /* the number is the key; a "number" field, when there, must agree */
    char *end;
    long k = strtol(key, &end, 10);
    json_t *num = json_object_get(t, "number");
    if (*end || k < 1 || k > 99999)
        return cfail(r, where, "number", "the tool's key must be its number, 1 to 99999");
    if (num && (!json_is_integer(num) || json_integer_value(num) != k))
        return cfail(r, where, "number", "differs from the tool's key");
    s->number = (int)k;
    snprintf(where, sizeof where, "tools[\"%.20s\"] (T%d \"%.60s\")", key, s->number, s->comment);
    double unit = unit0;
    json_t *u = json_object_get(t, "units");
    if (u && !(unit = unit_of(u)))
        return cfail(r, where, "units", "expected \"mm\" or \"inch\" (\"metric\", \"imperial\")");
    json_t *sh = json_object_get(t, "shape");
    if (!json_is_string(sh))
        return cfail(r, where, "shape", sh ? "expected a string" : "missing; expected CYLINDRICAL, "
                     "CONICAL, BALLNOSE, SPHEROID or SNUBNOSE");
    const char *shape = json_string_value(sh);
    fm_status st;
    if ((st = length(r, where, t, "diameter", unit, 1, &s->diameter)) ||
        (st = length(r, where, t, "length", unit, 1, &s->length)))
        return st;
    /* CAMotics' tool is its cutting part alone: no shank, no holder */
    s->flute_length = s->length;
    s->shank_diameter = s->diameter;
    double rad = s->diameter / 2;
    if (tt_same(shape, "cylindrical")) {
        s->shape = FM_TOOL_FLAT;
    } else if (tt_same(shape, "ballnose")) {
        s->shape = FM_TOOL_BALL;
    } else if (tt_same(shape, "conical")) {
        /* a cone from the tip to the diameter at the top */
        s->shape = FM_TOOL_VBIT;
        s->angle = 2 * atan(rad / s->length) / DEG;
    } else if (tt_same(shape, "snubnose")) {
        /* a cone frustum from snub_diameter at the tip to the diameter at
         * the top */
        double snub = 0;
        if ((st = length(r, where, t, "snub_diameter", unit, 1, &snub))) return st;
        if (!(snub < s->diameter))
            return cfail(r, where, "snub_diameter", "not smaller than the diameter");
        s->shape = FM_TOOL_TAPERED;
        s->taper_angle = atan((s->diameter - snub) / 2 / s->length) / DEG;
        s->diameter = snub;
        s->shank_diameter = 0; /* lib/tools: the diameter at the top of the flutes */
    } else if (tt_same(shape, "spheroid")) {
        /* an ellipsoid of the diameter and the length: its bounding cylinder */
        s->shape = FM_TOOL_FLAT;
        tt_warn(r, "%s: %s: SPHEROID taken as its bounding solid of revolution, the cylinder of "
                "the diameter over the length", r->name, where);
    } else {
        char what[256];
        snprintf(what, sizeof what, "\"%.40s\" is not a CAMotics shape (CYLINDRICAL, CONICAL, "
                 "BALLNOSE, SPHEROID, SNUBNOSE)", shape);
        return cfail(r, where, "shape", what);
    }
    return tt_validate(r, s, where);
}

fm_status tt_camotics(const tt_reader *r, json_t *root, fm_tool_table *out)
{
    out->count = 0;
    out->tools = NULL;
    json_t *tools = json_object_get(root, "tools");
    double unit = 1.0;
    if (json_is_object(tools)) { /* a project */
        json_t *u = json_object_get(root, "units");
        if (u && !(unit = unit_of(u)))
            return fm_error_at(r->err, FM_ERR_INPUT, r->name, 0, 0,
                               "field \"units\": expected \"metric\" or \"imperial\"");
    } else tools = root;
    if (json_object_size(tools) > FM_TOOLTABLE_MAX_TOOLS)
        return fm_error_at(r->err, FM_ERR_LIMIT, r->name, 0, 0, "more than %d tools",
                           FM_TOOLTABLE_MAX_TOOLS);
    size_t cap = 0;
    fm_status st = FM_OK;
    const char *key;
    json_t *t;
    json_object_foreach(tools, key, t) {
        fm_tool_spec s;
        char where[64];
        snprintf(where, sizeof where, "tools[\"%.20s\"]", key);
        if ((st = tool(r, key, t, unit, &s)) || (st = tt_push(r, out, &cap, &s, where))) break;
    }
    if (st) fm_tool_table_free(out);
    return st;
}
