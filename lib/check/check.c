/* check.c: the collision and safety relations of check.h, motion by
 * motion: which part of the tool is related to what (relate.c does one
 * relation), the flutes not yet cut from the grid, travel limits, the
 * start position, feeds with no tool, and the findings, grouped over consecutive motions with
 * the same kind and part. */
#include "check/check.h"
#include "check/check_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sweep/sweep.h"

void fm_check_options_default(fm_check_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->tolerance_mm = 0.01;
    opt->clearance_mm[FM_CHECK_PART_FLUTES] = 0.0;
    opt->clearance_mm[FM_CHECK_PART_SHANK] = 0.0;
    opt->clearance_mm[FM_CHECK_PART_HOLDER] = 1.0;
    opt->clearance_mm[FM_CHECK_PART_HEAD] = 1.0;
    opt->max_ramp_deg = 3.0;
}

int fm_check_band_voxels(const fm_check_options *opt, double voxel_mm)
{
    double clear = 0;
    for (int p = 0; p < FM_CHECK_PART_COUNT; p++) clear = fmax(clear, opt->clearance_mm[p]);
    /* A near miss within the clearance is seen where the grid's values reach
     * that far out (and a voxel more, for the voxel centres between part and
     * stock); a clamped value only hides near misses, never makes one.
     * Deeper than the band, depths are searched (relate.c). */
    int need = (int)ceil(clear / voxel_mm - 1e-9) + 1;
    return need > 3 ? need : 3;
}

const char *fm_check_kind_name(fm_check_kind kind)
{
    static const char *const names[FM_CHECK_KIND_COUNT] = {
        "rapid_into_stock",  "shank_contact",   "holder_contact", "fixture_contact",
        "non_center_plunge", "spindle_off_cut", "travel_limit",   "start_in_stock",
        "uncertain",         "machine_contact", "no_tool"};
    return (unsigned)kind < FM_CHECK_KIND_COUNT ? names[kind] : "unknown";
}

const char *fm_check_severity_name(fm_check_severity severity)
{
    return severity == FM_CHECK_ERROR ? "error" : "warning";
}

const char *fm_check_part_name(fm_check_part part)
{
    static const char *const names[FM_CHECK_PART_COUNT] = {"flutes", "shank", "holder", "head"};
    return (unsigned)part < FM_CHECK_PART_COUNT ? names[part] : "unknown";
}

fm_check *fm_check_new(const fm_check_options *opt, fm_error *err)
{
    fm_check_options o;
    if (opt) o = *opt;
    else fm_check_options_default(&o);
    if (!(o.tolerance_mm > 0) || !isfinite(o.tolerance_mm)) {
        fm_error_set(err, FM_ERR_INPUT, "the contact tolerance must be above 0 mm (got %g)",
                     o.tolerance_mm);
        return NULL;
    }
    for (int p = 0; p < FM_CHECK_PART_COUNT; p++)
        if (!(o.clearance_mm[p] >= 0) || !isfinite(o.clearance_mm[p])) {
            fm_error_set(err, FM_ERR_INPUT, "the %s clearance must be 0 mm or more (got %g)",
                         fm_check_part_name((fm_check_part)p), o.clearance_mm[p]);
            return NULL;
        }
    if (!(o.max_ramp_deg >= 0 && o.max_ramp_deg <= 90)) {
        fm_error_set(err, FM_ERR_INPUT, "the ramp limit must be 0..90 degrees (got %g)",
                     o.max_ramp_deg);
        return NULL;
    }
    for (int a = 0; a < 3; a++)
        if (o.machine.has_limit[a] && !(o.machine.limit_lo[a] <= o.machine.limit_hi[a])) {
            fm_error_set(err, FM_ERR_INPUT, "the machine's %c travel is empty (%g .. %g)",
                         "XYZ"[a], o.machine.limit_lo[a], o.machine.limit_hi[a]);
            return NULL;
        }
    fm_check *c = calloc(1, sizeof *c);
    if (!c) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        return NULL;
    }
    c->opt = o;
    c->sweep_opt.max_evaluations = o.sweep_evaluations;
    for (int k = 0; k < FM_CHECK_KIND_COUNT; k++)
        for (int p = 0; p < FM_CHECK_PART_COUNT; p++) c->open[k][p] = -1;
    return c;
}

void fm_check_stock_cut(fm_check *c)
{
    for (size_t i = 0; i < c->pending_count; i++) fm_sweep_free(c->pending[i].sweep);
    c->pending_count = 0;
}

void fm_check_free(fm_check *c)
{
    if (!c) return;
    fm_check_stock_cut(c);
    free(c->pending);
    for (size_t i = 0; i < c->worker_count; i++)
        for (int p = 0; p < FM_CHECK_PART_COUNT; p++) {
            fm_sweep_worker_free(c->workers[i].w[p]);
            fm_sweep_free(c->workers[i].keep[p]);
        }
    free(c->workers);
    for (size_t i = 0; i < c->fixture_count; i++) check_fixture_free(&c->fixtures[i]);
    free(c->fixtures);
    free(c->open_fixture);
    free(c->findings);
    free(c->hit_now);
    free(c->leaves);
    free(c->tiles);
    free(c->deep);
    free(c);
}

void fm_check_set_initial_box(fm_check *c, const double lo[3], const double hi[3])
{
    c->have_box = 1;
    for (int a = 0; a < 3; a++) {
        c->box_lo[a] = lo[a];
        c->box_hi[a] = hi[a];
    }
}

size_t fm_check_count(const fm_check *c) { return c->finding_count; }

const fm_check_finding *fm_check_get(const fm_check *c, size_t i)
{
    return i < c->finding_count ? &c->findings[i] : NULL;
}

size_t fm_check_count_severity(const fm_check *c, fm_check_severity s)
{
    size_t n = 0;
    for (size_t i = 0; i < c->finding_count; i++) n += c->findings[i].severity == s;
    return n;
}

void fm_check_get_stats(const fm_check *c, fm_check_stats *stats) { *stats = c->stats; }

const fm_sweep_options *check_sweep_options(const fm_check *c) { return &c->sweep_opt; }

/* ------------------------------------------------------- bookkeeping -- */

static check_workers *worker_slot(fm_check *c, int tool)
{
    for (size_t i = 0; i < c->worker_count; i++)
        if (c->workers[i].tool == tool) return &c->workers[i];
    if (c->worker_count == c->worker_cap) {
        size_t cap = c->worker_cap ? 2 * c->worker_cap : 8;
        check_workers *w = realloc(c->workers, cap * sizeof *w);
        if (!w) return NULL;
        c->workers = w;
        c->worker_cap = cap;
    }
    check_workers *w = &c->workers[c->worker_count++];
    memset(w, 0, sizeof *w);
    w->tool = tool;
    return w;
}

/* A worker for the part of this tool (one per tool and part: a worker made
 * for one sweep serves every sweep of the same part), made from a still
 * sweep of the part kept with it. */
static fm_sweep_worker *worker_for(fm_check *c, int tool, fm_check_part part,
                                   const fm_tool_part *tp)
{
    check_workers *slot = worker_slot(c, tool);
    if (!slot) return NULL;
    if (!slot->w[part]) {
        if (!slot->keep[part]) {
            fm_motion still;
            memset(&still, 0, sizeof still);
            still.kind = FM_MOTION_RAPID;
            still.axis_start[2] = still.axis_end[2] = 1;
            fm_error err;
            if (fm_sweep_new(&still, tp, NULL, &slot->keep[part], &err) != FM_OK) return NULL;
        }
        slot->w[part] = fm_sweep_worker_new(slot->keep[part]);
    }
    return slot->w[part];
}

static int is_straight(const fm_motion *m)
{
    if (m->kind != FM_MOTION_RAPID && m->kind != FM_MOTION_LINE) return 0;
    for (int a = 0; a < 3; a++)
        if (m->axis_start[a] != m->axis_end[a]) return 0;
    return 1;
}

static int *open_slot(fm_check *c, fm_check_kind kind, fm_check_part part, int fixture)
{
    return kind == FM_CHECK_FIXTURE_CONTACT ? &c->open_fixture[fixture * FM_CHECK_PART_COUNT + part]
                                            : &c->open[kind][part];
}

/* Record a hit of (kind, part[, fixture]) by this motion: open a finding or
 * extend the open one. */
static fm_status record(fm_check *c, fm_check_kind kind, fm_check_part part, int fixture,
                        const fm_check_finding *hit, fm_error *err)
{
    int *open = open_slot(c, kind, part, fixture);
    if (*open >= 0) {
        fm_check_finding *f = &c->findings[*open];
        if (hit->penetration_mm > f->penetration_mm) f->penetration_mm = hit->penetration_mm;
        if (hit->severity > f->severity) f->severity = hit->severity;
        f->points += hit->points;
        if (!c->hit_now[*open]) {
            f->last_line = hit->line;
            f->motions++;
        }
        c->hit_now[*open] = 1;
        return FM_OK;
    }
    if (c->finding_count == c->finding_cap) {
        size_t cap = c->finding_cap ? 2 * c->finding_cap : 16;
        fm_check_finding *f = realloc(c->findings, cap * sizeof *f);
        if (f) c->findings = f;
        unsigned char *h = realloc(c->hit_now, cap);
        if (h) c->hit_now = h;
        if (!f || !h) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        c->finding_cap = cap;
    }
    fm_check_finding *f = &c->findings[c->finding_count];
    *f = *hit;
    /* a machine component, or the machine's head, meeting anything */
    f->kind = (kind == FM_CHECK_FIXTURE_CONTACT && c->fixtures[fixture].machine) ||
                      (part == FM_CHECK_PART_HEAD && kind != FM_CHECK_NO_TOOL)
                  ? FM_CHECK_MACHINE_CONTACT
                  : kind;
    f->part = part;
    f->fixture = kind == FM_CHECK_FIXTURE_CONTACT ? fixture : -1;
    f->last_line = hit->line;
    f->motions = 1;
    c->hit_now[c->finding_count] = 1;
    *open = (int)c->finding_count++;
    return FM_OK;
}

/* After a motion: findings it did not extend are closed. */
static void close_unhit(fm_check *c)
{
    for (int k = 0; k < FM_CHECK_KIND_COUNT; k++)
        for (int p = 0; p < FM_CHECK_PART_COUNT; p++)
            if (c->open[k][p] >= 0 && !c->hit_now[c->open[k][p]]) c->open[k][p] = -1;
    for (size_t i = 0; i < c->fixture_count * FM_CHECK_PART_COUNT; i++)
        if (c->open_fixture[i] >= 0 && !c->hit_now[c->open_fixture[i]]) c->open_fixture[i] = -1;
    if (c->finding_count) memset(c->hit_now, 0, c->finding_count);
}

void fm_check_finish(fm_check *c)
{
    if (c->finding_count) memset(c->hit_now, 0, c->finding_count);
    close_unhit(c);
}

/* -------------------------------------------------------- relations -- */

/* The machine's head as a part of the tool numbered `number` (built once
 * per tool: it stands on the tool's holder); NULL when the machine has no
 * head segments or they do not make a part. */
static const fm_tool_part *head_part(fm_check *c, int number, const fm_tool *t)
{
    if (c->opt.machine.head_count <= 0) return NULL;
    check_workers *slot = worker_slot(c, number);
    if (!slot) return NULL;
    if (slot->head_state == 0)
        slot->head_state = fm_tool_build_head(&t->spec, c->opt.machine.head, c->opt.machine.head_count,
                                              &slot->head, NULL) == FM_OK
                               ? 1
                               : -1;
    return slot->head_state > 0 ? &slot->head : NULL;
}

static const fm_tool_part *tool_part(fm_check *c, int number, const fm_tool *t, fm_check_part p)
{
    switch (p) {
    case FM_CHECK_PART_FLUTES: return &t->flutes;
    case FM_CHECK_PART_SHANK: return t->has_shank ? &t->shank : NULL;
    case FM_CHECK_PART_HOLDER: return t->has_holder ? &t->holder : NULL;
    case FM_CHECK_PART_HEAD: return head_part(c, number, t);
    default: return NULL;
    }
}

/* One part over a motion against a grid, and what it finds recorded as
 * kind (an uncertain point as FM_CHECK_UNCERTAIN). flutes, when given,
 * lead the part: time order. */
typedef struct part_ctx {
    const fm_motion *m;
    const fm_tool *tool;
    fm_check_part part;
    const fm_sweep *sweep;
    fm_sweep_worker *worker;
    const fm_sweep *flutes;
    fm_sweep_worker *flutes_worker;
    /* A part swept in the frame of a link nearer the base (frame_up > 0):
     * findings give the tool's place from `report`, its sweep in the
     * workpiece frame, and carry the contact point back to that frame. */
    const fm_sweep *report;
    int frame_up;
} part_ctx;

/* A point of the link frame_up table axes nearer the base than the
 * workpiece's, at motion m's joints at time t, in the workpiece frame:
 * x_machine = R_link x + t_link = R_work x_work + t_work. */
static void link_to_workpiece(const fm_motion *m, int frame_up, double t, const double p[3], double out[3])
{
    const fm_machine *mc = m->machine;
    double joints[3], rl[9], tl[3], rw[9], tw[3], x[3];
    fm_motion_joints_at(m, t, joints);
    fm_machine_table_transform(mc, joints, fm_machine_table_axes(mc) - frame_up, rl, tl);
    fm_machine_table_transform(mc, joints, -1, rw, tw);
    for (int r = 0; r < 3; r++) x[r] = rl[3 * r] * p[0] + rl[3 * r + 1] * p[1] + rl[3 * r + 2] * p[2] + tl[r] - tw[r];
    for (int r = 0; r < 3; r++) out[r] = rw[r] * x[0] + rw[3 + r] * x[1] + rw[6 + r] * x[2];
}

/* Where the finding puts the tool and the contact (workpiece frame). */
static void finding_place(const part_ctx *pc, double t, const double at[3], fm_check_finding *f)
{
    double axis[3];
    fm_sweep_pose(pc->report ? pc->report : pc->sweep, t, f->position, axis);
    if (pc->frame_up > 0)
        link_to_workpiece(pc->m, pc->frame_up, t, at, f->contact);
    else
        memcpy(f->contact, at, sizeof f->contact);
}

static fm_status relate_part(fm_check *c, const part_ctx *pc, const fm_stock *grid, int is_stock,
                             int ordered, double clear, fm_check_kind kind, int fixture,
                             fm_error *err)
{
    if (!grid) return FM_OK;
    const fm_tool_part *shape = tool_part(c, pc->m->tool, pc->tool, pc->part);
    check_rel r;
    memset(&r, 0, sizeof r);
    r.check = c;
    r.grid = grid;
    r.is_stock = is_stock;
    r.motion = pc->m;
    r.shape = shape;
    r.sweep = pc->sweep;
    r.worker = pc->worker;
    r.custom = shape->kind == FM_TOOL_PART_CUSTOM;
    if (ordered && pc->flutes) {
        r.flutes_shape = &pc->tool->flutes;
        r.flutes = pc->flutes;
        r.flutes_worker = pc->flutes_worker;
    }
    r.threshold = clear > 0 ? -clear : 0.5 * c->opt.tolerance_mm;
    /* every point of the part lies within half a voxel diagonal of a voxel
     * centre: look one voxel beyond the part (and the clearance) */
    r.reach = clear + fm_stock_voxel_size(grid);
    int open = *open_slot(c, kind, pc->part, fixture);
    r.need_first = open < 0;
    r.known = open >= 0 ? c->findings[open].penetration_mm : 0;
    fm_status st = check_relate(&r, err);
    if (st != FM_OK) return st;
    const fm_motion *m = pc->m;
    if (r.uncertain) {
        c->stats.uncertain += r.uncertain;
        fm_check_finding f;
        memset(&f, 0, sizeof f);
        f.severity = FM_CHECK_WARNING;
        f.line = m->line;
        f.block = m->block;
        f.time_s = r.uncertain_t;
        finding_place(pc, r.uncertain_t, r.uncertain_at, &f);
        f.points = r.uncertain;
        st = record(c, FM_CHECK_UNCERTAIN, pc->part, -1, &f, err);
        if (st != FM_OK) return st;
    }
    if (!r.found) return FM_OK;
    fm_check_finding f;
    memset(&f, 0, sizeof f);
    f.penetration_mm = r.depth > 0 ? r.depth : 0;
    f.severity = f.penetration_mm > c->opt.tolerance_mm ? FM_CHECK_ERROR : FM_CHECK_WARNING;
    f.line = m->line;
    f.block = m->block;
    double t = r.need_first ? r.first_t : r.depth_t;
    const double *at = r.need_first ? r.first_at : r.depth_at;
    f.time_s = t;
    finding_place(pc, t, at, &f);
    return record(c, kind, pc->part, fixture, &f, err);
}

/* A motion that holds the tool still at a pose (tip, axis) at time t. */
static void static_motion(const fm_motion *like, const double tip[3], const double axis[3],
                          double t, fm_motion *out)
{
    memset(out, 0, sizeof *out);
    out->kind = FM_MOTION_RAPID;
    for (int a = 0; a < 3; a++) {
        out->start[a] = out->end[a] = tip[a];
        out->axis_start[a] = out->axis_end[a] = axis[a];
    }
    out->t0 = out->t1 = t;
    out->line = 0;
    out->block = -1;
    out->tool = like->tool;
}

/* The tool standing at the start position, before the first motion. */
static fm_status check_start(fm_check *c, const fm_motion *first, const fm_tool *tool,
                             const fm_stock *stock, fm_error *err)
{
    const double axis[3] = {0, 0, 1};
    fm_motion sm;
    static_motion(first, c->opt.machine.start, axis, first->t0, &sm);
    for (int p = 0; p < FM_CHECK_PART_COUNT; p++) {
        const fm_tool_part *tp = tool_part(c, first->tool, tool, (fm_check_part)p);
        if (!tp) continue;
        fm_sweep *s = NULL;
        fm_status st = fm_sweep_new(&sm, tp, check_sweep_options(c), &s, err);
        if (st != FM_OK) return st;
        fm_sweep_worker *w = worker_for(c, first->tool, (fm_check_part)p, tp);
        if (!w) {
            fm_sweep_free(s);
            return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        }
        /* the machine stands with every joint at 0: every link's frame is
         * the workpiece's */
        part_ctx pc = {&sm, tool, (fm_check_part)p, s, w, NULL, NULL, NULL, 0};
        st = relate_part(c, &pc, stock, 1, 0, 0.0, FM_CHECK_START_IN_STOCK, -1, err);
        for (size_t fx = 0; st == FM_OK && fx < c->fixture_count; fx++)
            st = relate_part(c, &pc, c->fixtures[fx].grid, 0, 0, c->opt.clearance_mm[p],
                             FM_CHECK_FIXTURE_CONTACT, (int)fx, err);
        fm_sweep_free(s);
        if (st != FM_OK) return st;
    }
    return FM_OK;
}

/* The stock's value at p (positive inside): the grid less the flutes not
 * yet cut when c is given. */
static double stock_value(const fm_check *c, const fm_stock *stock, const double p[3])
{
    double g = fm_stock_sample(stock, p);
    for (size_t j = 0; c && g > 0 && j < c->pending_count; j++)
        g = fmin(g, -fm_sweep_eval(c->pending[j].sweep, c->pending[j].worker, p));
    return g;
}

#define TIP_MAX_SAMPLES (1L << 20)

static int tip_in_stock(const fm_check *c, const fm_motion *m, const fm_stock *stock,
                        double min_depth, double *u_first, double *depth)
{
    /* the tip's path length, from a polyline fine enough for arcs and
     * rotary motions, gives the samples' count */
    int pieces = fm_motion_pieces(m, 0.05, 64, 4096);
    double len = 0, prev[3], tip[3], axis[3];
    fm_motion_pose_at(m, 0, prev, axis);
    for (int i = 1; i <= pieces; i++) {
        fm_motion_pose_at(m, (double)i / pieces, tip, axis);
        len += sqrt((tip[0] - prev[0]) * (tip[0] - prev[0]) + (tip[1] - prev[1]) * (tip[1] - prev[1]) +
                    (tip[2] - prev[2]) * (tip[2] - prev[2]));
        memcpy(prev, tip, sizeof prev);
    }
    double step = 0.5 * fm_stock_voxel_size(stock);
    double want = step > 0 && isfinite(len) ? ceil(len / step) : (double)pieces;
    long n = want < pieces ? pieces : want > TIP_MAX_SAMPLES ? TIP_MAX_SAMPLES : (long)want;
    int found = 0;
    double deepest = -INFINITY;
    for (long i = 0; i <= n; i++) {
        double u = (double)i / (double)n;
        fm_motion_pose_at(m, u, tip, axis);
        double v = stock_value(c, stock, tip);
        if (v > min_depth && !found) {
            found = 1;
            *u_first = u;
        }
        if (v > deepest) deepest = v;
    }
    *depth = deepest;
    return found;
}

int fm_check_tip_in_stock(const fm_motion *m, const fm_stock *stock, double min_depth, double *u,
                          double *depth)
{
    return tip_in_stock(NULL, m, stock, min_depth, u, depth);
}

/* A feed motion with no tool in the spindle: the spindle's nose goes where
 * the tip is programmed; into the stock it is a no_tool finding (its
 * penetration the tip's depth, within the grid's band). */
static fm_status check_no_tool(fm_check *c, const fm_motion *m, const fm_stock *stock, fm_error *err)
{
    double u = 0, depth = 0, axis[3];
    if (!stock || !tip_in_stock(c, m, stock, 0.5 * c->opt.tolerance_mm, &u, &depth)) return FM_OK;
    fm_check_finding f;
    memset(&f, 0, sizeof f);
    f.penetration_mm = depth;
    f.severity = depth > c->opt.tolerance_mm ? FM_CHECK_ERROR : FM_CHECK_WARNING;
    f.line = m->line;
    f.block = m->block;
    f.time_s = m->t0 + u * (m->t1 - m->t0);
    fm_motion_pose_at(m, u, f.position, axis);
    memcpy(f.contact, f.position, sizeof f.contact);
    return record(c, FM_CHECK_NO_TOOL, FM_CHECK_PART_HEAD, -1, &f, err);
}

/* A travel_limit finding of motion m at point p, overrun by `over` (mm or
 * degrees). */
static fm_status record_travel_limit(fm_check *c, const fm_motion *m, const double p[3],
                                     double over, fm_error *err)
{
    fm_check_finding f;
    memset(&f, 0, sizeof f);
    f.severity = FM_CHECK_ERROR;
    f.line = m->line;
    f.block = m->block;
    f.time_s = m->t0;
    memcpy(f.position, p, sizeof f.position);
    memcpy(f.contact, p, sizeof f.contact);
    f.penetration_mm = over;
    return record(c, FM_CHECK_TRAVEL_LIMIT, FM_CHECK_PART_FLUTES, -1, &f, err);
}

/* A rotary joint beyond its travel: the joints move linearly in joint
 * space from start to end (with TCP too), so the ends bound the travel.
 * Wrapped axes roll over and have no travel to leave. penetration_mm is
 * the overrun in degrees. */
static fm_status check_rotary_travel(fm_check *c, const fm_motion *m, fm_error *err)
{
    const fm_machine *chain = &c->opt.machine.chain;
    double worst = 0;
    int end_out = 0;
    for (int i = 0; i < chain->rotary_count; i++) {
        const fm_rotary_axis *r = &chain->rotary[i];
        if (!r->has_limits || r->wrapped || r->letter < 0 || r->letter > 2) continue;
        double s = m->rotary_start[r->letter], e = m->rotary_end[r->letter];
        double over = fmax(fmax(r->limit_lo - fmin(s, e), fmax(s, e) - r->limit_hi), 0);
        if (over > worst) {
            worst = over;
            end_out = e < r->limit_lo || e > r->limit_hi;
        }
    }
    if (worst <= 0) return FM_OK;
    const double *p = end_out ? m->end : m->start;
    return record_travel_limit(c, m, p, worst, err);
}

static fm_status check_travel(fm_check *c, const fm_motion *m, fm_error *err)
{
    fm_status st = check_rotary_travel(c, m, err);
    if (st != FM_OK) return st;
    const fm_check_machine *mc = &c->opt.machine;
    double lo[3], hi[3];
    check_motion_point_bounds(m, lo, hi);
    double worst = 0;
    int axis = -1;
    for (int a = 0; a < 3; a++) {
        if (!mc->has_limit[a]) continue;
        double over = fmax(mc->limit_lo[a] - lo[a], hi[a] - mc->limit_hi[a]);
        if (over > worst) {
            worst = over;
            axis = a;
        }
    }
    if (axis < 0) return FM_OK;
    /* the end beyond the limit, else the start (arcs: the end is a fair guess) */
    const double *p = m->end;
    if (m->end[axis] >= mc->limit_lo[axis] && m->end[axis] <= mc->limit_hi[axis]) p = m->start;
    return record_travel_limit(c, m, p, worst, err);
}

/* The motion's flutes stay in the stock's exact distance until the caller
 * says they are cut. */
static fm_status add_pending(fm_check *c, const fm_motion *m, const fm_tool *tool,
                             fm_sweep_worker *w, fm_error *err)
{
    if (c->pending_count == FM_CHECK_MAX_PENDING)
        return fm_error_set(err, FM_ERR_INTERNAL,
                            "%d motions fed to the check without a cut of the stock between",
                            FM_CHECK_MAX_PENDING);
    if (c->pending_count == c->pending_cap) {
        size_t cap = c->pending_cap ? 2 * c->pending_cap : 64;
        check_pending *p = realloc(c->pending, cap * sizeof *p);
        if (!p) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        c->pending = p;
        c->pending_cap = cap;
    }
    check_pending *p = &c->pending[c->pending_count];
    fm_status st = fm_sweep_new(m, &tool->flutes, check_sweep_options(c), &p->sweep, err);
    if (st != FM_OK) return st;
    p->worker = w;
    fm_sweep_bounds(p->sweep, p->lo, p->hi);
    c->pending_count++;
    return FM_OK;
}

/* Machine components on links nearer the base than the workpiece's: each
 * part swept in that link's frame (the motion's chain with frame_up, where
 * the component stands still) and related to the component there. Only
 * motions with joint values can be placed there (not parametric ones). */
static fm_status check_moving_components(fm_check *c, const fm_motion *m, const fm_tool *tool,
                                         fm_sweep *const sweeps[], fm_sweep_worker *const workers[],
                                         fm_error *err)
{
    if (!fm_motion_has_rotary(m)) return FM_OK;
    fm_status st = FM_OK;
    for (int up = 1; up <= FM_MACHINE_MAX_ROTARY && st == FM_OK; up++) {
        int any = 0;
        for (size_t fx = 0; fx < c->fixture_count; fx++) any |= c->fixtures[fx].grid && c->fixtures[fx].frame_up == up;
        if (!any) continue;
        fm_machine frame = *m->machine;
        frame.frame_up = up;
        fm_motion mf = *m;
        mf.machine = &frame;
        for (int p = 0; p < FM_CHECK_PART_COUNT && st == FM_OK; p++) {
            if (!sweeps[p]) continue;
            fm_sweep *s = NULL;
            st = fm_sweep_new(&mf, tool_part(c, m->tool, tool, (fm_check_part)p), check_sweep_options(c), &s, err);
            if (st != FM_OK) break;
            part_ctx pc = {&mf, tool, (fm_check_part)p, s, workers[p], NULL, NULL, sweeps[p], up};
            for (size_t fx = 0; st == FM_OK && fx < c->fixture_count; fx++)
                if (c->fixtures[fx].frame_up == up)
                    st = relate_part(c, &pc, c->fixtures[fx].grid, 0, 0, c->opt.clearance_mm[p],
                                     FM_CHECK_FIXTURE_CONTACT, (int)fx, err);
            fm_sweep_free(s);
        }
    }
    return st;
}

fm_status fm_check_motion(fm_check *c, const fm_motion *m, const fm_tool *tool,
                          const fm_stock *stock, fm_error *err)
{
    c->stats.motions++;
    if (!c->open_fixture && c->fixture_count) {
        c->open_fixture = malloc(c->fixture_count * FM_CHECK_PART_COUNT * sizeof *c->open_fixture);
        if (!c->open_fixture) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        for (size_t i = 0; i < c->fixture_count * FM_CHECK_PART_COUNT; i++) c->open_fixture[i] = -1;
    }
    fm_status st = FM_OK;
    if (!c->started) {
        c->started = 1;
        if (tool) st = check_start(c, m, tool, stock, err);
        if (st != FM_OK) return st;
        close_unhit(c); /* the start is a place of its own */
    }
    /* The machine stands at the start position before the first motion,
     * wherever the interpreter assumed it was: the first straight motion
     * goes from there (the stock is cut as the interpreter says). */
    const fm_motion *cut = m;
    fm_motion first;
    if (c->stats.motions == 1 && is_straight(m)) {
        first = *m;
        for (int a = 0; a < 3; a++) first.start[a] = c->opt.machine.start[a] - m->tip_offset[a];
        m = &first;
    }
    st = check_travel(c, m, err);
    if (st != FM_OK) return st;
    if (!tool || m->kind == FM_MOTION_DWELL) {
        if (!tool && m->kind != FM_MOTION_DWELL && m->kind != FM_MOTION_RAPID)
            st = check_no_tool(c, m, stock, err);
        close_unhit(c);
        return st;
    }

    int rapid = m->kind == FM_MOTION_RAPID;
    int spindle_off = !rapid && (m->spindle_rpm <= 0 || m->spindle_dir == 0);
    int plunge = !rapid && !tool->spec.center_cutting && check_descent_deg(m) > c->opt.max_ramp_deg;
    fm_sweep *sweeps[FM_CHECK_PART_COUNT] = {NULL};
    fm_sweep_worker *workers[FM_CHECK_PART_COUNT] = {NULL};
    for (int p = 0; p < FM_CHECK_PART_COUNT && st == FM_OK; p++) {
        const fm_tool_part *tp = tool_part(c, m->tool, tool, (fm_check_part)p);
        if (!tp) continue;
        st = fm_sweep_new(m, tp, check_sweep_options(c), &sweeps[p], err);
        if (st != FM_OK) break;
        workers[p] = worker_for(c, m->tool, (fm_check_part)p, tp);
        if (!workers[p]) st = fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    }
    for (int p = 0; p < FM_CHECK_PART_COUNT && st == FM_OK; p++) {
        if (!sweeps[p]) continue;
        part_ctx pc = {m,          tool, (fm_check_part)p, sweeps[p], workers[p], sweeps[FM_CHECK_PART_FLUTES],
                       workers[FM_CHECK_PART_FLUTES], NULL, 0};
        if (p == FM_CHECK_PART_FLUTES) {
            /* Feed motions' flutes are meant to cut; a rapid's must not, and
             * a feed's matter when the spindle is off or it plunges a tool
             * that cannot cut at its centre. Against the stock before the
             * motion: the flutes do not shelter themselves. */
            if (rapid)
                st = relate_part(c, &pc, stock, 1, 0, c->opt.clearance_mm[p],
                                 FM_CHECK_RAPID_INTO_STOCK, -1, err);
            if (st == FM_OK && spindle_off)
                st = relate_part(c, &pc, stock, 1, 0, 0.0, FM_CHECK_SPINDLE_OFF_CUT, -1, err);
            if (st == FM_OK && plunge)
                st = relate_part(c, &pc, stock, 1, 0, 0.0, FM_CHECK_NON_CENTER_PLUNGE, -1, err);
        } else {
            fm_check_kind kind = p == FM_CHECK_PART_SHANK    ? FM_CHECK_SHANK_CONTACT
                                 : p == FM_CHECK_PART_HOLDER ? FM_CHECK_HOLDER_CONTACT
                                                             : FM_CHECK_MACHINE_CONTACT;
            st = relate_part(c, &pc, stock, 1, 1, c->opt.clearance_mm[p], kind, -1, err);
        }
        for (size_t fx = 0; st == FM_OK && fx < c->fixture_count; fx++)
            if (!c->fixtures[fx].frame_up)
                st = relate_part(c, &pc, c->fixtures[fx].grid, 0, 0, c->opt.clearance_mm[p],
                                 FM_CHECK_FIXTURE_CONTACT, (int)fx, err);
    }
    if (st == FM_OK) st = check_moving_components(c, m, tool, sweeps, workers, err);
    for (int p = 0; p < FM_CHECK_PART_COUNT; p++) fm_sweep_free(sweeps[p]);
    /* What the caller cuts next: the motion as the interpreter gave it. */
    if (st == FM_OK) {
        fm_sweep_worker *w = worker_for(c, cut->tool, FM_CHECK_PART_FLUTES, &tool->flutes);
        st = w ? add_pending(c, cut, tool, w, err) : fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    }
    close_unhit(c);
    return st;
}
