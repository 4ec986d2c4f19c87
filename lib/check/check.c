/* check.c: the collision and safety relations of check.h. For each motion
 * and each tool part, the part's swept volume S (lib/sweep) is tested
 * against the stock and the fixtures by maximizing the R-conjunction
 * min(S + clearance, F) with a Lipschitz branch-and-bound over boxes, where
 * F is an upper bound of the target's signed distance (target.c). Findings
 * of consecutive motions with the same kind and part are grouped. */
#include "check/check.h"
#include "check/check_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "sweep/sweep.h"

#define CHECK_PI 3.14159265358979323846
/* A first contact is looked for at poses this far apart at most (mm), then
 * refined by bisection. */
#define CHECK_SCAN_STEP_MM 0.25
#define CHECK_SCAN_MAX 400
#define CHECK_BISECT 12
/* History entries looked at per relation (newest first). */
#define CHECK_HISTORY_SCAN 4096

void fm_check_options_default(fm_check_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->tolerance_mm = 0.01;
    opt->clearance_mm[FM_CHECK_PART_FLUTES] = 0.0;
    opt->clearance_mm[FM_CHECK_PART_SHANK] = 0.0;
    opt->clearance_mm[FM_CHECK_PART_HOLDER] = 1.0;
    opt->max_ramp_deg = 3.0;
    opt->history_terms = 64;
}

const char *fm_check_kind_name(fm_check_kind kind)
{
    static const char *const names[FM_CHECK_KIND_COUNT] = {
        "rapid_into_stock",   "shank_contact",   "holder_contact", "fixture_contact",
        "non_center_plunge",  "spindle_off_cut", "travel_limit",   "start_in_stock"};
    return (unsigned)kind < FM_CHECK_KIND_COUNT ? names[kind] : "unknown";
}

const char *fm_check_severity_name(fm_check_severity severity)
{
    return severity == FM_CHECK_ERROR ? "error" : "warning";
}

const char *fm_check_part_name(fm_check_part part)
{
    static const char *const names[FM_CHECK_PART_COUNT] = {"flutes", "shank", "holder"};
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
    if (o.history_terms == 0) o.history_terms = 64;
    fm_check *c = calloc(1, sizeof *c);
    if (!c) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        return NULL;
    }
    c->opt = o;
    for (int k = 0; k < FM_CHECK_KIND_COUNT; k++)
        for (int p = 0; p < FM_CHECK_PART_COUNT; p++) c->open[k][p] = -1;
    return c;
}

void fm_check_free(fm_check *c)
{
    if (!c) return;
    for (size_t i = 0; i < c->history_count; i++) fm_sweep_free(c->history[i].sweep);
    free(c->history);
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
    free(c->pick);
    free(c->stack);
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

static fm_status add_history(fm_check *c, const fm_motion *m, fm_sweep *s, fm_sweep_worker *w,
                             fm_error *err)
{
    if (c->history_count == c->history_cap) {
        size_t cap = c->history_cap ? 2 * c->history_cap : 256;
        check_history *h = realloc(c->history, cap * sizeof *h);
        if (!h) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        c->history = h;
        c->history_cap = cap;
    }
    check_history *h = &c->history[c->history_count++];
    h->sweep = s;
    h->worker = w;
    h->straight = is_straight(m);
    for (int a = 0; a < 3; a++) {
        h->tip0[a] = m->start[a] + m->tip_offset[a];
        h->tip1[a] = m->end[a] + m->tip_offset[a];
        h->axis[a] = m->axis_start[a];
    }
    fm_sweep_bounds(s, h->lo, h->hi);
    return FM_OK;
}

/* The newest cutting motions whose swept volume reaches the region: each
 * gives a term -S_i >= the stock's distance (target.c). */
static size_t pick_history(fm_check *c, const double lo[3], const double hi[3])
{
    size_t want = c->opt.history_terms, n = 0;
    if (c->pick_cap < want) {
        size_t *p = realloc(c->pick, want * sizeof *p);
        if (!p) return 0; /* fewer terms only loosen the bound */
        c->pick = p;
        c->pick_cap = want;
    }
    size_t scanned = 0;
    for (size_t i = c->history_count; i-- > 0 && n < want && scanned < CHECK_HISTORY_SCAN;
         scanned++) {
        const check_history *h = &c->history[i];
        int meets = 1;
        for (int a = 0; a < 3; a++)
            if (h->hi[a] < lo[a] || h->lo[a] > hi[a]) meets = 0;
        if (meets) c->pick[n++] = i;
    }
    return n;
}

/* Record a hit of (kind, part[, fixture]) by this motion: open a finding or
 * extend the open one. */
static fm_status record(fm_check *c, fm_check_kind kind, fm_check_part part, int fixture,
                        const fm_check_finding *hit, fm_error *err)
{
    int *open = kind == FM_CHECK_FIXTURE_CONTACT ? &c->open_fixture[fixture * FM_CHECK_PART_COUNT + part]
                                                 : &c->open[kind][part];
    if (*open >= 0) {
        fm_check_finding *f = &c->findings[*open];
        if (hit->penetration_mm > f->penetration_mm) f->penetration_mm = hit->penetration_mm;
        if (hit->severity > f->severity) f->severity = hit->severity;
        f->last_line = hit->line;
        f->motions++;
        c->hit_now[*open] = 1;
        return FM_OK;
    }
    if (c->finding_count == c->finding_cap) {
        size_t cap = c->finding_cap ? 2 * c->finding_cap : 16;
        fm_check_finding *f = realloc(c->findings, cap * sizeof *f);
        unsigned char *h = realloc(c->hit_now, cap);
        if (f) c->findings = f;
        if (h) c->hit_now = h;
        if (!f || !h) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        c->finding_cap = cap;
    }
    fm_check_finding *f = &c->findings[c->finding_count];
    *f = *hit;
    f->kind = kind;
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

/* ---------------------------------------------------------- geometry -- */

static double motion_length(const fm_motion *m)
{
    double d2 = 0;
    for (int a = 0; a < 3; a++) d2 += (m->end[a] - m->start[a]) * (m->end[a] - m->start[a]);
    double chord = sqrt(d2);
    if (m->kind == FM_MOTION_ARC) {
        double r2 = 0;
        for (int a = 0; a < 3; a++)
            if (a != m->plane_axis) r2 += (m->start[a] - m->center[a]) * (m->start[a] - m->center[a]);
        int turns = m->turns < 0 ? -m->turns : m->turns;
        return chord + 2 * CHECK_PI * sqrt(r2) * (turns > 0 ? turns : 1);
    }
    return chord;
}

/* Swept angle of an arc in radians (positive), as LinuxCNC's ARC_FEED. */
static double arc_angle(const fm_motion *m, double *radius, double *a0, int *ccw)
{
    int p = m->plane_axis, u = (p + 1) % 3, v = (p + 2) % 3;
    double su = m->start[u] - m->center[u], sv = m->start[v] - m->center[v];
    double eu = m->end[u] - m->center[u], ev = m->end[v] - m->center[v];
    double s = atan2(sv, su), e = atan2(ev, eu);
    *radius = sqrt(su * su + sv * sv);
    *a0 = s;
    *ccw = m->turns >= 0;
    int turns = m->turns < 0 ? -m->turns : m->turns;
    double sweep = *ccw ? e - s : s - e;
    while (sweep <= 1e-12) sweep += 2 * CHECK_PI;
    if (turns > 1) sweep += 2 * CHECK_PI * (turns - 1);
    return sweep;
}

/* Descent angle of a feed motion along the tool axis, degrees (0: level
 * or climbing; 90: a straight plunge). */
static double descent_deg(const fm_motion *m)
{
    const double *ax = m->axis_start;
    double d[3], along = 0;
    for (int a = 0; a < 3; a++) {
        d[a] = m->end[a] - m->start[a];
        along += d[a] * ax[a];
    }
    double down = -along;
    if (down <= 1e-12) return 0;
    double lateral;
    if (m->kind == FM_MOTION_ARC) {
        double r, a0;
        int ccw;
        double ang = arc_angle(m, &r, &a0, &ccw);
        /* the helix descends along its plane axis while it turns */
        lateral = r * ang;
    } else {
        double l2 = 0;
        for (int a = 0; a < 3; a++) {
            double q = d[a] - along * ax[a];
            l2 += q * q;
        }
        lateral = sqrt(l2);
    }
    return atan2(down, lateral) * 180.0 / CHECK_PI;
}

/* Bounds of the programmed point over a motion (machine coordinates). */
static void motion_point_bounds(const fm_motion *m, double lo[3], double hi[3])
{
    for (int a = 0; a < 3; a++) {
        lo[a] = fmin(m->start[a], m->end[a]);
        hi[a] = fmax(m->start[a], m->end[a]);
    }
    if (m->kind == FM_MOTION_ARC) {
        double r, a0;
        int ccw;
        double ang = arc_angle(m, &r, &a0, &ccw);
        int p = m->plane_axis, u = (p + 1) % 3, v = (p + 2) % 3;
        /* the circle's extreme points that the arc passes */
        for (int k = -8; k <= 8 + 4 * (int)(ang / (2 * CHECK_PI)); k++) {
            double q = k * 0.5 * CHECK_PI;
            double rel = ccw ? q - a0 : a0 - q;
            if (rel < 0 || rel > ang) continue;
            double pu = m->center[u] + r * cos(q), pv = m->center[v] + r * sin(q);
            lo[u] = fmin(lo[u], pu);
            hi[u] = fmax(hi[u], pu);
            lo[v] = fmin(lo[v], pv);
            hi[v] = fmax(hi[v], pv);
        }
    } else if (m->kind == FM_MOTION_PARAM && m->path && m->path->pose_bounds) {
        double plo[3], phi[3], alo[3], ahi[3];
        m->path->pose_bounds(m->path->ctx, m->t0, m->t1, plo, phi, alo, ahi);
        /* the path gives the tip; the programmed point is the tip minus the offset */
        for (int a = 0; a < 3; a++) {
            lo[a] = fmin(lo[a], plo[a] - m->tip_offset[a]);
            hi[a] = fmax(hi[a], phi[a] - m->tip_offset[a]);
        }
    }
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
    out->line = like ? like->line : 0;
    out->block = like ? like->block : -1;
    out->tool = like ? like->tool : 0;
}

/* -------------------------------------------------------- relations -- */

static const fm_tool_part *tool_part(const fm_tool *t, fm_check_part p)
{
    switch (p) {
    case FM_CHECK_PART_FLUTES: return &t->flutes;
    case FM_CHECK_PART_SHANK: return t->has_shank ? &t->shank : NULL;
    case FM_CHECK_PART_HOLDER: return t->has_holder ? &t->holder : NULL;
    default: return NULL;
    }
}

/* Set up the target for a relation with a sweep: the stock (grid, initial
 * box and history) or fixture i. 0 when the sweep cannot reach it. */
static int make_target(fm_check *c, const fm_stock *stock, int fixture, const double slo[3],
                       const double shi[3], double clear, check_target *tg)
{
    memset(tg, 0, sizeof *tg);
    for (int a = 0; a < 3; a++) {
        tg->lo[a] = slo[a] - clear;
        tg->hi[a] = shi[a] + clear;
    }
    if (fixture >= 0) {
        check_fixture *fx = &c->fixtures[fixture];
        if (fx->grid && !check_grid_init(&tg->grid, fx->grid)) return 0;
        tg->fixture = fx;
        tg->has_grid = fx->grid != NULL;
        for (int a = 0; a < 3; a++) {
            tg->lo[a] = fmax(tg->lo[a], fx->lo[a]);
            tg->hi[a] = fmin(tg->hi[a], fx->hi[a]);
            if (tg->lo[a] > tg->hi[a]) return 0;
        }
        return 1;
    }
    if (!check_grid_init(&tg->grid, stock)) return 0; /* an empty stock meets nothing */
    tg->has_grid = 1;
    for (int a = 0; a < 3; a++) {
        tg->lo[a] = fmax(tg->lo[a], tg->grid.lo[a]);
        tg->hi[a] = fmin(tg->hi[a], tg->grid.hi[a]);
        if (c->have_box) {
            /* the stock's field is at most the initial box's: none of it lies outside */
            tg->lo[a] = fmax(tg->lo[a], c->box_lo[a]);
            tg->hi[a] = fmin(tg->hi[a], c->box_hi[a]);
        }
        if (tg->lo[a] > tg->hi[a]) return 0;
    }
    tg->have_box = c->have_box;
    memcpy(tg->box_lo, c->box_lo, sizeof tg->box_lo);
    memcpy(tg->box_hi, c->box_hi, sizeof tg->box_hi);
    tg->pick_count = pick_history(c, tg->lo, tg->hi);
    tg->pick = c->pick;
    tg->history = c->history;
    tg->check = c;
    return 1;
}

/* A straight motion of the flutes that retraces earlier straight cuts of
 * the same tool on the same line sweeps, over the retraced part, only
 * space those cuts emptied (sweep(A->C) lies in sweep(P->Q) when [A, C]
 * lies in [P, Q]), so only the rest can meet the stock: the interval
 * [*u0, *u1] of the motion's parameter left to check. 0: all retraced. */
static int untraced(const fm_check *c, const fm_motion *m, fm_sweep_worker *w, double *u0,
                    double *u1)
{
    *u0 = 0;
    *u1 = 1;
    if (!is_straight(m)) return 1;
    double a[3], d[3], dd = 0;
    for (int k = 0; k < 3; k++) {
        a[k] = m->start[k] + m->tip_offset[k];
        d[k] = m->end[k] - m->start[k];
        dd += d[k] * d[k];
    }
    if (dd < 1e-12) return 1;
    double len = sqrt(dd);
    /* covered intervals, newest first; merged while they touch [lo, hi] */
    double lo = 1, hi = 0; /* nothing covered yet */
    int any = 0;
    size_t scanned = 0;
    for (size_t i = c->history_count; i-- > 0 && scanned < 64; scanned++) {
        const check_history *h = &c->history[i];
        if (!h->straight || h->worker != w) continue;
        int same_axis = 1;
        for (int k = 0; k < 3; k++)
            if (fabs(h->axis[k] - m->axis_start[k]) > 1e-12) same_axis = 0;
        if (!same_axis) continue;
        double p0 = 0, p1 = 0, off = 0;
        for (int k = 0; k < 3; k++) {
            p0 += (h->tip0[k] - a[k]) * d[k];
            p1 += (h->tip1[k] - a[k]) * d[k];
        }
        p0 /= dd;
        p1 /= dd;
        /* both ends on the motion's line */
        for (int e = 0; e < 2; e++) {
            const double *q = e ? h->tip1 : h->tip0;
            double u = e ? p1 : p0, r2 = 0;
            for (int k = 0; k < 3; k++) {
                double x = q[k] - (a[k] + u * d[k]);
                r2 += x * x;
            }
            off = fmax(off, sqrt(r2));
        }
        if (off > 1e-9 * fmax(1.0, len)) continue;
        double ca = fmin(p0, p1), cb = fmax(p0, p1);
        if (!any) {
            if (ca > 1e-12 && cb < 1 - 1e-12) continue; /* covers neither end: no use */
            lo = ca;
            hi = cb;
            any = 1;
        } else if (ca <= hi && cb >= lo) {
            lo = fmin(lo, ca);
            hi = fmax(hi, cb);
        }
    }
    if (!any) return 1;
    if (lo <= 0 && hi >= 1) return 0;
    if (lo <= 0) *u0 = fmax(0, hi);
    else if (hi >= 1) *u1 = fmin(1, lo);
    return 1;
}

typedef struct relation_out {
    int found;
    double penetration;
    double contact[3];
    double time;
    double tip[3];
} relation_out;

/* Does the part of this motion meet the target (within clear)? If so, how
 * deep, and where and when first. */
static fm_status relate(fm_check *c, const fm_motion *m, const fm_tool *tool, fm_check_part part,
                        const fm_sweep *sweep, fm_sweep_worker *w, const fm_stock *stock,
                        int fixture, double clear, relation_out *out, fm_error *err)
{
    memset(out, 0, sizeof *out);
    c->stats.relations++;
    double slo[3], shi[3];
    fm_sweep_bounds(sweep, slo, shi);
    check_target tg;
    if (!make_target(c, stock, fixture, slo, shi, clear, &tg)) {
        c->stats.skipped++;
        return FM_OK;
    }
    const fm_tool_part *tp = tool_part(tool, part);
    check_bb bb = {.check = c,
                   .sweep = sweep,
                   .worker = w,
                   .custom = tp->kind == FM_TOOL_PART_CUSTOM,
                   .clear = clear,
                   .target = &tg,
                   .tol = c->opt.tolerance_mm};
    check_bb_result r;
    fm_status st = check_bb_detect(&bb, tg.lo, tg.hi, &r, err);
    if (st != FM_OK) return st;
    if (!r.found) return FM_OK;
    out->found = 1;

    /* How deep: the maximum of min(S, F) over the same region. */
    check_bb_result mx;
    bb.clear = 0;
    st = check_bb_maximize(&bb, tg.lo, tg.hi, &mx, err);
    if (st != FM_OK) return st;
    out->penetration = mx.value > 0 ? mx.value : 0;

    double len = motion_length(m);
    double dur = m->t1 - m->t0;
    if (!c->need_first) {
        /* extends an open finding, whose first contact is known */
        double axis[3];
        memcpy(out->contact, r.at, sizeof out->contact);
        out->time = m->t0;
        fm_sweep_pose(sweep, m->t0, out->tip, axis);
        return FM_OK;
    }
    /* First contact: scan the poses along the motion, then bisect to a
     * fraction of the tolerance. */
    bb.clear = clear;
    int n = (int)ceil(len / CHECK_SCAN_STEP_MM);
    if (n < 1) n = 1;
    if (n > CHECK_SCAN_MAX) n = CHECK_SCAN_MAX;
    double u_prev = 0, u_hit = -1;
    check_bb_result hit = {0};
    for (int k = 0; k <= n && u_hit < 0; k++) {
        double u = (double)k / n;
        check_bb_result sr;
        int found;
        st = check_static_detect(&bb, m, tp, u, &sr, &found, err);
        if (st != FM_OK) return st;
        if (found) {
            u_hit = u;
            hit = sr;
        } else {
            u_prev = u;
        }
    }
    if (u_hit > 0) {
        double lo = u_prev, hi = u_hit;
        for (int i = 0; i < CHECK_BISECT && (hi - lo) * len > 0.5 * c->opt.tolerance_mm; i++) {
            double mid = 0.5 * (lo + hi);
            check_bb_result sr;
            int found;
            st = check_static_detect(&bb, m, tp, mid, &sr, &found, err);
            if (st != FM_OK) return st;
            if (found) {
                hi = mid;
                hit = sr;
            } else {
                lo = mid;
            }
        }
        u_hit = hi;
    }
    double t;
    if (u_hit >= 0) {
        memcpy(out->contact, hit.at, sizeof out->contact);
        t = m->t0 + u_hit * dur;
    } else {
        /* Met only between the scanned poses: the point found, at the time
         * the sweep reaches it. */
        memcpy(out->contact, r.at, sizeof out->contact);
        fm_sweep_value v;
        fm_sweep_eval_ex(sweep, w, r.at, &v);
        t = v.t;
    }
    double axis[3];
    fm_sweep_pose(sweep, t, out->tip, axis);
    out->time = t;
    return FM_OK;
}

/* Whether (kind, part[, fixture]) has a finding open: then the motion only
 * extends it and its first contact need not be looked for. */
static int is_open(const fm_check *c, fm_check_kind kind, fm_check_part part, int fixture)
{
    if (kind == FM_CHECK_FIXTURE_CONTACT)
        return c->open_fixture && c->open_fixture[fixture * FM_CHECK_PART_COUNT + part] >= 0;
    return c->open[kind][part] >= 0;
}

/* The flutes against the stock, skipping what the motion retraces. */
static fm_status relate_flutes(fm_check *c, const fm_motion *m, const fm_tool *tool,
                               const fm_sweep *sweep, fm_sweep_worker *w, const fm_stock *stock,
                               double clear, relation_out *out, fm_error *err)
{
    double u0, u1;
    memset(out, 0, sizeof *out);
    if (!untraced(c, m, w, &u0, &u1)) return FM_OK;
    if (u0 <= 0 && u1 >= 1)
        return relate(c, m, tool, FM_CHECK_PART_FLUTES, sweep, w, stock, -1, clear, out, err);
    fm_motion sub = *m;
    for (int a = 0; a < 3; a++) {
        double d = m->end[a] - m->start[a];
        sub.start[a] = m->start[a] + u0 * d;
        sub.end[a] = m->start[a] + u1 * d;
    }
    sub.t0 = m->t0 + u0 * (m->t1 - m->t0);
    sub.t1 = m->t0 + u1 * (m->t1 - m->t0);
    fm_sweep *ss = NULL;
    fm_status st = fm_sweep_new(&sub, &tool->flutes, NULL, &ss, err);
    if (st != FM_OK) return st;
    st = relate(c, &sub, tool, FM_CHECK_PART_FLUTES, ss, w, stock, -1, clear, out, err);
    fm_sweep_free(ss);
    return st;
}

static fm_status report(fm_check *c, fm_check_kind kind, fm_check_part part, int fixture,
                        const fm_motion *m, const relation_out *r, fm_error *err)
{
    fm_check_finding f;
    memset(&f, 0, sizeof f);
    f.severity = r->penetration > c->opt.tolerance_mm ? FM_CHECK_ERROR : FM_CHECK_WARNING;
    f.line = m ? m->line : 0;
    f.block = m ? m->block : -1;
    f.time_s = r->time;
    memcpy(f.position, r->tip, sizeof f.position);
    f.penetration_mm = r->penetration;
    memcpy(f.contact, r->contact, sizeof f.contact);
    return record(c, kind, part, fixture, &f, err);
}

/* The tool standing at the start position, before the first motion. */
static fm_status check_start(fm_check *c, const fm_motion *first, const fm_tool *tool,
                             const fm_stock *stock, fm_error *err)
{
    const double axis[3] = {0, 0, 1};
    fm_motion sm;
    c->need_first = 1;
    static_motion(NULL, c->opt.machine.start, axis, first->t0, &sm);
    sm.tool = first->tool;
    for (int p = 0; p < FM_CHECK_PART_COUNT; p++) {
        const fm_tool_part *tp = tool_part(tool, (fm_check_part)p);
        if (!tp) continue;
        fm_sweep *s = NULL;
        fm_status st = fm_sweep_new(&sm, tp, NULL, &s, err);
        if (st != FM_OK) return st;
        fm_sweep_worker *w = worker_for(c, first->tool, (fm_check_part)p, tp);
        if (!w) {
            fm_sweep_free(s);
            return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        }
        relation_out r;
        st = relate(c, &sm, tool, (fm_check_part)p, s, w, stock, -1, 0.0, &r, err);
        if (st == FM_OK && r.found) st = report(c, FM_CHECK_START_IN_STOCK, (fm_check_part)p, -1, &sm, &r, err);
        for (size_t fx = 0; st == FM_OK && fx < c->fixture_count; fx++) {
            st = relate(c, &sm, tool, (fm_check_part)p, s, w, NULL, (int)fx, c->opt.clearance_mm[p], &r,
                        err);
            if (st == FM_OK && r.found)
                st = report(c, FM_CHECK_FIXTURE_CONTACT, (fm_check_part)p, (int)fx, &sm, &r, err);
        }
        fm_sweep_free(s);
        if (st != FM_OK) return st;
    }
    return FM_OK;
}

static fm_status check_travel(fm_check *c, const fm_motion *m, fm_error *err)
{
    const fm_check_machine *mc = &c->opt.machine;
    double lo[3], hi[3];
    motion_point_bounds(m, lo, hi);
    double worst = 0;
    int axis = -1;
    double point[3];
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
    memcpy(point, p, sizeof point);
    fm_check_finding f;
    memset(&f, 0, sizeof f);
    f.severity = FM_CHECK_ERROR;
    f.line = m->line;
    f.block = m->block;
    f.time_s = m->t0;
    for (int a = 0; a < 3; a++) {
        f.position[a] = point[a];
        f.contact[a] = point[a];
    }
    f.penetration_mm = worst;
    return record(c, FM_CHECK_TRAVEL_LIMIT, FM_CHECK_PART_FLUTES, -1, &f, err);
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
     * goes from there. */
    fm_motion first;
    if (c->stats.motions == 1 && is_straight(m)) {
        first = *m;
        for (int a = 0; a < 3; a++) first.start[a] = c->opt.machine.start[a] - m->tip_offset[a];
        m = &first;
    }
    st = check_travel(c, m, err);
    if (st != FM_OK) return st;
    if (!tool || m->kind == FM_MOTION_DWELL) {
        close_unhit(c);
        return FM_OK;
    }

    int rapid = m->kind == FM_MOTION_RAPID;
    int spindle_off = !rapid && (m->spindle_rpm <= 0 || m->spindle_dir == 0);
    int plunge = !rapid && !tool->spec.center_cutting && descent_deg(m) > c->opt.max_ramp_deg;
    fm_sweep *flutes_sweep = NULL;
    fm_sweep_worker *flutes_worker = NULL;
    for (int p = 0; p < FM_CHECK_PART_COUNT && st == FM_OK; p++) {
        const fm_tool_part *tp = tool_part(tool, (fm_check_part)p);
        if (!tp) continue;
        fm_sweep *s = NULL;
        st = fm_sweep_new(m, tp, NULL, &s, err);
        if (st != FM_OK) break;
        fm_sweep_worker *w = worker_for(c, m->tool, (fm_check_part)p, tp);
        if (!w) {
            fm_sweep_free(s);
            st = fm_error_set(err, FM_ERR_LIMIT, "out of memory");
            break;
        }
        relation_out r;
        if (p == FM_CHECK_PART_FLUTES) {
            if (rapid) {
                c->need_first = !is_open(c, FM_CHECK_RAPID_INTO_STOCK, FM_CHECK_PART_FLUTES, -1);
                st = relate_flutes(c, m, tool, s, w, stock, c->opt.clearance_mm[p], &r, err);
                if (st == FM_OK && r.found)
                    st = report(c, FM_CHECK_RAPID_INTO_STOCK, (fm_check_part)p, -1, m, &r, err);
            } else if (spindle_off || plunge) {
                /* cutting is what a feed motion's flutes do: these only
                 * matter when they meet material */
                c->need_first =
                    (spindle_off && !is_open(c, FM_CHECK_SPINDLE_OFF_CUT, FM_CHECK_PART_FLUTES, -1)) ||
                    (plunge && !is_open(c, FM_CHECK_NON_CENTER_PLUNGE, FM_CHECK_PART_FLUTES, -1));
                st = relate_flutes(c, m, tool, s, w, stock, 0.0, &r, err);
                if (st == FM_OK && r.found && spindle_off)
                    st = report(c, FM_CHECK_SPINDLE_OFF_CUT, (fm_check_part)p, -1, m, &r, err);
                if (st == FM_OK && r.found && plunge)
                    st = report(c, FM_CHECK_NON_CENTER_PLUNGE, (fm_check_part)p, -1, m, &r, err);
            }
        } else {
            c->need_first = !is_open(c,
                                     p == FM_CHECK_PART_SHANK ? FM_CHECK_SHANK_CONTACT
                                                              : FM_CHECK_HOLDER_CONTACT,
                                     (fm_check_part)p, -1);
            st = relate(c, m, tool, (fm_check_part)p, s, w, stock, -1, c->opt.clearance_mm[p], &r,
                        err);
            if (st == FM_OK && r.found)
                st = report(c,
                            p == FM_CHECK_PART_SHANK ? FM_CHECK_SHANK_CONTACT : FM_CHECK_HOLDER_CONTACT,
                            (fm_check_part)p, -1, m, &r, err);
        }
        for (size_t fx = 0; st == FM_OK && fx < c->fixture_count; fx++) {
            c->need_first = !is_open(c, FM_CHECK_FIXTURE_CONTACT, (fm_check_part)p, (int)fx);
            st = relate(c, m, tool, (fm_check_part)p, s, w, NULL, (int)fx, c->opt.clearance_mm[p], &r,
                        err);
            if (st == FM_OK && r.found)
                st = report(c, FM_CHECK_FIXTURE_CONTACT, (fm_check_part)p, (int)fx, m, &r, err);
        }
        if (p == FM_CHECK_PART_FLUTES) {
            flutes_sweep = s;
            flutes_worker = w;
        } else {
            fm_sweep_free(s);
        }
    }
    /* The runner cuts the flutes' sweep next: its exact field tightens the
     * stock's bound from now on. A parametric path does not outlive this
     * call, so such a cut is known from the grid alone. */
    if (st == FM_OK && flutes_sweep && m->kind != FM_MOTION_PARAM) {
        st = add_history(c, m, flutes_sweep, flutes_worker, err);
        if (st == FM_OK) flutes_sweep = NULL;
    }
    fm_sweep_free(flutes_sweep);
    close_unhit(c);
    return st;
}
