/* shapes.c: the standard cutters, shanks and holders as (r, z) profiles,
 * from a tool table entry, with the checks that turn impossible
 * dimensions into errors a person can act on. Geometry per shape is
 * documented in docs/tools.md. */
#include "tools/tools.h"

#include <math.h>
#include <string.h>

typedef struct chain {
    fm_profile_elem e[FM_PROFILE_MAX];
    size_t n;
    double at[2]; /* current end */
    int overflow;
} chain;

static void chain_start(chain *c, double z)
{
    c->n = 0;
    c->at[0] = 0;
    c->at[1] = z;
    c->overflow = 0;
}

static void chain_line(chain *c, double r, double z)
{
    if (fabs(r - c->at[0]) < 1e-12 && fabs(z - c->at[1]) < 1e-12) return; /* zero length */
    if (c->n >= FM_PROFILE_MAX) {
        c->overflow = 1;
        return;
    }
    fm_profile_elem *e = &c->e[c->n++];
    memset(e, 0, sizeof *e);
    e->kind = FM_PROFILE_SEGMENT;
    e->a[0] = c->at[0];
    e->a[1] = c->at[1];
    e->b[0] = r;
    e->b[1] = z;
    c->at[0] = r;
    c->at[1] = z;
}

static void chain_arc(chain *c, double r, double z, double cr, double cz, double radius)
{
    if (fabs(r - c->at[0]) < 1e-12 && fabs(z - c->at[1]) < 1e-12) return;
    if (c->n >= FM_PROFILE_MAX) {
        c->overflow = 1;
        return;
    }
    fm_profile_elem *e = &c->e[c->n++];
    memset(e, 0, sizeof *e);
    e->kind = FM_PROFILE_ARC;
    e->a[0] = c->at[0];
    e->a[1] = c->at[1];
    e->b[0] = r;
    e->b[1] = z;
    e->c[0] = cr;
    e->c[1] = cz;
    e->radius = radius;
    c->at[0] = r;
    c->at[1] = z;
}

static fm_status chain_finish(chain *c, fm_tool_part *part, const fm_tool_spec *s, const char *what,
                              fm_error *err)
{
    if (c->overflow)
        return fm_error_set(err, FM_ERR_INPUT, "tool %d: the %s profile has too many elements", s->number,
                            what);
    fm_status st = fm_tool_part_from_profile(c->e, c->n, part, err);
    if (st != FM_OK) {
        char msg[sizeof err->message];
        if (err) {
            memcpy(msg, err->message, sizeof msg);
            fm_error_set(err, st, "tool %d (%s): %s", s->number, what, msg);
        }
    }
    return st;
}

static const char *shape_name(fm_tool_shape s)
{
    switch (s) {
    case FM_TOOL_FLAT: return "flat";
    case FM_TOOL_BALL: return "ball";
    case FM_TOOL_BULL: return "bull";
    case FM_TOOL_VBIT: return "vbit";
    case FM_TOOL_DRILL: return "drill";
    case FM_TOOL_TAPERED: return "tapered";
    case FM_TOOL_DOVETAIL: return "dovetail";
    case FM_TOOL_LOLLIPOP: return "lollipop";
    case FM_TOOL_HYPERFUN: return "hyperfun";
    }
    return "?";
}

/* Height of the lollipop's neck joint and the dovetail's head: shared by
 * validation and building. */
static double lollipop_neck_z(const fm_tool_spec *s)
{
    double R = s->diameter / 2, rn = s->neck_diameter / 2;
    return R + sqrt(R * R - rn * rn);
}

static double dovetail_head_h(const fm_tool_spec *s)
{
    return (s->diameter / 2 - s->neck_diameter / 2) / tan(s->angle * FM_DEG);
}

#define BAD(...) fm_error_set(err, FM_ERR_INPUT, __VA_ARGS__)

fm_status fm_tool_validate(const fm_tool_spec *s, fm_error *err)
{
    int T = s->number;
    const char *name = shape_name(s->shape);
    if ((int)s->shape < FM_TOOL_FLAT || s->shape > FM_TOOL_HYPERFUN)
        return BAD("tool %d: unknown shape %d", T, (int)s->shape);
    double R = s->diameter / 2;
    if (s->shape == FM_TOOL_HYPERFUN) {
        if (!(s->bound_radius > 0) || !isfinite(s->bound_radius))
            return BAD("tool %d (hyperfun): bound_radius must be positive, not %g", T, s->bound_radius);
    } else if (s->shape == FM_TOOL_TAPERED && s->tip_radius > 0 && s->diameter == 0) {
        R = s->tip_radius; /* a tapered ball may give the tip radius alone */
    } else if (!(s->diameter > 0) || !isfinite(s->diameter)) {
        return BAD("tool %d (%s): diameter must be positive, not %g", T, name, s->diameter);
    }
    if (!(s->flute_length > 0) || !isfinite(s->flute_length))
        return BAD("tool %d (%s): flute_length must be positive, not %g", T, name, s->flute_length);
    if (!(s->length > 0) || !isfinite(s->length))
        return BAD("tool %d (%s): length (stick-out) must be positive, not %g", T, name, s->length);
    if (s->flute_length > s->length)
        return BAD("tool %d (%s): flute_length %g is longer than the stick-out length %g", T, name,
                   s->flute_length, s->length);
    if (s->shank_diameter < 0 || !isfinite(s->shank_diameter))
        return BAD("tool %d (%s): shank_diameter must not be negative (0 means the cutting diameter), not %g",
                   T, name, s->shank_diameter);
    if (s->holder_count < 0 || s->holder_count > FM_TOOL_MAX_HOLDER)
        return BAD("tool %d: %d holder segments; at most %d", T, s->holder_count, FM_TOOL_MAX_HOLDER);
    for (int i = 0; i < s->holder_count; i++) {
        const fm_holder_segment *h = &s->holder[i];
        if (!(h->diameter > 0) || !isfinite(h->diameter))
            return BAD("tool %d: holder segment %d: diameter must be positive, not %g", T, i + 1, h->diameter);
        if (h->diameter_top < 0 || !isfinite(h->diameter_top))
            return BAD("tool %d: holder segment %d: diameter_top must not be negative, not %g", T, i + 1,
                       h->diameter_top);
        if (!(h->length > 0) || !isfinite(h->length))
            return BAD("tool %d: holder segment %d: length must be positive, not %g", T, i + 1, h->length);
    }
    switch (s->shape) {
    case FM_TOOL_FLAT:
    case FM_TOOL_HYPERFUN:
        break;
    case FM_TOOL_BALL:
        if (s->flute_length < R)
            return BAD("tool %d (ball): flute_length %g is shorter than the ball radius %g", T, s->flute_length, R);
        break;
    case FM_TOOL_BULL:
        if (!(s->corner_radius >= 0) || s->corner_radius > R)
            return BAD("tool %d (bull): corner_radius %g must be between 0 and the radius %g", T,
                       s->corner_radius, R);
        if (s->flute_length < s->corner_radius)
            return BAD("tool %d (bull): flute_length %g is shorter than the corner radius %g", T,
                       s->flute_length, s->corner_radius);
        break;
    case FM_TOOL_VBIT:
        if (!(s->angle > 0 && s->angle < 180))
            return BAD("tool %d (vbit): included angle %g must be between 0 and 180 degrees", T, s->angle);
        if (!(s->tip_diameter >= 0) || s->tip_diameter >= s->diameter)
            return BAD("tool %d (vbit): tip_diameter %g must be at least 0 and less than the diameter %g", T,
                       s->tip_diameter, s->diameter);
        break;
    case FM_TOOL_DRILL:
        if (!(s->point_angle > 0 && s->point_angle < 180))
            return BAD("tool %d (drill): point_angle %g must be between 0 and 180 degrees", T, s->point_angle);
        break;
    case FM_TOOL_TAPERED:
        if (!(s->taper_angle >= 0 && s->taper_angle < 90))
            return BAD("tool %d (tapered): taper_angle %g (per side) must be at least 0 and under 90 degrees",
                       T, s->taper_angle);
        if (!(s->tip_radius >= 0))
            return BAD("tool %d (tapered): tip_radius must not be negative, not %g", T, s->tip_radius);
        if (s->tip_radius > 0 && s->diameter != 0 && fabs(s->diameter - 2 * s->tip_radius) > 1e-6)
            return BAD("tool %d (tapered): with a ball tip the diameter (%g) is the tip's, twice tip_radius "
                       "(%g); give one of them or make them agree", T, s->diameter, s->tip_radius);
        if (s->tip_radius > 0 && s->flute_length <= s->tip_radius * (1 - sin(s->taper_angle * FM_DEG)))
            return BAD("tool %d (tapered): flute_length %g ends inside the ball tip", T, s->flute_length);
        break;
    case FM_TOOL_DOVETAIL:
        if (!(s->angle > 0 && s->angle < 90))
            return BAD("tool %d (dovetail): angle %g (flank to the axis) must be between 0 and 90 degrees", T,
                       s->angle);
        if (!(s->neck_diameter > 0) || s->neck_diameter >= s->diameter)
            return BAD("tool %d (dovetail): neck_diameter %g must be positive and less than the diameter %g", T,
                       s->neck_diameter, s->diameter);
        if (s->flute_length < dovetail_head_h(s))
            return BAD("tool %d (dovetail): flute_length %g is shorter than the head height %g", T,
                       s->flute_length, dovetail_head_h(s));
        break;
    case FM_TOOL_LOLLIPOP:
        if (!(s->neck_diameter > 0) || s->neck_diameter >= s->diameter)
            return BAD("tool %d (lollipop): neck_diameter %g must be positive and less than the ball diameter %g",
                       T, s->neck_diameter, s->diameter);
        if (s->flute_length < lollipop_neck_z(s))
            return BAD("tool %d (lollipop): flute_length %g ends inside the ball (neck joins at %g)", T,
                       s->flute_length, lollipop_neck_z(s));
        break;
    }
    return FM_OK;
}

static fm_status build_flutes(const fm_tool_spec *s, fm_tool_part *part, fm_error *err)
{
    chain c;
    double R = s->diameter / 2, F = s->flute_length;
    chain_start(&c, 0);
    switch (s->shape) {
    case FM_TOOL_FLAT:
        chain_line(&c, R, 0);
        chain_line(&c, R, F);
        break;
    case FM_TOOL_BALL:
        chain_arc(&c, R, R, 0, R, R);
        chain_line(&c, R, F);
        break;
    case FM_TOOL_BULL: {
        double rc = s->corner_radius;
        chain_line(&c, R - rc, 0);
        if (rc > 0) chain_arc(&c, R, rc, R - rc, rc, rc);
        chain_line(&c, R, F);
        break;
    }
    case FM_TOOL_VBIT: {
        double rt = s->tip_diameter / 2, h = (R - rt) / tan(s->angle / 2 * FM_DEG);
        chain_line(&c, rt, 0);
        if (F < h) { /* the flutes end on the cone */
            chain_line(&c, rt + (R - rt) * F / h, F);
        } else {
            chain_line(&c, R, h);
            chain_line(&c, R, F);
        }
        break;
    }
    case FM_TOOL_DRILL: {
        double h = R / tan(s->point_angle / 2 * FM_DEG);
        if (F < h) {
            chain_line(&c, R * F / h, F);
        } else {
            chain_line(&c, R, h);
            chain_line(&c, R, F);
        }
        break;
    }
    case FM_TOOL_TAPERED: {
        double a = s->taper_angle * FM_DEG, rt = s->tip_radius;
        if (rt > 0) {
            /* Ball tip centred at (0, rt); the flank is tangent to it. */
            double tr = rt * cos(a), tz = rt * (1 - sin(a));
            chain_arc(&c, tr, tz, 0, rt, rt);
            chain_line(&c, tr + (F - tz) * tan(a), F);
        } else {
            chain_line(&c, R, 0);
            chain_line(&c, R + F * tan(a), F);
        }
        break;
    }
    case FM_TOOL_DOVETAIL: {
        double rn = s->neck_diameter / 2, h = dovetail_head_h(s);
        chain_line(&c, R, 0);
        chain_line(&c, rn, h);
        chain_line(&c, rn, F);
        break;
    }
    case FM_TOOL_LOLLIPOP: {
        double rn = s->neck_diameter / 2, zn = lollipop_neck_z(s);
        chain_arc(&c, R, R, 0, R, R);
        chain_arc(&c, rn, zn, 0, R, R);
        chain_line(&c, rn, F);
        break;
    }
    case FM_TOOL_HYPERFUN:
        return fm_error_set(err, FM_ERR_INPUT, "tool %d is a HyperFun model: build it with fm_tool_build_custom",
                            s->number);
    }
    chain_line(&c, 0, F);
    return chain_finish(&c, part, s, "flutes", err);
}

/* The radius at the top of the flutes: the default shank radius for
 * shapes whose cutting diameter is elsewhere. */
static double flute_top_radius(const fm_tool_part *flutes)
{
    const fm_profile_elem *top = &flutes->elem[flutes->count - 1];
    return top->a[0];
}

static fm_status build_shank_holder(const fm_tool_spec *s, fm_tool *tool, double default_rs,
                                    fm_error *err)
{
    fm_status st;
    tool->has_shank = s->length > s->flute_length;
    if (tool->has_shank) {
        chain c;
        double rs = s->shank_diameter > 0 ? s->shank_diameter / 2 : default_rs;
        chain_start(&c, s->flute_length);
        chain_line(&c, rs, s->flute_length);
        chain_line(&c, rs, s->length);
        chain_line(&c, 0, s->length);
        if ((st = chain_finish(&c, &tool->shank, s, "shank", err)) != FM_OK) return st;
    }
    tool->has_holder = s->holder_count > 0;
    if (tool->has_holder) {
        chain c;
        double z = s->length;
        chain_start(&c, z);
        for (int i = 0; i < s->holder_count; i++) {
            const fm_holder_segment *h = &s->holder[i];
            double top = h->diameter_top > 0 ? h->diameter_top : h->diameter;
            chain_line(&c, h->diameter / 2, z);
            z += h->length;
            chain_line(&c, top / 2, z);
        }
        chain_line(&c, 0, z);
        if ((st = chain_finish(&c, &tool->holder, s, "holder", err)) != FM_OK) return st;
    }
    return FM_OK;
}

fm_status fm_tool_build(const fm_tool_spec *spec, fm_tool *tool, fm_error *err)
{
    fm_status st = fm_tool_validate(spec, err);
    if (st != FM_OK) return st;
    memset(tool, 0, sizeof *tool);
    tool->spec = *spec;
    if (spec->shape == FM_TOOL_TAPERED && spec->tip_radius > 0) tool->spec.diameter = 2 * spec->tip_radius;
    if ((st = build_flutes(&tool->spec, &tool->flutes, err)) != FM_OK) return st;
    double rs = spec->shape == FM_TOOL_DOVETAIL || spec->shape == FM_TOOL_LOLLIPOP ||
                        spec->shape == FM_TOOL_TAPERED
                    ? flute_top_radius(&tool->flutes)
                    : tool->spec.diameter / 2;
    return build_shank_holder(&tool->spec, tool, rs, err);
}

fm_status fm_tool_build_custom(const fm_tool_spec *spec, const fm_tool_custom *custom,
                               fm_tool *tool, fm_error *err)
{
    fm_status st = fm_tool_validate(spec, err);
    if (st != FM_OK) return st;
    if (!custom || !custom->eval || !custom->interval)
        return fm_error_set(err, FM_ERR_INPUT, "tool %d: a custom cutter needs eval and interval callbacks",
                            spec->number);
    if (!(custom->bound_radius > 0) || !(custom->bound_length > 0))
        return fm_error_set(err, FM_ERR_INPUT, "tool %d: a custom cutter needs a positive bounding radius and length",
                            spec->number);
    memset(tool, 0, sizeof *tool);
    tool->spec = *spec;
    tool->flutes.kind = FM_TOOL_PART_CUSTOM;
    tool->flutes.custom = *custom;
    tool->flutes.z_lo = 0;
    tool->flutes.z_hi = custom->bound_length;
    tool->flutes.r_max = custom->bound_radius;
    double rs = spec->diameter > 0 ? spec->diameter / 2 : custom->bound_radius;
    return build_shank_holder(spec, tool, rs, err);
}

fm_status fm_tool_build_head(const fm_tool_spec *spec, const fm_holder_segment *segments, int count,
                             fm_tool_part *head, fm_error *err)
{
    if (count < 1 || count > FM_TOOL_MAX_HOLDER)
        return fm_error_set(err, FM_ERR_INPUT, "the head has %d round segments; 1 to %d", count, FM_TOOL_MAX_HOLDER);
    double z = spec->length;
    for (int i = 0; i < spec->holder_count && i < FM_TOOL_MAX_HOLDER; i++) z += spec->holder[i].length;
    if (!isfinite(z)) return fm_error_set(err, FM_ERR_INPUT, "tool %d: its length is not finite", spec->number);
    chain c;
    chain_start(&c, z);
    for (int i = 0; i < count; i++) {
        const fm_holder_segment *h = &segments[i];
        if (!(h->diameter > 0) || !isfinite(h->diameter) || h->diameter_top < 0 || !isfinite(h->diameter_top) ||
            !(h->length > 0) || !isfinite(h->length))
            return fm_error_set(err, FM_ERR_INPUT,
                                "head segment %d: diameter and length must be positive, diameter_top not "
                                "negative",
                                i + 1);
        double top = h->diameter_top > 0 ? h->diameter_top : h->diameter;
        chain_line(&c, h->diameter / 2, z);
        z += h->length;
        chain_line(&c, top / 2, z);
    }
    chain_line(&c, 0, z);
    return chain_finish(&c, head, spec, "head", err);
}
