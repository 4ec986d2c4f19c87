/* setup.c: from an fm_motion and a tool part to an fm_sweep: the pose of
 * each motion kind (LinuxCNC arc semantics), the choice of method (closed
 * form, concave search, branch-and-bound) with the constants its bounds
 * need, and the bounding box of the swept volume. */
#include "sweep/sweep_internal.h"

#include <float.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

static double dot3(const double a[3], const double b[3]) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }
static double norm3(const double a[3]) { return sqrt(dot3(a, a)); }

static int unit(const double in[3], double out[3])
{
    double n = norm3(in);
    if (!(n > 1e-12) || !isfinite(n)) return 0;
    for (int i = 0; i < 3; i++) out[i] = in[i] / n;
    return 1;
}

static int finite3(const double v[3]) { return isfinite(v[0]) && isfinite(v[1]) && isfinite(v[2]); }

/* Grow [lo, hi] by the box of the part at tip c with unit axis a: the
 * bounding cylinder's box (its end discs reach r_max sqrt(1 - a_i^2)). */
static void add_tool_box(const fm_tool_part *part, const double c[3], const double a[3], double lo[3],
                         double hi[3])
{
    for (int i = 0; i < 3; i++) {
        double e0 = c[i] + part->z_lo * a[i], e1 = c[i] + part->z_hi * a[i];
        double ext = part->r_max * sqrt(fmax(0.0, 1 - a[i] * a[i]));
        lo[i] = fmin(lo[i], fmin(e0, e1) - ext);
        hi[i] = fmax(hi[i], fmax(e0, e1) + ext);
    }
}

static void compute_bounds(fm_sweep *s)
{
    for (int i = 0; i < 3; i++) {
        s->lo[i] = DBL_MAX;
        s->hi[i] = -DBL_MAX;
    }
    double c[3], a[3];
    if (s->kind == SW_STATIC || (s->kind == SW_LINE && s->axis_const)) {
        /* The box of a convex hull of two boxes moving linearly. */
        fm_sweep_pose(s, s->t0, c, a);
        add_tool_box(&s->part, c, a, s->lo, s->hi);
        if (s->kind == SW_LINE) {
            for (int i = 0; i < 3; i++) c[i] = s->c0[i] + s->d[i];
            add_tool_box(&s->part, c, s->a0, s->lo, s->hi);
        }
        return;
    }
    if (s->kind == SW_ARC) {
        /* The path's box (ends, plus the extreme points of the circle the
         * arc passes), then the tool's box about it (fixed axis). */
        double plo[3], phi[3], rmax = fmax(fabs(s->r0), fabs(s->r0 + s->drr));
        for (int k = 0; k <= 1; k++) {
            double cc[3], aa[3];
            fm_sweep_pose(s, k ? s->t1 : s->t0, cc, aa);
            for (int i = 0; i < 3; i++) {
                if (k == 0 || cc[i] < plo[i]) plo[i] = cc[i];
                if (k == 0 || cc[i] > phi[i]) phi[i] = cc[i];
            }
            if (s->t1 == s->t0) { /* zero duration: fm_sweep_pose cannot reach u = 1 */
                double th = s->th0 + s->dth, rr = s->r0 + s->drr;
                memcpy(cc, s->ctr, sizeof cc);
                cc[s->ai] += rr * cos(th);
                cc[s->aj] += rr * sin(th);
                cc[s->ak] += s->dh;
                for (int i = 0; i < 3; i++) {
                    plo[i] = fmin(plo[i], cc[i]);
                    phi[i] = fmax(phi[i], cc[i]);
                }
            }
        }
        for (int q = -8; q <= 8; q++) {
            double th = q * FM_PI / 2;
            double off = s->dth > 0 ? th - s->th0 : s->th0 - th;
            if (off < 0 || off > fabs(s->dth)) continue;
            double ci = s->ctr[s->ai] + rmax * cos(th), cj = s->ctr[s->aj] + rmax * sin(th);
            plo[s->ai] = fmin(plo[s->ai], ci);
            phi[s->ai] = fmax(phi[s->ai], ci);
            plo[s->aj] = fmin(plo[s->aj], cj);
            phi[s->aj] = fmax(phi[s->aj], cj);
        }
        double zero[3] = {0, 0, 0}, tlo[3] = {DBL_MAX, DBL_MAX, DBL_MAX}, thi[3] = {-DBL_MAX, -DBL_MAX, -DBL_MAX};
        add_tool_box(&s->part, zero, s->a0, tlo, thi);
        for (int i = 0; i < 3; i++) {
            s->lo[i] = plo[i] + tlo[i];
            s->hi[i] = phi[i] + thi[i];
        }
        return;
    }
    /* Changing axis, rotary axes or parametric path: pieces of the pose
     * box, each grown by the radius of the ball round the tip that holds
     * the part. */
    double B = sqrt(s->part.r_max * s->part.r_max +
                    fmax(s->part.z_lo * s->part.z_lo, s->part.z_hi * s->part.z_hi));
    int pieces = 64;
    for (int k = 0; k < pieces; k++) {
        double clo[3], chi[3], alo[3], ahi[3];
        double ua = (double)k / pieces, ub = (double)(k + 1) / pieces;
        if (s->kind == SW_KIN) {
            fm_kin_pose_box(&s->kin, ua, ub, clo, chi, alo, ahi);
        } else if (s->kind == SW_PARAM) {
            s->path->pose_bounds(s->path->ctx, s->t0 + ua * (s->t1 - s->t0), s->t0 + ub * (s->t1 - s->t0), clo,
                                 chi, alo, ahi);
            for (int i = 0; i < 3; i++) {
                clo[i] += s->tip_offset[i];
                chi[i] += s->tip_offset[i];
            }
        } else {
            for (int i = 0; i < 3; i++) {
                double x0 = s->c0[i] + ua * s->d[i], x1 = s->c0[i] + ub * s->d[i];
                clo[i] = fmin(x0, x1);
                chi[i] = fmax(x0, x1);
            }
        }
        for (int i = 0; i < 3; i++) {
            s->lo[i] = fmin(s->lo[i], clo[i] - B);
            s->hi[i] = fmax(s->hi[i], chi[i] + B);
        }
    }
}

fm_status fm_sweep_new(const fm_motion *m, const fm_tool_part *part, const fm_sweep_options *opt,
                       fm_sweep **out, fm_error *err)
{
    *out = NULL;
    if (!m || !part) return fm_error_set(err, FM_ERR_INTERNAL, "sweep: no motion or no tool part");
    /* Rotary joints that stand still: the same motion in the workpiece
     * frame, with every fast path of a 3-axis motion. */
    fm_motion folded;
    if (fm_kin_fold(m, &folded)) m = &folded;
    if (!(m->t1 >= m->t0) || !isfinite(m->t0) || !isfinite(m->t1))
        return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: time interval [%g, %g] is not valid",
                           m->index, m->t0, m->t1);
    if (!finite3(m->start) || !finite3(m->end) || !finite3(m->tip_offset))
        return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: a coordinate is not finite", m->index);
    fm_sweep *s = calloc(1, sizeof *s);
    if (!s) return fm_error_set(err, FM_ERR_LIMIT, "sweep: out of memory");
    s->part = *part;
    s->t0 = m->t0;
    s->t1 = m->t1;
    s->tol = opt && opt->tol > 0 ? opt->tol : FM_SWEEP_TOL;
    s->max_evals = opt && opt->max_evaluations > 0 ? opt->max_evaluations : 20000;
    int fast = !(opt && opt->no_fast_paths);
    int profile = part->kind == FM_TOOL_PART_PROFILE;
    memcpy(s->tip_offset, m->tip_offset, sizeof s->tip_offset);
    if (!unit(m->axis_start, s->a0)) {
        free(s);
        return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: the tool axis is zero or not finite",
                           m->index);
    }
    if (!unit(m->axis_end, s->a1)) memcpy(s->a1, s->a0, sizeof s->a0);
    s->axis_const = fabs(s->a1[0] - s->a0[0]) + fabs(s->a1[1] - s->a0[1]) + fabs(s->a1[2] - s->a0[2]) <= 1e-12;
    if (s->axis_const) memcpy(s->a1, s->a0, sizeof s->a0);
    for (int i = 0; i < 3; i++) s->c0[i] = m->start[i] + m->tip_offset[i];

    if (fm_motion_has_rotary(m)) {
        /* Rotary axes: the machine's chain (kinematics.c), searched. */
        if (!fm_kin_init(&s->kin, m, err)) {
            free(s);
            return err ? err->code : FM_ERR_INPUT;
        }
        s->kind = SW_KIN;
        s->axis_const = 0;
        s->lipschitz = s->kin.speed;
        s->turn_rate = s->kin.turn;
        s->pieces = (int)ceil(s->kin.turn / (FM_PI / 2));
        if (s->pieces < 2) s->pieces = 2;
        if (s->pieces > 64) s->pieces = 64;
        fm_kin_pose(&s->kin, 0, s->c0, s->a0, NULL, NULL);
        memcpy(s->a1, s->a0, sizeof s->a0);
    } else switch (m->kind) {
    case FM_MOTION_DWELL:
        s->kind = SW_STATIC;
        break;
    case FM_MOTION_RAPID:
    case FM_MOTION_LINE: {
        for (int i = 0; i < 3; i++) s->d[i] = m->end[i] - m->start[i];
        s->dd = dot3(s->d, s->d);
        if (s->dd == 0 && s->axis_const) {
            s->kind = SW_STATIC;
            break;
        }
        s->kind = SW_LINE;
        if (!s->axis_const) {
            double h[3] = {s->a0[0] + s->a1[0], s->a0[1] + s->a1[1], s->a0[2] + s->a1[2]};
            s->lmin = 0.5 * norm3(h);
            if (s->lmin < 1e-6) {
                free(s);
                return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0,
                                   "motion %ld: the tool axis turns by 180 degrees in one move", m->index);
            }
            double da[3] = {s->a1[0] - s->a0[0], s->a1[1] - s->a0[1], s->a1[2] - s->a0[2]};
            s->turn_rate = norm3(da) / s->lmin;
        }
        s->lipschitz = sqrt(s->dd);
        s->pieces = 2;
        break;
    }
    case FM_MOTION_ARC: {
        int k = m->plane_axis;
        if (k < 0 || k > 2) {
            free(s);
            return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: arc plane axis %d is not 0, 1 or 2",
                               m->index, k);
        }
        if (!s->axis_const) {
            free(s);
            return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0,
                               "motion %ld: an arc with a changing tool axis is not supported", m->index);
        }
        if (m->turns == 0 || !finite3(m->center)) {
            free(s);
            return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: arc with turns = 0 or no centre",
                               m->index);
        }
        s->kind = SW_ARC;
        s->ak = k;
        /* the arc's geometry from the one place every user reads it */
        fm_motion_arc arc;
        if (!fm_motion_arc_of(m, &arc)) {
            free(s);
            return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: arc of zero radius", m->index);
        }
        s->ai = arc.ai;
        s->aj = arc.aj;
        for (int i = 0; i < 3; i++) s->ctr[i] = arc.center[i] + m->tip_offset[i];
        s->r0 = arc.r0;
        s->drr = arc.dr;
        if (fast && arc.dr != 0 && fabs(arc.dr) <= FM_SWEEP_NEAR_CIRCLE) {
            s->r0 = arc.r0 + 0.5 * arc.dr; /* the circle meant (sweep.h) */
            s->drr = 0;
        }
        double r1 = s->r0 + s->drr;
        s->th0 = arc.th0;
        s->dth = arc.dth;
        s->dh = arc.dh;
        s->full_turn = fabs(s->dth) >= 2 * FM_PI - 1e-12;
        double rmax = fmax(s->r0, r1);
        s->speed = sqrt(rmax * s->dth * rmax * s->dth + s->dh * s->dh) + fabs(s->drr);
        s->lipschitz = s->speed;
        s->accel = rmax * s->dth * s->dth + 2 * fabs(s->drr * s->dth);
        s->pieces = (int)ceil(fabs(s->dth) / (FM_PI / 2));
        if (s->pieces < 1) s->pieces = 1;
        if (s->pieces > 64) s->pieces = 64;
        break;
    }
    case FM_MOTION_PARAM:
        if (!m->path || !m->path->pose || !m->path->pose_bounds) {
            free(s);
            return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: parametric motion without a path",
                               m->index);
        }
        s->kind = SW_PARAM;
        s->path = m->path;
        s->axis_const = 0;
        s->pieces = 8;
        {
            double c[3], a[3];
            m->path->pose(m->path->ctx, m->t0, c, a);
            for (int i = 0; i < 3; i++) s->c0[i] = c[i] + m->tip_offset[i];
            if (!unit(a, s->a0)) {
                free(s);
                return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: the path's tool axis is zero",
                                   m->index);
            }
        }
        break;
    default:
        free(s);
        return fm_error_at(err, FM_ERR_INPUT, "", m->line, 0, "motion %ld: unknown kind %d", m->index, (int)m->kind);
    }

    /* Method. */
    s->method = FM_SWEEP_SEARCH;
    if (s->kind == SW_STATIC) {
        s->method = FM_SWEEP_STATIC;
    } else if (s->kind == SW_LINE && s->axis_const && profile && fast && fabs(dot3(s->d, s->a0)) <= 1e-10) {
        s->method = FM_SWEEP_PLANAR_LINE;
    } else if (s->kind == SW_ARC && profile && fast && fabs(fabs(s->a0[s->ak]) - 1) <= 1e-15 &&
               fabs(s->dh) <= 1e-10 && fabs(s->drr) <= 1e-10) {
        s->method = FM_SWEEP_PLANAR_ARC;
    } else if (s->kind == SW_LINE && s->axis_const && profile && fast && part->ball_radius > 0) {
        s->method = FM_SWEEP_CAPSULE;
    } else if (s->kind == SW_LINE && s->axis_const && profile && fast && part->convex) {
        s->method = FM_SWEEP_CONCAVE;
    } else if (s->kind == SW_ARC && profile && fast && part->convex && s->a0[s->ai] == 0 && s->a0[s->aj] == 0 &&
               fabs(s->drr) <= 1e-10 && s->r0 > 0 &&
               fm_tool_profile_eval(part, NULL, 0, 0.5 * (part->z_lo + part->z_hi), NULL) >=
                   part->r_max * (1 - 1e-12)) {
        /* A helix (or an arc with a rise below planar_arc's 1e-10) about
         * the tool's own axis, with a part that holds the ball of radius
         * r_max about its middle (flat, bull, ball, drill flutes taller than
         * their diameter): the distance to the axis is monotone between the
         * angles nearest and farthest from the point, and the part's
         * largest value over a box of (r, z) is one evaluation (sweep.c).
         * V-bits and tapered cutters stay with the search, which that
         * bound would not speed up. */
        s->method = FM_SWEEP_HELIX;
        s->hx_c0 = cos(s->th0);
        s->hx_s0 = sin(s->th0);
        s->hx_c1 = cos(s->th0 + s->dth);
        s->hx_s1 = sin(s->th0 + s->dth);
        s->hx_zmid = 0.5 * (part->z_lo + part->z_hi);
    }
    /* Second-order bound: a convex part on a fixed axis has F'' <= |tip''|. */
    s->second_order = profile && part->convex && s->axis_const && (s->kind == SW_LINE || s->kind == SW_ARC);
    /* ... and on a rotary motion F'' <= |q''|, bounded per piece (kinematics.c). */
    if (profile && part->convex && s->kind == SW_KIN) s->second_order = 1;
    s->certified = s->second_order;
    compute_bounds(s);
    *out = s;
    return FM_OK;
}

void fm_sweep_free(fm_sweep *s) { free(s); }
