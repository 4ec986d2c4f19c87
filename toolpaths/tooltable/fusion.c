/* fusion.c: Fusion 360 tool libraries (the JSON Fusion exports: {"data":
 * [...], "version": N}) -> fm_tool_table. Geometry by ISO 13399 symbols,
 * each Fusion type mapped to a frepmill shape, taken as its bounding solid of
 * revolution with a warning, or refused with why (docs/tooltable.md). */
#include "tooltable_internal.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#define DEG (3.14159265358979323846 / 180.0)

/* One library entry being read. */
typedef struct fentry {
    const tt_reader *r;
    int index;        /* position in "data" */
    int number;       /* post-process.number once known, else -1 */
    const char *desc; /* description, "" when none */
    double unit;      /* mm per the entry's unit */
} fentry;

static void entry_where(const fentry *e, char *buf, size_t size)
{
    if (e->number >= 0)
        snprintf(buf, size, "data[%d] (T%d \"%.60s\")", e->index, e->number, e->desc);
    else snprintf(buf, size, "data[%d] (\"%.60s\")", e->index, e->desc);
}

static fm_status efail(const fentry *e, const char *field, const char *what)
{
    char where[128];
    entry_where(e, where, sizeof where);
    return fm_error_at(e->r->err, FM_ERR_INPUT, e->r->name, 0, 0, "%s: field \"%s\": %s", where,
                       field, what);
}

static void ewarn(const fentry *e, const char *what)
{
    char where[128];
    entry_where(e, where, sizeof where);
    tt_warn(e->r, "%s: %s: %s", e->r->name, where, what);
}

/* A number of obj (named path for messages): required or *out unchanged;
 * scaled by scale; at least lo (open: above lo). */
static fm_status num(const fentry *e, json_t *obj, const char *key, const char *path, int required,
                     double scale, double lo, int open, double *out)
{
    json_t *v = obj ? json_object_get(obj, key) : NULL;
    if (!v) return required ? efail(e, path, "missing; expected a number") : FM_OK;
    if (!json_is_number(v)) return efail(e, path, "not a number");
    double x = json_number_value(v);
    if (!isfinite(x)) return efail(e, path, "not a finite number");
    if (open ? !(x > lo) : !(x >= lo)) {
        char what[96];
        snprintf(what, sizeof what, "%s (got %g)",
                 lo == 0 ? (open ? "must be positive" : "must not be negative") : "below its range",
                 x);
        return efail(e, path, what);
    }
    *out = x * scale;
    return FM_OK;
}

static fm_status unit_field(const fentry *e, json_t *obj, const char *path, double *unit)
{
    json_t *u = json_object_get(obj, "unit");
    if (!u) return efail(e, path, "missing; expected \"millimeters\" or \"inches\"");
    const char *s = json_is_string(u) ? json_string_value(u) : "";
    if (tt_same(s, "millimeters") || tt_same(s, "mm")) *unit = 1.0;
    else if (tt_same(s, "inches") || tt_same(s, "inch") || tt_same(s, "in")) *unit = 25.4;
    else {
        char what[128];
        snprintf(what, sizeof what, "\"%.40s\" is not a unit; expected \"millimeters\" or \"inches\"",
                 s);
        return efail(e, path, what);
    }
    return FM_OK;
}

#define G(key, req, lo, open, out) num(e, geom, key, "geometry." key, req, e->unit, lo, open, out)
#define A(key, req, lo, open, out) num(e, geom, key, "geometry." key, req, 1.0, lo, open, out)

/* The shape of each Fusion type frepmill simulates. kind: 0 exact, 1 the
 * bounding solid (why says what it leaves out), 2 refused (why), 3 skipped
 * (not a cutter). */
typedef struct ftype {
    const char *name;
    int kind;
    const char *why;
} ftype;

static const ftype types[] = {
    {"flat end mill", 0, NULL},
    {"ball end mill", 0, NULL},
    {"bull nose end mill", 0, NULL},
    {"drill", 0, NULL},
    {"spot drill", 0, NULL},
    {"chamfer mill", 0, NULL},
    {"counter sink", 0, NULL},
    {"tapered mill", 0, NULL},
    {"dovetail mill", 0, NULL},
    {"lollipop mill", 0, NULL},
    {"face mill", 0, NULL},
    {"slot mill", 0, NULL},
    {"radius mill", 1, "its concave corner-rounding profile is not modelled: the cylinder of DC over LCF"},
    {"thread mill", 1, "its thread form is not modelled: the cylinder of DC over LCF"},
    {"boring bar", 1, "a single-point bar: the cylinder its insert sweeps, DC over LCF"},
    {"reamer", 1, "its lead chamfer is not modelled: the cylinder of DC over LCF"},
    {"tap right hand", 1, "its thread and lead are not modelled: the cylinder of DC over LCF"},
    {"tap left hand", 1, "its thread and lead are not modelled: the cylinder of DC over LCF"},
    {"counter bore", 1, "its pilot is not modelled: the cylinder of DC over LCF"},
    {"form mill", 2, "its profile is a sketch the library does not carry"},
    {"probe", 3, "a probe, not a cutter"},
    {"holder", 3, NULL},
    {"shaft", 3, NULL},
};

static const ftype *find_type(const char *name)
{
    for (size_t i = 0; i < sizeof types / sizeof types[0]; i++)
        if (tt_same(types[i].name, name)) return &types[i];
    return NULL;
}

/* Stacked segments {height, lower-diameter, upper-diameter} of a holder or
 * shaft object into segs (at most max; more are merged into the last, as the
 * cylinder that holds them, with a warning). */
static fm_status segments(const fentry *e, json_t *obj, const char *what, double unit,
                          fm_holder_segment *segs, int max, int *count)
{
    *count = 0;
    json_t *arr = json_object_get(obj, "segments");
    if (!arr) return FM_OK;
    char path[64];
    snprintf(path, sizeof path, "%s.segments", what);
    if (!json_is_array(arr)) return efail(e, path, "expected an array of segments");
    size_t n = json_array_size(arr);
    if (n > 1000) return efail(e, path, "more than 1000 segments");
    for (size_t i = 0; i < n; i++) {
        json_t *s = json_array_get(arr, i);
        fm_holder_segment g = {0, 0, 0};
        if (!json_is_object(s)) {
            snprintf(path, sizeof path, "%s.segments[%zu]", what, i);
            return efail(e, path, "expected {\"height\", \"lower-diameter\", \"upper-diameter\"}");
        }
        fm_status st;
        snprintf(path, sizeof path, "%s.segments[%zu].height", what, i);
        if ((st = num(e, s, "height", path, 1, unit, 0, 1, &g.length))) return st;
        snprintf(path, sizeof path, "%s.segments[%zu].lower-diameter", what, i);
        if ((st = num(e, s, "lower-diameter", path, 1, unit, 0, 0, &g.diameter))) return st;
        snprintf(path, sizeof path, "%s.segments[%zu].upper-diameter", what, i);
        if ((st = num(e, s, "upper-diameter", path, 1, unit, 0, 0, &g.diameter_top))) return st;
        if (g.diameter <= 0 && g.diameter_top <= 0) {
            snprintf(path, sizeof path, "%s.segments[%zu]", what, i);
            return efail(e, path, "both diameters are 0");
        }
        if (*count < max) {
            segs[(*count)++] = g;
            continue;
        }
        /* beyond the last slot: the last segment becomes the cylinder that
         * holds itself and this one */
        fm_holder_segment *l = &segs[max - 1];
        double d = fmax(fmax(l->diameter, l->diameter_top), fmax(g.diameter, g.diameter_top));
        l->diameter = l->diameter_top = d;
        l->length += g.length;
        if (i == (size_t)max) {
            char w[160];
            snprintf(w, sizeof w, "%s has %zu segments, frepmill keeps %d: the top ones are taken "
                     "as the cylinder that holds them", what, n, max);
            ewarn(e, w);
        }
    }
    return FM_OK;
}

static fm_status presets(const fentry *e, json_t *entry, fm_tool_spec *s)
{
    json_t *sv = json_object_get(entry, "start-values");
    json_t *arr = json_is_object(sv) ? json_object_get(sv, "presets") : NULL;
    if (!json_is_array(arr)) return FM_OK;
    /* feeds are in the tool's unit per minute, cutting speeds in m/min or
     * ft/min with it */
    double speed = e->unit == 1.0 ? 1.0 : 0.3048;
    size_t i;
    json_t *p;
    json_array_foreach(arr, i, p) {
        if (s->preset_count >= FM_TOOL_MAX_PRESETS) break;
        if (!json_is_object(p)) continue;
        fm_tool_preset *q = &s->presets[s->preset_count];
        memset(q, 0, sizeof *q);
        json_t *nm = json_object_get(p, "name");
        tt_copy(q->name, sizeof q->name, json_is_string(nm) ? json_string_value(nm) : "");
        char path[64];
        fm_status st;
        struct { const char *key; double scale; double *out; } f[] = {
            {"n", 1.0, &q->spindle_rpm},        {"v_c", speed, &q->cutting_speed},
            {"v_f", e->unit, &q->feed},         {"v_f_plunge", e->unit, &q->plunge_feed},
            {"f_z", e->unit, &q->feed_per_tooth}};
        for (size_t k = 0; k < sizeof f / sizeof f[0]; k++) {
            snprintf(path, sizeof path, "start-values.presets[%zu].%s", i, f[k].key);
            if ((st = num(e, p, f[k].key, path, 0, f[k].scale, 0, 0, f[k].out))) return st;
        }
        s->preset_count++;
    }
    return FM_OK;
}

/* The geometry of a cutter by its type. */
static fm_status shape(const fentry *e, const ftype *t, json_t *geom, fm_tool_spec *s)
{
    fm_status st;
    double re = 0, ta = 0, sig = 0, tipd = 0;
    char w[256];
    if ((st = G("RE", 0, 0, 0, &re)) || (st = A("TA", 0, 0, 0, &ta)) ||
        (st = A("SIG", 0, 0, 0, &sig)) || (st = G("tip-diameter", 0, 0, 0, &tipd)))
        return st;
    const char *n = t->name;
    s->shape = FM_TOOL_FLAT;
    if (t->kind == 1) {
        snprintf(w, sizeof w, "type \"%s\" taken as its bounding solid of revolution: %s", n, t->why);
        ewarn(e, w);
    } else if (tt_same(n, "ball end mill")) {
        s->shape = FM_TOOL_BALL;
    } else if (tt_same(n, "bull nose end mill")) {
        s->shape = FM_TOOL_BULL;
        if ((st = G("RE", 1, 0, 1, &s->corner_radius))) return st;
    } else if (tt_same(n, "drill") || tt_same(n, "spot drill")) {
        s->shape = FM_TOOL_DRILL;
        if ((st = A("SIG", 1, 0, 1, &s->point_angle))) return st;
        if (s->point_angle >= 180) return efail(e, "geometry.SIG", "expected an angle below 180");
    } else if (tt_same(n, "chamfer mill") || tt_same(n, "counter sink")) {
        /* Fusion gives a chamfer mill its taper angle per side (TA, 45 for
         * a 90-degree tool) and a countersink its included point angle (SIG) */
        s->shape = FM_TOOL_VBIT;
        if (tt_same(n, "counter sink") && sig > 0) s->angle = sig;
        else {
            if ((st = A("TA", 1, 0, 1, &ta))) return st;
            s->angle = 2 * ta;
        }
        if (s->angle >= 180)
            return efail(e, tt_same(n, "counter sink") && sig > 0 ? "geometry.SIG" : "geometry.TA",
                         "expected an angle below 180 (included) or 90 (per side)");
        s->tip_diameter = tipd;
    } else if (tt_same(n, "tapered mill")) {
        s->shape = FM_TOOL_TAPERED;
        if ((st = A("TA", 1, 0, 0, &s->taper_angle))) return st;
        if (s->taper_angle >= 90) return efail(e, "geometry.TA", "expected an angle below 90");
        s->tip_radius = re;
    } else if (tt_same(n, "dovetail mill")) {
        s->shape = FM_TOOL_DOVETAIL;
        if ((st = A("TA", 1, 0, 1, &s->angle))) return st;
        if (s->angle >= 90) return efail(e, "geometry.TA", "expected an angle below 90");
        /* the flank narrows from DC over the flute length LCF: the neck is
         * where it ends, up to the shoulder */
        double lcf = s->flute_length, shoulder = 0;
        if ((st = G("shoulder-length", 0, 0, 0, &shoulder))) return st;
        s->neck_diameter = s->diameter - 2 * lcf * tan(s->angle * DEG);
        if (s->neck_diameter <= 0)
            return efail(e, "geometry.TA", "the flank meets the axis below LCF (2 LCF tan(TA) >= DC)");
        /* the flank's height as lib/tools computes it, not below LCF by a
         * rounding */
        double h = (s->diameter - s->neck_diameter) / 2 / tan(s->angle * DEG);
        s->flute_length = fmin(fmax(fmax(lcf, h), shoulder), s->length);
        if (re > 0) {
            snprintf(w, sizeof w, "dovetail's corner radius RE %g mm not modelled (sharp corner: "
                     "the bounding solid)", re);
            ewarn(e, w);
        }
    } else if (tt_same(n, "lollipop mill")) {
        s->shape = FM_TOOL_LOLLIPOP;
        /* the neck under the ball is the shaft (SFDM) */
        s->neck_diameter = s->shank_diameter;
        if (!(s->neck_diameter < s->diameter))
            return efail(e, "geometry.SFDM", "a lollipop's neck (SFDM) must be smaller than DC");
    } else if (tt_same(n, "face mill")) {
        if (ta > 0) {
            /* a lead angle: the inserts' flank widens up to DC + 2 LCF tan(TA) */
            double top = s->diameter + 2 * s->flute_length * tan(ta * DEG);
            snprintf(w, sizeof w, "face mill's lead angle TA %g not modelled: the cylinder of "
                     "%g mm over LCF (bounding)", ta, top);
            ewarn(e, w);
            s->diameter = top;
        }
        if (re > 0) {
            snprintf(w, sizeof w, "face mill's insert radius RE %g mm not modelled (bounding)", re);
            ewarn(e, w);
        }
    } else if (tt_same(n, "slot mill")) {
        if (re > 0) {
            snprintf(w, sizeof w, "slot mill's corner radius RE %g mm not modelled (bounding)", re);
            ewarn(e, w);
        }
    }
    return FM_OK;
}

static fm_status entry(const fentry *e0, json_t *t, fm_tool_spec *s, int *skip)
{
    fentry ev = *e0, *e = &ev;
    fm_status st;
    memset(s, 0, sizeof *s);
    *skip = 0;
    if (!json_is_object(t)) return efail(e, "", "expected a tool object");
    json_t *d = json_object_get(t, "description");
    e->desc = json_is_string(d) ? json_string_value(d) : "";
    json_t *ty = json_object_get(t, "type");
    if (!ty) return efail(e, "type", "missing; expected the tool type (\"flat end mill\", ...)");
    if (!json_is_string(ty)) return efail(e, "type", "expected a string");
    const ftype *ft = find_type(json_string_value(ty));
    if (ft && ft->kind == 3) {
        if (ft->why) {
            char w[160];
            snprintf(w, sizeof w, "skipped: %s", ft->why);
            ewarn(e, w);
        }
        *skip = 1;
        return FM_OK;
    }
    json_t *pp = json_object_get(t, "post-process");
    if (!pp) return efail(e, "post-process", "missing; expected {\"number\": T, ...}");
    json_t *nb = json_object_get(pp, "number");
    if (!nb) return efail(e, "post-process.number", "missing; expected the T number");
    if (!json_is_integer(nb) || json_integer_value(nb) < 1 || json_integer_value(nb) > 99999)
        return efail(e, "post-process.number", "expected an integer from 1 to 99999");
    s->number = e->number = (int)json_integer_value(nb);
    if (!ft) {
        char what[256];
        snprintf(what, sizeof what, "\"%.60s\" is not a milling tool type frepmill knows (flat end "
                 "mill, ball end mill, drill, ...: docs/tooltable.md)", json_string_value(ty));
        return efail(e, "type", what);
    }
    if (ft->kind == 2) {
        char what[256];
        snprintf(what, sizeof what, "\"%s\" is refused: %s", ft->name, ft->why);
        return efail(e, "type", what);
    }
    if ((st = unit_field(e, t, "unit", &e->unit))) return st;
    json_t *lo = json_object_get(pp, "length-offset");
    if (lo && json_is_integer(lo) && json_integer_value(lo) >= 0 &&
        json_integer_value(lo) <= 99999)
        s->length_register = (int)json_integer_value(lo);
    else if (lo) return efail(e, "post-process.length-offset", "expected a register number");
    json_t *dor = json_object_get(pp, "diameter-offset");
    if (dor && json_is_integer(dor) && json_integer_value(dor) >= 0 &&
        json_integer_value(dor) <= 99999)
        s->diameter_register = (int)json_integer_value(dor);
    else if (dor) return efail(e, "post-process.diameter-offset", "expected a register number");
    json_t *geom = json_object_get(t, "geometry");
    if (!json_is_object(geom))
        return efail(e, "geometry", geom ? "expected an object" : "missing; expected {\"DC\": ...}");
    if ((st = G("DC", 1, 0, 1, &s->diameter)) || (st = G("LCF", 1, 0, 1, &s->flute_length)) ||
        (st = G("LB", 1, 0, 1, &s->length)))
        return st;
    s->shank_diameter = s->diameter;
    if ((st = G("SFDM", 0, 0, 1, &s->shank_diameter))) return st;
    double nof = 0;
    if ((st = A("NOF", 0, 0, 0, &nof))) return st;
    s->flute_count = nof <= 1000 ? (int)nof : 0;
    s->center_cutting = 1;
    tt_copy(s->comment, sizeof s->comment, e->desc);
    if ((st = shape(e, ft, geom, s))) return st;
    json_t *shaft = json_object_get(t, "shaft");
    if (json_is_object(shaft)) {
        fm_holder_segment seg[64];
        int n = 0;
        if ((st = segments(e, shaft, "shaft", e->unit, seg, 64, &n))) return st;
        double dmax = s->shank_diameter;
        for (int i = 0; i < n; i++) dmax = fmax(dmax, fmax(seg[i].diameter, seg[i].diameter_top));
        if (dmax > s->shank_diameter) {
            char w[160];
            snprintf(w, sizeof w, "shaft segments up to %g mm wide: the shank is their bounding "
                     "cylinder", dmax);
            ewarn(e, w);
            s->shank_diameter = dmax;
        }
    }
    json_t *holder = json_object_get(t, "holder");
    if (holder) {
        if (!json_is_object(holder)) return efail(e, "holder", "expected an object");
        double hu = e->unit;
        if (json_object_get(holder, "unit") && (st = unit_field(e, holder, "holder.unit", &hu)))
            return st;
        if ((st = segments(e, holder, "holder", hu, s->holder, FM_TOOL_MAX_HOLDER,
                           &s->holder_count)))
            return st;
    }
    return presets(e, t, s);
}

fm_status tt_fusion_json(const tt_reader *r, json_t *root, fm_tool_table *out)
{
    out->count = 0;
    out->tools = NULL;
    json_t *data = json_object_get(root, "data");
    if (!json_is_array(data))
        return fm_error_at(r->err, FM_ERR_INPUT, r->name, 0, 0,
                           "field \"data\": expected the array of a Fusion 360 tool library");
    size_t n = json_array_size(data), cap = 0;
    if (n > FM_TOOLTABLE_MAX_TOOLS)
        return fm_error_at(r->err, FM_ERR_LIMIT, r->name, 0, 0, "more than %d tools",
                           FM_TOOLTABLE_MAX_TOOLS);
    fm_status st = FM_OK;
    for (size_t i = 0; i < n; i++) {
        fentry e = {r, (int)i, -1, "", 1.0};
        fm_tool_spec s;
        int skip;
        if ((st = entry(&e, json_array_get(data, i), &s, &skip))) break;
        if (skip) continue;
        e.number = s.number;
        e.desc = s.comment;
        char where[128];
        entry_where(&e, where, sizeof where);
        if ((st = tt_validate(r, &s, where)) || (st = tt_push(r, out, &cap, &s, where))) break;
    }
    if (st) fm_tool_table_free(out);
    return st;
}
