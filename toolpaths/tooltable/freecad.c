/* freecad.c: FreeCAD Path/CAM tool bits (.fctb: a shape name and its
 * parameters as quantities, "6.0000 mm") and libraries (.fctl: tool numbers
 * and the bit files they name) -> fm_tool_table, for the shapes FreeCAD
 * ships (docs/tooltable.md). */
#include "tooltable_internal.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

static fm_status bfail(const tt_reader *r, const char *where, const char *field, const char *what)
{
    return fm_error_at(r->err, FM_ERR_INPUT, r->name, 0, 0, "%s: field \"%s\": %s", where, field,
                       what);
}

/* A quantity: a number, or a string "<number> <unit>"; lengths in mm, cm,
 * m, in (or "), ft, um; angles in degrees (°, deg). angle: which kind is
 * expected. -1 when the text is not such a quantity. */
static int quantity(json_t *v, int angle, double *out)
{
    if (json_is_number(v)) {
        *out = json_number_value(v);
        return isfinite(*out) ? 0 : -1;
    }
    if (!json_is_string(v)) return -1;
    const char *s = json_string_value(v);
    char *end;
    double x = strtod(s, &end);
    if (end == s || !isfinite(x)) return -1;
    while (*end == ' ') end++;
    double k;
    if (angle) {
        if (!*end || !strcmp(end, "\xc2\xb0") || !strcmp(end, "deg")) k = 1;
        else return -1;
    } else if (!*end || !strcmp(end, "mm")) k = 1;
    else if (!strcmp(end, "cm")) k = 10;
    else if (!strcmp(end, "m")) k = 1000;
    else if (!strcmp(end, "in") || !strcmp(end, "\"")) k = 25.4;
    else if (!strcmp(end, "ft")) k = 304.8;
    else if (!strcmp(end, "um") || !strcmp(end, "\xc2\xb5m")) k = 0.001;
    else return -1;
    *out = x * k;
    return 0;
}

/* A parameter of the bit: required or *out unchanged; > 0 (open) or >= 0. */
static fm_status param(const tt_reader *r, const char *where, json_t *params, const char *key,
                       int required, int angle, int open, double *out)
{
    json_t *v = json_object_get(params, key);
    char field[64];
    snprintf(field, sizeof field, "parameter.%s", key);
    if (!v)
        return required ? bfail(r, where, field, angle ? "missing; expected an angle (\"60 \xc2\xb0\")"
                                                       : "missing; expected a length (\"6 mm\")")
                        : FM_OK;
    double x;
    if (quantity(v, angle, &x))
        return bfail(r, where, field, angle ? "not an angle (a number with \xc2\xb0 or deg)"
                                            : "not a length (a number with mm, cm, m, in, ft)");
    if (open ? !(x > 0) : !(x >= 0)) return bfail(r, where, field, "out of range (must be positive)");
    *out = x;
    return FM_OK;
}

fm_status tt_freecad_bit(const tt_reader *r, json_t *root, int number, fm_tool_spec *s,
                         const char *where_in)
{
    memset(s, 0, sizeof *s);
    s->number = number;
    s->center_cutting = 1;
    json_t *nm = json_object_get(root, "name");
    tt_copy(s->comment, sizeof s->comment, json_is_string(nm) ? json_string_value(nm) : "");
    char where[192];
    snprintf(where, sizeof where, "%s (T%d \"%.60s\")", where_in, number, s->comment);
    json_t *sh = json_object_get(root, "shape");
    if (!json_is_string(sh))
        return bfail(r, where, "shape", sh ? "expected a string" : "missing; expected \"endmill.fcstd\"");
    /* "endmill.fcstd", a path to it, or "endmill" */
    const char *base = json_string_value(sh);
    for (const char *p = base; *p; p++)
        if (*p == '/' || *p == '\\') base = p + 1;
    char shape[32];
    size_t n = strcspn(base, ".");
    if (n >= sizeof shape) n = sizeof shape - 1;
    for (size_t i = 0; i < n; i++) shape[i] = (char)tolower((unsigned char)base[i]);
    shape[n] = '\0';
    static const char *const shapes[] = {"endmill", "ballend", "bullnose", "chamfer", "v-bit",
                                         "vbit", "drill", "dovetail", "slittingsaw", "thread-mill",
                                         "threadmill", "probe", NULL};
    int known = 0;
    for (int i = 0; shapes[i]; i++) known |= !strcmp(shape, shapes[i]);
    if (!known) {
        char what[256];
        snprintf(what, sizeof what, "\"%.40s\" is not a shape FreeCAD ships (endmill, ballend, "
                 "bullnose, chamfer, v-bit, drill, dovetail, slittingsaw, thread-mill)", shape);
        return bfail(r, where, "shape", what);
    }
    json_t *pr = json_object_get(root, "parameter");
    if (!json_is_object(pr))
        return bfail(r, where, "parameter", pr ? "expected an object" : "missing");
    fm_status st;
    if ((st = param(r, where, pr, "Diameter", 1, 0, 1, &s->diameter)) ||
        (st = param(r, where, pr, "Length", 1, 0, 1, &s->length)))
        return st;
    s->shank_diameter = s->diameter;
    if ((st = param(r, where, pr, "ShankDiameter", 0, 0, 1, &s->shank_diameter))) return st;
    s->flute_length = s->length;
    int edge = strcmp(shape, "drill") != 0; /* a drill has no CuttingEdgeHeight */
    if ((st = param(r, where, pr, "CuttingEdgeHeight", 0, 0, 1, &s->flute_length))) return st;
    if (edge && !json_object_get(pr, "CuttingEdgeHeight") && strcmp(shape, "slittingsaw") &&
        strcmp(shape, "thread-mill") && strcmp(shape, "threadmill") && strcmp(shape, "probe"))
        return bfail(r, where, "parameter.CuttingEdgeHeight", "missing; expected a length (\"20 mm\")");
    if (!strcmp(shape, "endmill")) {
        s->shape = FM_TOOL_FLAT;
    } else if (!strcmp(shape, "ballend")) {
        s->shape = FM_TOOL_BALL;
    } else if (!strcmp(shape, "bullnose")) {
        s->shape = FM_TOOL_BULL;
        if (json_object_get(pr, "CornerRadius")) {
            if ((st = param(r, where, pr, "CornerRadius", 1, 0, 1, &s->corner_radius))) return st;
        } else {
            /* older bits give the flat's radius at the bottom */
            double flat = 0;
            if ((st = param(r, where, pr, "FlatRadius", 1, 0, 0, &flat))) return st;
            s->corner_radius = s->diameter / 2 - flat;
            if (!(s->corner_radius > 0))
                return bfail(r, where, "parameter.FlatRadius", "not smaller than the radius");
        }
    } else if (!strcmp(shape, "chamfer") || !strcmp(shape, "v-bit") || !strcmp(shape, "vbit")) {
        s->shape = FM_TOOL_VBIT;
        if ((st = param(r, where, pr, "CuttingEdgeAngle", 1, 1, 1, &s->angle)) ||
            (st = param(r, where, pr, "TipDiameter", 0, 0, 0, &s->tip_diameter)))
            return st;
    } else if (!strcmp(shape, "drill")) {
        s->shape = FM_TOOL_DRILL;
        if ((st = param(r, where, pr, "TipAngle", 1, 1, 1, &s->point_angle))) return st;
    } else if (!strcmp(shape, "dovetail")) {
        s->shape = FM_TOOL_DOVETAIL;
        double cea = 0, neck_h = 0;
        if ((st = param(r, where, pr, "CuttingEdgeAngle", 1, 1, 1, &cea)) ||
            (st = param(r, where, pr, "NeckDiameter", 1, 0, 1, &s->neck_diameter)) ||
            (st = param(r, where, pr, "NeckHeight", 0, 0, 0, &neck_h)))
            return st;
        /* FreeCAD's angle is the flank's to the bottom face (a "60 degree"
         * dovetail); frepmill's is the flank's to the axis */
        if (cea >= 90)
            return bfail(r, where, "parameter.CuttingEdgeAngle", "expected an angle below 90");
        s->angle = 90 - cea;
        s->flute_length += neck_h;
        if (s->flute_length > s->length) s->flute_length = s->length;
    } else if (!strcmp(shape, "slittingsaw")) {
        s->shape = FM_TOOL_FLAT;
        double cap = 0, cap_h = 0;
        if ((st = param(r, where, pr, "BladeThickness", 1, 0, 1, &s->flute_length)) ||
            (st = param(r, where, pr, "CapDiameter", 0, 0, 0, &cap)) ||
            (st = param(r, where, pr, "CapHeight", 0, 0, 0, &cap_h)))
            return st;
        if (cap > s->shank_diameter && cap_h > 0) {
            tt_warn(r, "%s: %s: the saw's cap (%g mm) is wider than the shank: the shank is taken "
                    "as the cap's cylinder (bounding)", r->name, where, cap);
            s->shank_diameter = cap;
        }
    } else if (!strcmp(shape, "thread-mill") || !strcmp(shape, "threadmill")) {
        s->shape = FM_TOOL_FLAT;
        double crest = 0, ca = 60, neck = 0;
        if ((st = param(r, where, pr, "Crest", 0, 0, 0, &crest)) ||
            (st = param(r, where, pr, "cuttingAngle", 0, 1, 1, &ca)) ||
            (st = param(r, where, pr, "CuttingAngle", 0, 1, 1, &ca)) ||
            (st = param(r, where, pr, "NeckDiameter", 0, 0, 0, &neck)))
            return st;
        if (ca >= 180) return bfail(r, where, "parameter.CuttingAngle", "expected an angle below 180");
        /* the head's V form, crest at the diameter, flanks down to the neck */
        double h = crest + (s->diameter - neck) * tan(ca * 3.14159265358979323846 / 360.0);
        s->flute_length = fmin(fmax(h, 1e-3), s->length);
        tt_warn(r, "%s: %s: thread-mill taken as its bounding solid of revolution: the cylinder "
                "of the diameter over the head's height %g mm (its thread form is not modelled)",
                r->name, where, s->flute_length);
    } else if (!strcmp(shape, "probe")) {
        return bfail(r, where, "shape", "\"probe\" is a probe, not a cutter");
    } else {
        char what[256];
        snprintf(what, sizeof what, "\"%.40s\" is not a shape FreeCAD ships (endmill, ballend, "
                 "bullnose, chamfer, v-bit, drill, dovetail, slittingsaw, thread-mill)", shape);
        return bfail(r, where, "shape", what);
    }
    if (s->flute_length > s->length) s->flute_length = s->length;
    return tt_validate(r, s, where);
}

/* A bit path of a library: relative, no "..", no drive. */
static int safe_relative(const char *p)
{
    if (!p[0] || p[0] == '/' || p[0] == '\\' || strchr(p, ':')) return 0;
    for (const char *q = p; *q;) {
        size_t len = strcspn(q, "/\\");
        if (len == 2 && q[0] == '.' && q[1] == '.') return 0;
        q += len;
        if (*q) q++;
    }
    return 1;
}

fm_status tt_freecad_library(const tt_reader *r, json_t *root, const char *dir,
                             fm_tool_table *out)
{
    out->count = 0;
    out->tools = NULL;
    if (!dir)
        return fm_error_at(r->err, FM_ERR_INPUT, r->name, 0, 0,
                           "a FreeCAD tool library (.fctl) names its bit files: give it as a file");
    json_t *tools = json_object_get(root, "tools");
    size_t n = json_array_size(tools), cap = 0;
    if (n > FM_TOOLTABLE_MAX_TOOLS)
        return fm_error_at(r->err, FM_ERR_LIMIT, r->name, 0, 0, "more than %d tools",
                           FM_TOOLTABLE_MAX_TOOLS);
    fm_status st = FM_OK;
    for (size_t i = 0; i < n && !st; i++) {
        json_t *t = json_array_get(tools, i);
        char where[64];
        snprintf(where, sizeof where, "tools[%zu]", i);
        json_t *nr = json_object_get(t, "nr"), *path = json_object_get(t, "path");
        if (!json_is_integer(nr) || json_integer_value(nr) < 1 || json_integer_value(nr) > 99999) {
            st = bfail(r, where, "nr", "expected the tool number, an integer from 1 to 99999");
            break;
        }
        int number = (int)json_integer_value(nr);
        snprintf(where, sizeof where, "tools[%zu] (T%d)", i, number);
        if (!json_is_string(path) || !safe_relative(json_string_value(path))) {
            st = bfail(r, where, "path", "expected a bit file relative to the library (no \"..\")");
            break;
        }
        /* FreeCAD keeps libraries in Tools/Library and bits in Tools/Bit */
        const char *rel = json_string_value(path);
        char file[1024];
        char *text = NULL;
        size_t len = 0;
        fm_error ferr;
        const char *tries[2] = {"%s/%s", "%s/../Bit/%s"};
        for (int k = 0; k < 2; k++) {
            if (snprintf(file, sizeof file, tries[k], dir, rel) >= (int)sizeof file) continue;
            if (tt_read_file(file, FM_TOOLTABLE_MAX_BYTES, &text, &len, &ferr) == FM_OK) break;
        }
        if (!text) {
            st = fm_error_at(r->err, FM_ERR_IO, r->name, 0, 0,
                             "%s: field \"path\": bit file \"%.200s\" not found next to the library "
                             "nor in ../Bit", where, rel);
            break;
        }
        json_error_t je;
        json_t *bit = json_loadb(text, len, JSON_REJECT_DUPLICATES, &je);
        free(text);
        if (!bit) {
            st = fm_error_at(r->err, FM_ERR_INPUT, file, je.line > 0 ? je.line : 0,
                             je.column > 0 ? je.column : 0, "invalid JSON: %s", je.text);
            break;
        }
        fm_tool_spec s;
        tt_reader br = *r;
        br.name = file;
        json_t *shape = json_object_get(bit, "shape");
        if (json_is_string(shape) && strstr(json_string_value(shape), "probe")) {
            tt_warn(r, "%s: %s: skipped: a probe, not a cutter", r->name, where);
            json_decref(bit);
            continue;
        }
        st = tt_freecad_bit(&br, bit, number, &s, "bit");
        json_decref(bit);
        if (!st) st = tt_push(r, out, &cap, &s, where);
    }
    if (st) fm_tool_table_free(out);
    return st;
}
