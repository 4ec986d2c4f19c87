/* traj.c: the trajectory document: JSON (jansson) -> validated segments ->
 * motion stream. The whole document is checked before the first motion is
 * emitted, so a sink never sees half of a refused trajectory. */
#include "toolpaths/traj/traj.h"

#include <jansson.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hf/hf.h"
#include "toolpaths/traj/traj_internal.h"

#define MM_PER_INCH 25.4
/* Document times closer than this (relative to the times' size) meet. */
#define TIME_TOL 1e-9

void fm_traj_options_default(fm_traj_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->rapid_rate = 5000;
    opt->tolerance = 1e-3;
    opt->axis_tolerance = 1e-4;
    opt->max_document_bytes = 16u << 20;
    opt->max_segments = 10000;
    opt->max_expression_bytes = 4096;
    opt->max_expression_nodes = 20000;
    opt->max_total_nodes = 1000000;
    opt->samples = 1000;
}

typedef struct traj_doc {
    const char *text;
    size_t len;
    const char *name;
    fm_traj_options opt;
    fm_error *err;
    long *seg_off; /* JSON offset of each segment object */
    fm_graph *g;
    traj_seg *segs;
    size_t n;
    double scale; /* mm per document unit */
    double tol;   /* mm */
} traj_doc;

static const char *const component_field[TRAJ_COMPONENTS] = {"x", "y", "z", "axis", "axis", "axis"};
static const char *const component_name[TRAJ_COMPONENTS + 1] = {"x", "y", "z", "axis[0]",
                                                                "axis[1]", "axis[2]", "axis"};

/* An error at a JSON offset (-1: no position). */
static fm_status fail_at(traj_doc *d, fm_status code, long off, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 4, 5)))
#endif
    ;
static fm_status fail_at(traj_doc *d, fm_status code, long off, const char *fmt, ...)
{
    char msg[480];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(msg, sizeof msg, fmt, ap);
    va_end(ap);
    int line = 0, col = 0;
    if (off >= 0) traj_json_position(d->text, d->len, off, &line, &col);
    return fm_error_at(d->err, code, d->name, line, col, "%s", msg);
}

/* Offset of a segment's field (or its k-th element when k >= 0); falls back
 * to the segment itself. */
static long field_off(traj_doc *d, size_t i, const char *field, long k)
{
    long seg = d->seg_off[i];
    long v = traj_json_member(d->text, d->len, seg, field);
    if (v >= 0 && k >= 0) v = traj_json_element(d->text, d->len, v, (size_t)k);
    return v >= 0 ? v : seg;
}

static long component_off(traj_doc *d, size_t i, int comp)
{
    return field_off(d, i, component_field[comp], comp >= 3 ? comp - 3 : -1);
}

static fm_status compile_component(traj_doc *d, size_t i, traj_seg *s, int comp, json_t *v)
{
    const char *field = component_name[comp];
    long off = component_off(d, i, comp);
    if (json_is_number(v)) {
        s->cval[comp] = json_number_value(v);
        return FM_OK;
    }
    if (!json_is_string(v))
        return fail_at(d, FM_ERR_INPUT, off,
                       "segment %zu: \"%s\": expected an expression of t (a string) or a number", i,
                       field);
    const char *text = json_string_value(v);
    size_t len = json_string_length(v);
    if (len > d->opt.max_expression_bytes)
        return fail_at(d, FM_ERR_LIMIT, off,
                       "segment %zu: \"%s\": expression of %zu bytes; the limit is %zu", i, field,
                       len, d->opt.max_expression_bytes);
    if (strlen(text) != len)
        return fail_at(d, FM_ERR_INPUT, off, "segment %zu: \"%s\": NUL character in the expression",
                       i, field);
    size_t before = fm_graph_node_count(d->g);
    fm_node t = fm_var(d->g, FM_T);
    /* u runs from 0 to 1 over the segment's own interval. */
    fm_node u = fm_div(d->g, fm_sub(d->g, t, fm_const(d->g, s->t0)), fm_const(d->g, s->t1 - s->t0));
    const char *names[2] = {"t", "u"};
    fm_node nodes[2] = {t, u};
    fm_error e;
    fm_error_clear(&e);
    fm_node root = fm_hf_parse_expression(d->g, text, names, nodes, 2, "expression", &e);
    if (fm_graph_error(d->g))
        return fail_at(d, FM_ERR_LIMIT, off,
                       "segment %zu: \"%s\": the document's expressions need more than %zu frep "
                       "nodes", i, field, d->opt.max_total_nodes);
    if (root == FM_NONE) {
        long at = e.column > 0 ? traj_json_string_char(d->text, d->len, off, e.column) : off;
        return fail_at(d, e.code == FM_ERR_LIMIT ? FM_ERR_LIMIT : FM_ERR_INPUT, at,
                       "segment %zu: \"%s\": expression column %d: %s", i, field, e.column,
                       e.message);
    }
    size_t used = fm_graph_node_count(d->g) - before;
    if (used > d->opt.max_expression_nodes)
        return fail_at(d, FM_ERR_LIMIT, off,
                       "segment %zu: \"%s\": expression of %zu frep nodes; the limit is %zu", i,
                       field, used, d->opt.max_expression_nodes);
    double c;
    if (fm_node_is_const(d->g, root, &c)) {
        s->cval[comp] = c;
        return FM_OK;
    }
    if (root == t) {
        s->is_t[comp] = 1;
        return FM_OK;
    }
    s->tape[comp] = fm_tape_compile(d->g, root, &e);
    if (!s->tape[comp])
        return fail_at(d, e.code ? e.code : FM_ERR_INTERNAL, off, "segment %zu: \"%s\": %s", i,
                       field, e.message);
    return FM_OK;
}

static int get_vec3(json_t *a, double out[3])
{
    if (!json_is_array(a) || json_array_size(a) != 3) return 0;
    for (size_t k = 0; k < 3; k++) {
        json_t *e = json_array_get(a, k);
        if (!json_is_number(e)) return 0;
        out[k] = json_number_value(e);
    }
    return 1;
}

static int key_allowed(const char *key, const char *const *allowed)
{
    for (; *allowed; allowed++)
        if (!strcmp(key, *allowed)) return 1;
    return 0;
}

/* Reads one segment; tool, feed and spindle carry over from the previous. */
static fm_status parse_segment(traj_doc *d, size_t i, json_t *js, traj_seg *s, int *tool,
                               double *feed, double *spindle)
{
    static const char *const feed_keys[] = {"t", "x", "y", "z", "axis", "tool", "feed",
                                            "spindle", "comment", "rapid", NULL};
    static const char *const rapid_keys[] = {"rapid", "to", "comment", NULL};
    long seg = d->seg_off[i];
    if (!json_is_object(js))
        return fail_at(d, FM_ERR_INPUT, seg, "segment %zu: expected an object", i);
    json_t *rapid = json_object_get(js, "rapid");
    if (rapid && !json_is_boolean(rapid))
        return fail_at(d, FM_ERR_INPUT, field_off(d, i, "rapid", -1),
                       "segment %zu: \"rapid\": expected true or false", i);
    s->rapid = rapid && json_is_true(rapid);
    s->scale = d->scale;
    s->line = 0;
    traj_seg_init_path(s);
    const char *key;
    json_t *val;
    json_object_foreach(js, key, val) {
        if (!key_allowed(key, s->rapid ? rapid_keys : feed_keys))
            return fail_at(d, FM_ERR_INPUT, field_off(d, i, key, -1),
                           "segment %zu: unknown field \"%s\"%s", i, key,
                           s->rapid ? "; a rapid segment has \"rapid\", \"to\" and \"comment\""
                                    : "; expected t, x, y, z, axis, tool, feed, spindle, "
                                      "comment or rapid");
    }
    json_t *cm = json_object_get(js, "comment");
    if (cm && !json_is_string(cm))
        return fail_at(d, FM_ERR_INPUT, field_off(d, i, "comment", -1),
                       "segment %zu: \"comment\": expected a string", i);
    s->tool = *tool;
    s->spindle = *spindle;
    if (s->rapid) {
        json_t *to = json_object_get(js, "to");
        if (to) {
            if (!get_vec3(to, s->to))
                return fail_at(d, FM_ERR_INPUT, field_off(d, i, "to", -1),
                               "segment %zu: \"to\": expected [x, y, z] numbers", i);
            for (int k = 0; k < 3; k++) s->to[k] *= d->scale;
            s->has_to = 1;
        }
        return FM_OK;
    }
    s->feed = *feed;
    json_t *t = json_object_get(js, "t");
    double tt[2];
    if (!t)
        return fail_at(d, FM_ERR_INPUT, seg, "segment %zu: missing \"t\": [t0, t1] in seconds", i);
    if (!json_is_array(t) || json_array_size(t) != 2 || !json_is_number(json_array_get(t, 0)) ||
        !json_is_number(json_array_get(t, 1)))
        return fail_at(d, FM_ERR_INPUT, field_off(d, i, "t", -1),
                       "segment %zu: \"t\": expected [t0, t1], two numbers (seconds)", i);
    tt[0] = json_number_value(json_array_get(t, 0));
    tt[1] = json_number_value(json_array_get(t, 1));
    if (!(tt[0] < tt[1]))
        return fail_at(d, FM_ERR_INPUT, field_off(d, i, "t", -1),
                       "segment %zu: \"t\": the interval [%.9g, %.9g] is empty; expected t0 < t1",
                       i, tt[0], tt[1]);
    s->t0 = tt[0];
    s->t1 = tt[1];
    json_t *tn = json_object_get(js, "tool");
    if (tn) {
        if (!json_is_integer(tn) || json_integer_value(tn) < 0 || json_integer_value(tn) > 99999)
            return fail_at(d, FM_ERR_INPUT, field_off(d, i, "tool", -1),
                           "segment %zu: \"tool\": expected an integer 0..99999", i);
        s->tool = *tool = (int)json_integer_value(tn);
    }
    json_t *fd = json_object_get(js, "feed");
    if (fd) {
        if (!json_is_number(fd) || json_number_value(fd) < 0)
            return fail_at(d, FM_ERR_INPUT, field_off(d, i, "feed", -1),
                           "segment %zu: \"feed\": expected a number >= 0 (units per minute)", i);
        s->feed = *feed = json_number_value(fd) * d->scale;
    }
    json_t *sp = json_object_get(js, "spindle");
    if (sp) {
        if (!json_is_number(sp))
            return fail_at(d, FM_ERR_INPUT, field_off(d, i, "spindle", -1),
                           "segment %zu: \"spindle\": expected rpm (negative: counter-clockwise)",
                           i);
        s->spindle = *spindle = json_number_value(sp);
    }
    fm_status st;
    for (int c = 0; c < 3; c++) {
        json_t *v = json_object_get(js, component_field[c]);
        if (!v)
            return fail_at(d, FM_ERR_INPUT, seg,
                           "segment %zu: missing \"%s\" (an expression of t)", i,
                           component_field[c]);
        if ((st = compile_component(d, i, s, c, v))) return st;
    }
    json_t *ax = json_object_get(js, "axis");
    s->cval[3] = s->cval[4] = 0;
    s->cval[5] = 1;
    if (ax) {
        if (!json_is_array(ax) || json_array_size(ax) != 3)
            return fail_at(d, FM_ERR_INPUT, field_off(d, i, "axis", -1),
                           "segment %zu: \"axis\": expected [a, b, c], three expressions of t", i);
        for (int c = 0; c < 3; c++)
            if ((st = compile_component(d, i, s, 3 + c, json_array_get(ax, (size_t)c)))) return st;
    }
    double t_bad, value;
    int how;
    int bad = traj_seg_check(s, d->opt.samples, &t_bad, &value, &how);
    if (bad == -2)
        return fail_at(d, FM_ERR_LIMIT, seg, "segment %zu: out of memory for the evaluators", i);
    if (bad >= 0) {
        long off = bad < TRAJ_COMPONENTS ? component_off(d, i, bad) : field_off(d, i, "axis", -1);
        const char *f = component_name[bad];
        if (how == TRAJ_CHECK_BUDGET)
            return fail_at(d, FM_ERR_LIMIT, off,
                           "segment %zu: \"%s\": could not prove it finite (and the axis non-zero) "
                           "on [%.9g, %.9g] within %d interval checks",
                           i, f, s->t0, s->t1, TRAJ_CHECK_MAX);
        if (bad == TRAJ_COMPONENTS && how == TRAJ_CHECK_SAMPLE)
            return fail_at(d, FM_ERR_INPUT, off,
                           "segment %zu: the tool axis is zero at t = %.9g (length %g; expected "
                           ">= %g)", i, t_bad, value, TRAJ_MIN_AXIS);
        if (bad == TRAJ_COMPONENTS)
            return fail_at(d, FM_ERR_INPUT, off,
                           "segment %zu: the tool axis may be zero near t = %.9g (interval check)",
                           i, t_bad);
        if (how == TRAJ_CHECK_SAMPLE)
            return fail_at(d, FM_ERR_INPUT, off, "segment %zu: \"%s\" is not finite at t = %.9g (%s)",
                           i, f, t_bad, isnan(value) ? "NaN" : value > 0 ? "inf" : "-inf");
        return fail_at(d, FM_ERR_INPUT, off,
                       "segment %zu: \"%s\" is unbounded near t = %.9g (interval check)", i, f,
                       t_bad);
    }
    return FM_OK;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

static double dist3(const double a[3], const double b[3])
{
    double d[3] = {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
    return sqrt(dot3(d, d));
}

/* Angle between unit vectors, accurate for small angles (atan2 of the
 * cross product's length and the dot product). */
static double angle3(const double a[3], const double b[3])
{
    double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
    return atan2(sqrt(dot3(c, c)), dot3(a, b));
}

static int times_meet(double a, double b)
{
    return fabs(a - b) <= TIME_TOL * fmax(1, fmax(fabs(a), fabs(b)));
}

/* Order in time and continuity of segment i with what came before. */
static fm_status check_join(traj_doc *d, size_t i, long prev_feed)
{
    traj_seg *s = &d->segs[i], *prev = &d->segs[i - 1];
    if (s->rapid) {
        if (prev->rapid && !prev->has_to)
            return fail_at(d, FM_ERR_INPUT, d->seg_off[i - 1],
                           "segment %zu: a rapid without \"to\" must be followed by a feed segment "
                           "(it jumps to that segment's start)", i - 1);
        return FM_OK;
    }
    traj_seg *pf = &d->segs[prev_feed];
    if (s->t0 < pf->t1 && !times_meet(s->t0, pf->t1))
        return fail_at(d, FM_ERR_INPUT, field_off(d, i, "t", 0),
                       "segment %zu: \"t\" starts at %.9g, before segment %ld ends (t = %.9g); "
                       "intervals must be in order", i, s->t0, prev_feed, pf->t1);
    if (!prev->rapid && !times_meet(s->t0, pf->t1))
        return fail_at(d, FM_ERR_INPUT, field_off(d, i, "t", 0),
                       "segment %zu: \"t\" starts at %.9g but segment %zu ends at t = %.9g; "
                       "consecutive segments must meet in time (or put {\"rapid\": true} "
                       "between them)", i, s->t0, i - 1, pf->t1);
    double p0[3], a0[3], p1[3], a1[3];
    traj_seg_pose_doc(pf, pf->t1, p1, a1);
    traj_seg_pose_doc(s, s->t0, p0, a0);
    if (prev->rapid && !prev->has_to) {
        /* The jump itself: only a half turn of the axis cannot be
         * interpolated (the axis would pass through zero). */
        if (dot3(a0, a1) <= -1 + 1e-9)
            return fail_at(d, FM_ERR_INPUT, d->seg_off[i - 1],
                           "segment %zu: the rapid would turn the tool axis by 180 degrees", i - 1);
        return FM_OK;
    }
    if (prev->rapid) memcpy(p1, prev->to, sizeof p1);
    double gap = dist3(p0, p1), turn = angle3(a0, a1);
    const char *u = d->scale == 1 ? "mm" : "inch";
    if (gap > d->tol)
        return fail_at(d, FM_ERR_INPUT, d->seg_off[i],
                       "segment %zu starts at (%.6g, %.6g, %.6g) but %s %zu ends at "
                       "(%.6g, %.6g, %.6g) %s: gap %.6g %s exceeds the tolerance %.6g %s; make "
                       "them meet or put {\"rapid\": true} between them",
                       i, p0[0] / d->scale, p0[1] / d->scale, p0[2] / d->scale,
                       prev->rapid ? "the rapid" : "segment", i - 1, p1[0] / d->scale,
                       p1[1] / d->scale, p1[2] / d->scale, u, gap / d->scale, u, d->tol / d->scale,
                       u);
    if (turn > d->opt.axis_tolerance)
        return fail_at(d, FM_ERR_INPUT, field_off(d, i, "axis", -1),
                       "segment %zu starts with the tool axis (%.6g, %.6g, %.6g) but segment %ld "
                       "ends with (%.6g, %.6g, %.6g): %.6g degrees apart, more than the "
                       "tolerance %.6g; put {\"rapid\": true} between them",
                       i, a0[0], a0[1], a0[2], prev_feed, a1[0], a1[1], a1[2],
                       turn * 180 / FM_PI, d->opt.axis_tolerance * 180 / FM_PI);
    return FM_OK;
}

static fm_status parse_document(traj_doc *d, json_t *root)
{
    static const char *const root_keys[] = {"units", "segments", "tolerance", "tool", "comment",
                                            NULL};
    if (!json_is_object(root))
        return fail_at(d, FM_ERR_INPUT, 0, "expected a JSON object {\"units\": ..., \"segments\": [...]}");
    const char *key;
    json_t *val;
    json_object_foreach(root, key, val) {
        if (!key_allowed(key, root_keys))
            return fail_at(d, FM_ERR_INPUT, traj_json_member(d->text, d->len, 0, key),
                           "unknown field \"%s\"; expected units, segments, tolerance, tool or "
                           "comment", key);
    }
    json_t *units = json_object_get(root, "units");
    d->scale = 1;
    if (units) {
        const char *u = json_is_string(units) ? json_string_value(units) : "";
        if (!strcmp(u, "inch"))
            d->scale = MM_PER_INCH;
        else if (strcmp(u, "mm"))
            return fail_at(d, FM_ERR_INPUT, traj_json_member(d->text, d->len, 0, "units"),
                           "\"units\": expected \"mm\" or \"inch\"");
    }
    d->tol = d->opt.tolerance;
    json_t *tol = json_object_get(root, "tolerance");
    if (tol) {
        if (!json_is_number(tol) || !(json_number_value(tol) > 0))
            return fail_at(d, FM_ERR_INPUT, traj_json_member(d->text, d->len, 0, "tolerance"),
                           "\"tolerance\": expected a number > 0 (document units)");
        d->tol = json_number_value(tol) * d->scale;
    }
    int tool = 0;
    json_t *tn = json_object_get(root, "tool");
    if (tn) {
        if (!json_is_integer(tn) || json_integer_value(tn) < 0 || json_integer_value(tn) > 99999)
            return fail_at(d, FM_ERR_INPUT, traj_json_member(d->text, d->len, 0, "tool"),
                           "\"tool\": expected an integer 0..99999");
        tool = (int)json_integer_value(tn);
    }
    json_t *segs = json_object_get(root, "segments");
    long segs_off = traj_json_member(d->text, d->len, 0, "segments");
    if (!json_is_array(segs) || json_array_size(segs) == 0)
        return fail_at(d, FM_ERR_INPUT, segs_off,
                       "\"segments\": expected a non-empty array of segments");
    d->n = json_array_size(segs);
    if (d->n > d->opt.max_segments)
        return fail_at(d, FM_ERR_LIMIT, segs_off, "%zu segments; the limit is %zu", d->n,
                       d->opt.max_segments);
    size_t bytes;
    if (!fm_size_mul(d->n, sizeof *d->segs, &bytes) ||
        !(d->segs = calloc(d->n, sizeof *d->segs)) ||
        !(d->seg_off = malloc(d->n * sizeof *d->seg_off)))
        return fail_at(d, FM_ERR_LIMIT, segs_off, "out of memory for %zu segments", d->n);
    size_t found = traj_json_elements(d->text, d->len, segs_off, d->seg_off, d->n);
    for (size_t i = found; i < d->n; i++) d->seg_off[i] = segs_off;
    int *lines = malloc(d->n * sizeof *lines);
    if (!lines) return fail_at(d, FM_ERR_LIMIT, segs_off, "out of memory for %zu segments", d->n);
    traj_json_lines(d->text, d->len, d->seg_off, d->n, lines);
    d->g = fm_graph_new(d->opt.max_total_nodes);
    if (!d->g) {
        free(lines);
        return fail_at(d, FM_ERR_LIMIT, segs_off, "out of memory for the expression graph");
    }
    double feed = 0, spindle = 0;
    long prev_feed = -1;
    fm_status st = FM_OK;
    for (size_t i = 0; i < d->n && !st; i++) {
        traj_seg *s = &d->segs[i];
        st = parse_segment(d, i, json_array_get(segs, i), s, &tool, &feed, &spindle);
        s->line = lines[i];
        if (st) break;
        if (i == 0 && s->rapid)
            st = fail_at(d, FM_ERR_INPUT, d->seg_off[0],
                         "segment 0: a rapid cannot be the first segment (it starts where the "
                         "previous segment ends)");
        else if (i > 0)
            st = check_join(d, i, prev_feed);
        if (!s->rapid) prev_feed = (long)i;
    }
    if (!st && d->segs[d->n - 1].rapid && !d->segs[d->n - 1].has_to)
        st = fail_at(d, FM_ERR_INPUT, d->seg_off[d->n - 1],
                     "segment %zu: a rapid at the end needs \"to\": [x, y, z]", d->n - 1);
    free(lines);
    return st;
}

static void motion_common(fm_motion *m, const traj_seg *s, size_t i, long index)
{
    memset(m, 0, sizeof *m);
    m->tool = s->tool;
    m->spindle_rpm = fabs(s->spindle);
    m->spindle_dir = s->spindle > 0 ? 1 : s->spindle < 0 ? -1 : 0;
    m->line = s->line;
    m->block = (long)i;
    m->index = index;
}

/* Emit the validated document: feed segments follow each other in program
 * time, rapids take their length at the rapid rate. */
static fm_status emit(traj_doc *d, fm_motion_sink sink, void *user, fm_traj_summary *sum)
{
    double now = d->segs[0].t0, pos[3] = {0, 0, 0}, axis[3] = {0, 0, 1};
    long index = 0;
    int tool = d->segs[0].tool;
    double spindle = d->segs[0].spindle;
    for (size_t i = 0; i < d->n && !sum->stopped; i++) {
        traj_seg *s = &d->segs[i];
        fm_motion m;
        if (s->rapid) {
            double to[3], to_axis[3];
            if (s->has_to) {
                memcpy(to, s->to, sizeof to);
                memcpy(to_axis, axis, sizeof to_axis);
            } else {
                traj_seg_pose_doc(&d->segs[i + 1], d->segs[i + 1].t0, to, to_axis);
            }
            double len = dist3(pos, to);
            if (len == 0 && !memcmp(axis, to_axis, sizeof axis)) continue;
            s->tool = tool;
            s->spindle = spindle;
            motion_common(&m, s, i, index);
            m.kind = FM_MOTION_RAPID;
            memcpy(m.start, pos, sizeof pos);
            memcpy(m.end, to, sizeof to);
            memcpy(m.axis_start, axis, sizeof axis);
            memcpy(m.axis_end, to_axis, sizeof to_axis);
            m.t0 = now;
            m.t1 = now + len / d->opt.rapid_rate * 60;
            memcpy(pos, to, sizeof pos);
            memcpy(axis, to_axis, sizeof axis);
        } else {
            s->shift = now - s->t0;
            motion_common(&m, s, i, index);
            m.kind = FM_MOTION_PARAM;
            m.feed = s->feed;
            traj_seg_pose_doc(s, s->t0, m.start, m.axis_start);
            traj_seg_pose_doc(s, s->t1, m.end, m.axis_end);
            m.t0 = now;
            m.t1 = s->t1 + s->shift;
            m.path = &s->path;
            memcpy(pos, m.end, sizeof pos);
            memcpy(axis, m.axis_end, sizeof axis);
            tool = s->tool;
            spindle = s->spindle;
        }
        now = m.t1;
        if (index >= d->opt.skip_motions && sink && sink(user, &m)) sum->stopped = 1;
        index++;
    }
    sum->motions = index;
    sum->seconds = now;
    return FM_OK;
}

fm_status fm_traj_run_string(const char *text, size_t len, const char *name,
                             const fm_traj_options *opt, fm_motion_sink sink, void *user,
                             fm_traj_summary *summary, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    traj_doc d;
    memset(&d, 0, sizeof d);
    d.text = text;
    d.len = len;
    d.name = name ? name : "";
    d.err = err;
    if (opt)
        d.opt = *opt;
    else
        fm_traj_options_default(&d.opt);
    fm_traj_summary sum = {0, 0, 0, 0};
    if (!text) return fm_error_set(err, FM_ERR_INTERNAL, "fm_traj_run_string: no text");
    if (d.opt.samples < 2 || !(d.opt.rapid_rate > 0) || !(d.opt.tolerance > 0) ||
        !(d.opt.axis_tolerance > 0))
        return fm_error_set(err, FM_ERR_INTERNAL,
                            "fm_traj_run_string: options need samples >= 2 and positive rapid "
                            "rate and tolerances");
    if (len > d.opt.max_document_bytes)
        return fm_error_at(err, FM_ERR_LIMIT, d.name, 0, 0,
                           "trajectory of %zu bytes; the limit is %zu", len,
                           d.opt.max_document_bytes);
    json_error_t je;
    json_t *root = json_loadb(text, len, JSON_REJECT_DUPLICATES, &je);
    if (!root)
        return fm_error_at(err, FM_ERR_INPUT, d.name, je.line > 0 ? je.line : 0,
                           je.column > 0 ? je.column : 0, "invalid JSON: %s", je.text);
    fm_status st = parse_document(&d, root);
    sum.segments = (long)d.n;
    if (!st) st = emit(&d, sink, user, &sum);
    if (summary) *summary = sum;
    for (size_t i = 0; d.segs && i < d.n; i++) traj_seg_free(&d.segs[i]);
    free(d.segs);
    free(d.seg_off);
    fm_graph_free(d.g);
    json_decref(root);
    return st;
}

fm_status fm_traj_run_file(const char *path, const fm_traj_options *opt, fm_motion_sink sink,
                           void *user, fm_traj_summary *summary, fm_error *err)
{
    fm_traj_options o;
    if (opt)
        o = *opt;
    else
        fm_traj_options_default(&o);
    char *buf;
    size_t len;
    fm_status st = fm_file_read(path, "trajectory", o.max_document_bytes, &buf, &len, err);
    if (st) {
        if (err) snprintf(err->file, sizeof err->file, "%s", path);
        return st;
    }
    st = fm_traj_run_string(buf, len, path, &o, sink, user, summary, err);
    free(buf);
    return st;
}
