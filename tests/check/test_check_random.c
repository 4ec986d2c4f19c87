/* test_check_random.c: the check against brute force on 200 random motions
 * (lines, rapids and arcs, three tools with shanks and holders, some with a
 * shank wider than the cutter) in and around a small block, with a fixed
 * seed. The reference samples every part densely against the exact stock,
 * min(box, -S_j) over every earlier flute sweep S_j (lib/sweep, nothing of
 * lib/check), with the rule of issue 14 for the shank and holder: a point
 * counts at the first time t the part holds it, at depth min(stock before
 * the motion, distance to the flutes' sweep over [t0, t]) (the prefix
 * motions are built here, from the motion's own geometry). Rapids' flutes
 * count against the stock before the motion.
 *
 * Asserted, as issue 14 states it: every contact the sampling finds deeper
 * than the tolerance plus one voxel is an error of the check, and every
 * error of the check is a place where the sampling finds the part in the
 * stock. Also: no depth the check reports exceeds the sampled one by more
 * than a voxel plus the sampling's own spacing, and none falls short of it
 * by more than docs/check.md allows: the sampled depth is at most the true
 * depth D, and the check reports at least D - h sqrt(3) (the nearest voxel
 * centre outside the part), a voxel lower still where the searches beyond
 * the band ran out (a check that reported every contact 0.1 mm deep passed
 * the other assertions). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "check/check.h"
#include "job.h"
#include "sweep/sweep.h"
#include "test.h"
#include "toolpaths/gcode/gcode.h"

#define MOTIONS 200
#define TOOLS 3
#define VOXEL 0.5
#define TOL 0.25
/* spacing of the reference's points (mm) and time scan steps per motion */
#define STEP 0.2
#define SCAN 200

static const double stock_lo[3] = {0, 0, -12}, stock_hi[3] = {30, 30, 0};

static fm_tool_spec specs[TOOLS];
static fm_tool tools[TOOLS];

static void make_tools(void)
{
    /* flat 4 mm: 6 mm of flute, shank as wide, 16 mm out, holder 14 x 10 */
    /* ball 6 mm: 8 mm of flute, a 5 mm shank, 18 mm out, holder 18 x 10 */
    /* flat 3 mm: 4 mm of flute, a 5 mm shank (wider than the cutter), 9 mm out, holder 12 x 10 */
    const int shape[TOOLS] = {FM_TOOL_FLAT, FM_TOOL_BALL, FM_TOOL_FLAT};
    const double d[TOOLS] = {4, 6, 3}, flute[TOOLS] = {6, 8, 4}, shank[TOOLS] = {4, 5, 5},
                 length[TOOLS] = {16, 18, 9}, holder_d[TOOLS] = {14, 18, 12};
    for (int i = 0; i < TOOLS; i++) {
        memset(&specs[i], 0, sizeof specs[i]);
        specs[i].number = i + 1;
        specs[i].shape = shape[i];
        specs[i].diameter = d[i];
        specs[i].flute_length = flute[i];
        specs[i].shank_diameter = shank[i];
        specs[i].length = length[i];
        specs[i].holder_count = 1;
        specs[i].holder[0] = (fm_holder_segment){holder_d[i], holder_d[i], 10};
        specs[i].center_cutting = 1;
        fm_error err;
        CHECK(fm_tool_build(&specs[i], &tools[i], &err) == FM_OK);
    }
}

/* ---------------------------------------------------------- program -- */

static char program[64 * 1024];

static void make_program(void)
{
    size_t n = 0;
    n += (size_t)snprintf(program + n, sizeof program - n, "G21 G90 G17\nS1000 M3\nT1 M6\nG0 X-10 Y-10 Z10\n");
    double x = -10, y = -10;
    for (int i = 0; i < MOTIONS; i++) {
        double r = test_rand01();
        if (r < 0.06) {
            /* a tool change, high above the stock */
            int t = 1 + (int)(test_uniform(0, TOOLS - 1e-9));
            n += (size_t)snprintf(program + n, sizeof program - n, "T%d M6\nG0 Z10\n", t);
            i++;
            continue;
        }
        double nx = test_uniform(-6, 36), ny = test_uniform(-6, 36), nz = test_uniform(-13, 5);
        if (r < 0.30) {
            n += (size_t)snprintf(program + n, sizeof program - n, "G0 X%.4f Y%.4f Z%.4f\n", nx, ny, nz);
        } else if (r < 0.45) {
            /* an arc from here: a centre 3..9 mm away, up to 300 degrees */
            double rad = test_uniform(3, 9), a0 = test_uniform(0, 2 * FM_PI), sweep = test_uniform(0.3, 5.2);
            int ccw = test_rand01() < 0.5;
            double cx = x - rad * cos(a0), cy = y - rad * sin(a0);
            double a1 = ccw ? a0 + sweep : a0 - sweep;
            nx = cx + rad * cos(a1);
            ny = cy + rad * sin(a1);
            n += (size_t)snprintf(program + n, sizeof program - n, "G%d X%.6f Y%.6f Z%.4f I%.6f J%.6f F300\n",
                                  ccw ? 3 : 2, nx, ny, nz, cx - x, cy - y);
        } else {
            /* short feeds stay near the last point: the tool works in the stock */
            if (test_rand01() < 0.5) {
                nx = x + test_uniform(-8, 8);
                ny = y + test_uniform(-8, 8);
            }
            n += (size_t)snprintf(program + n, sizeof program - n, "G1 X%.4f Y%.4f Z%.4f F300\n", nx, ny, nz);
        }
        x = nx;
        y = ny;
    }
    snprintf(program + n, sizeof program - n, "G0 Z20\nM2\n");
}

/* ---------------------------------------------------------- motions -- */

typedef struct ref_motion {
    fm_motion m;
    int tool; /* index, -1: none */
    fm_sweep *flutes;
    double lo[3], hi[3];
} ref_motion;

static ref_motion motions[4 * MOTIONS];
static int motion_count;
static fm_sweep_worker *flute_workers[TOOLS], *part_workers[TOOLS][3];

static int collect(void *user, const fm_motion *m)
{
    (void)user;
    if (motion_count == (int)(sizeof motions / sizeof motions[0])) return 1;
    ref_motion *r = &motions[motion_count++];
    memset(r, 0, sizeof *r);
    r->m = *m;
    r->tool = m->tool >= 1 && m->tool <= TOOLS ? m->tool - 1 : -1;
    if (r->tool >= 0 && m->kind != FM_MOTION_DWELL) {
        fm_error err;
        if (fm_sweep_new(m, &tools[r->tool].flutes, NULL, &r->flutes, &err) != FM_OK) return 1;
        fm_sweep_bounds(r->flutes, r->lo, r->hi);
    }
    return 0;
}

/* The exact stock before motion k at p (positive inside): the box, less
 * every flute sweep before k. */
static double stock_before(int k, const double p[3], double cap)
{
    double g = cap;
    for (int a = 0; a < 3; a++) g = fmin(g, fmin(p[a] - stock_lo[a], stock_hi[a] - p[a]));
    for (int j = 0; j < k && g > 0; j++) {
        const ref_motion *r = &motions[j];
        if (!r->flutes) continue;
        double d2 = 0;
        for (int a = 0; a < 3; a++) {
            double e = fmax(r->lo[a] - p[a], p[a] - r->hi[a]);
            if (e > 0) d2 += e * e;
        }
        if (d2 > 0 && sqrt(d2) >= g) continue;
        g = fmin(g, -fm_sweep_eval(r->flutes, flute_workers[r->tool], p));
    }
    return g;
}

/* The motion up to parameter u: lines by their ends, arcs by their angle
 * (these arcs turn less than a full circle, about a centre in XY). */
static void prefix(const fm_motion *m, double u, fm_motion *out)
{
    *out = *m;
    out->t1 = m->t0 + u * (m->t1 - m->t0);
    if (m->kind == FM_MOTION_ARC) {
        double sx = m->start[0] - m->center[0], sy = m->start[1] - m->center[1];
        double ex = m->end[0] - m->center[0], ey = m->end[1] - m->center[1];
        double a0 = atan2(sy, sx), a1 = atan2(ey, ex);
        double sweep = m->turns > 0 ? a1 - a0 : a0 - a1;
        while (sweep <= 0) sweep += 2 * FM_PI;
        double a = m->turns > 0 ? a0 + u * sweep : a0 - u * sweep;
        double r0 = hypot(sx, sy), r1 = hypot(ex, ey), rr = r0 + u * (r1 - r0);
        if (u * sweep < 1e-9) {
            out->kind = FM_MOTION_RAPID;
            memcpy(out->end, m->start, sizeof out->end);
            return;
        }
        out->end[0] = m->center[0] + rr * cos(a);
        out->end[1] = m->center[1] + rr * sin(a);
        out->end[2] = m->start[2] + u * (m->end[2] - m->start[2]);
        return;
    }
    for (int a = 0; a < 3; a++) out->end[a] = m->start[a] + u * (m->end[a] - m->start[a]);
}

/* The deepest point of part p (0 flutes, 1 shank, 2 holder) of motion k in
 * the stock, by the rule; 0 when none is found. ordered: the flutes lead. */
static double reference_depth(int k, int part, int ordered)
{
    const ref_motion *r = &motions[k];
    const fm_tool *t = &tools[r->tool];
    const fm_tool_part *tp = part == 0 ? &t->flutes : part == 1 ? &t->shank : &t->holder;
    if ((part == 1 && !t->has_shank) || (part == 2 && !t->has_holder)) return 0;
    fm_sweep *s = NULL;
    fm_error err;
    if (fm_sweep_new(&r->m, tp, NULL, &s, &err) != FM_OK) return 0;
    fm_sweep_worker *w = part_workers[r->tool][part];
    double lo[3], hi[3];
    fm_sweep_bounds(s, lo, hi);
    int n[3];
    for (int a = 0; a < 3; a++) {
        lo[a] = fmax(lo[a], stock_lo[a]);
        hi[a] = fmin(hi[a], stock_hi[a]);
        if (lo[a] > hi[a]) {
            fm_sweep_free(s);
            return 0;
        }
        n[a] = (int)floor((hi[a] - lo[a]) / STEP) + 1;
    }
    double best = 0;
    for (int i = 0; i < n[0]; i++)
        for (int j = 0; j < n[1]; j++)
            for (int l = 0; l < n[2]; l++) {
                double p[3] = {lo[0] + i * STEP, lo[1] + j * STEP, lo[2] + l * STEP};
                if (fm_sweep_eval(s, w, p) < 0) continue;
                double g = stock_before(k, p, INFINITY);
                if (g <= best) continue;
                if (!ordered) {
                    best = g;
                    continue;
                }
                /* the first time the part holds p: scanned, then bisected */
                double u_prev = 0, u_in = -1;
                for (int q = 0; q <= SCAN; q++) {
                    double u = (double)q / SCAN;
                    if (fm_sweep_tool_at_u(s, w, p, u) >= 0) {
                        u_in = u;
                        break;
                    }
                    u_prev = u;
                }
                if (u_in < 0) continue; /* between scanned times: a sliver */
                if (u_in > 0)
                    for (int b = 0; b < 40; b++) {
                        double mid = 0.5 * (u_prev + u_in);
                        if (fm_sweep_tool_at_u(s, w, p, mid) >= 0) u_in = mid;
                        else u_prev = mid;
                    }
                fm_motion pm;
                prefix(&r->m, u_in, &pm);
                fm_sweep *fs = NULL;
                if (fm_sweep_new(&pm, &t->flutes, NULL, &fs, &err) != FM_OK) continue;
                double d = fmin(g, -fm_sweep_eval(fs, flute_workers[r->tool], p));
                fm_sweep_free(fs);
                if (d > best) best = d;
            }
    fm_sweep_free(s);
    return best;
}

/* ------------------------------------------------------------ check -- */

static fm_check *run_check(void)
{
    fm_tool_table table = {TOOLS, specs};
    fm_job_check check;
    fm_job_check_default(&check);
    check.options.tolerance_mm = TOL;
    for (int p = 0; p < FM_CHECK_PART_COUNT; p++) check.options.clearance_mm[p] = 0;
    check.options.machine.start[2] = 20;
    check.voxel_mm = VOXEL;
    char stock[128];
    snprintf(stock, sizeof stock, "box:%g,%g,%g,%g,%g,%g", stock_lo[0], stock_lo[1], stock_lo[2],
             stock_hi[0], stock_hi[1], stock_hi[2]);
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "random.ngc";
    spec.stock_spec = stock;
    spec.tools = &table;
    spec.stock.voxel_mm = VOXEL;
    spec.stock.band_voxels = fm_check_band_voxels(&check.options, VOXEL);
    spec.check = &check;
    fm_job_result res;
    fm_error err;
    fm_status st = fm_job_run(&spec, NULL, &res, &err);
    if (st != FM_OK) fprintf(stderr, "job: %s\n", err.message);
    CHECK(st == FM_OK);
    if (st != FM_OK) return NULL;
    fm_stock_free(res.stock);
    return res.check;
}

/* The check's finding of kind covering line, if any. */
static const fm_check_finding *finding_at(const fm_check *c, fm_check_kind kind, int line)
{
    for (size_t i = 0; i < fm_check_count(c); i++) {
        const fm_check_finding *f = fm_check_get(c, i);
        if (f->kind == kind && f->line <= line && line <= f->last_line) return f;
    }
    return NULL;
}

int main(void)
{
    make_tools();
    make_program();
    fm_gcode_options gopt;
    fm_gcode_options_default(&gopt);
    fm_tool_table table = {TOOLS, specs};
    gopt.tools = &table;
    fm_error err;
    CHECK(fm_gcode_run_string(program, strlen(program), "random.ngc", &gopt, collect, NULL, NULL,
                              &err) == FM_OK);
    /* a worker for each tool part, made from a still sweep of that part
     * kept as long as the worker */
    static fm_sweep *keep[TOOLS][3];
    for (int i = 0; i < TOOLS; i++) {
        fm_motion still;
        memset(&still, 0, sizeof still);
        still.axis_start[2] = still.axis_end[2] = 1;
        const fm_tool_part *parts[3] = {&tools[i].flutes, &tools[i].shank, &tools[i].holder};
        for (int p = 0; p < 3; p++) {
            CHECK(fm_sweep_new(&still, parts[p], NULL, &keep[i][p], &err) == FM_OK);
            part_workers[i][p] = fm_sweep_worker_new(keep[i][p]);
        }
        flute_workers[i] = fm_sweep_worker_new(keep[i][0]);
    }
    fm_check *c = run_check();
    if (!c) return 1;
    fprintf(stderr, "%d motions, %zu findings (%zu errors)\n", motion_count, fm_check_count(c),
            fm_check_count_severity(c, FM_CHECK_ERROR));

    /* per motion and part: the sampled depth, and the finding covering it */
    static double depth[4 * MOTIONS][3];
    long contacts = 0, missed = 0, checked = 0, understated = 0;
    double worst_miss = 0, worst_short = 0;
    for (int k = 1; k < motion_count; k++) {
        const ref_motion *r = &motions[k];
        if (r->tool < 0 || r->m.kind == FM_MOTION_DWELL) continue;
        for (int part = 0; part < 3; part++) {
            fm_check_kind kind = part == 0   ? FM_CHECK_RAPID_INTO_STOCK
                                 : part == 1 ? FM_CHECK_SHANK_CONTACT
                                             : FM_CHECK_HOLDER_CONTACT;
            if (part == 0 && r->m.kind != FM_MOTION_RAPID) continue;
            double d = reference_depth(k, part, part != 0);
            depth[k][part] = d;
            checked++;
            if (d > 0) contacts++;
            const fm_check_finding *f = finding_at(c, kind, r->m.line);
            if (d > 0)
                fprintf(stderr, "  line %3d %-16s sampled %.3f  check %s %.3f\n", r->m.line,
                        fm_check_kind_name(kind), d,
                        f ? fm_check_severity_name(f->severity) : "-", f ? f->penetration_mm : 0.0);
            if (d > TOL + VOXEL && !(f && f->severity == FM_CHECK_ERROR)) {
                missed++;
                if (d > worst_miss) worst_miss = d;
                fprintf(stderr, "missed: line %d %s, sampled depth %.3f\n", r->m.line,
                        fm_check_kind_name(kind), d);
            }
            if (d > 0 && f && f->severity == FM_CHECK_ERROR) {
                worst_short = fmax(worst_short, d - f->penetration_mm);
                if (f->penetration_mm < d - VOXEL * (sqrt(3.0) + 1)) {
                    understated++;
                    fprintf(stderr, "understated: line %d %s, %.3f mm, sampled %.3f\n", r->m.line,
                            fm_check_kind_name(kind), f->penetration_mm, d);
                }
            }
        }
    }
    fprintf(stderr, "%ld relations sampled, %ld with a contact; %ld missed beyond %.2f mm\n",
            checked, contacts, missed, TOL + VOXEL);
    fprintf(stderr, "%ld errors shallower than sampled by more than h (sqrt 3 + 1) (largest shortfall %.3f "
            "mm)\n", understated, worst_short);
    CHECK(missed == 0);
    CHECK(understated == 0);

    /* every error of the check is a place where the sampling finds the part
     * in the stock, and its depth is not overstated by more than a voxel
     * and the sampling's spacing */
    long errors = 0, unfounded = 0, overstated = 0;
    for (size_t i = 0; i < fm_check_count(c); i++) {
        const fm_check_finding *f = fm_check_get(c, i);
        int part = f->kind == FM_CHECK_RAPID_INTO_STOCK ? 0
                   : f->kind == FM_CHECK_SHANK_CONTACT  ? 1
                   : f->kind == FM_CHECK_HOLDER_CONTACT ? 2
                                                        : -1;
        if (part < 0 || f->severity != FM_CHECK_ERROR) continue;
        errors++;
        double d = 0;
        for (int k = 1; k < motion_count; k++)
            if (motions[k].m.line >= f->line && motions[k].m.line <= f->last_line)
                d = fmax(d, depth[k][part]);
        if (!(d > 0)) {
            unfounded++;
            fprintf(stderr, "unfounded: %s lines %d-%d, %.3f mm, sampled nothing\n",
                    fm_check_kind_name(f->kind), f->line, f->last_line, f->penetration_mm);
        }
        if (f->penetration_mm > d + VOXEL + STEP * sqrt(3.0)) {
            overstated++;
            fprintf(stderr, "overstated: %s lines %d-%d, %.3f mm, sampled %.3f\n",
                    fm_check_kind_name(f->kind), f->line, f->last_line, f->penetration_mm, d);
        }
    }
    fprintf(stderr, "%ld errors of the check: %ld without a sampled contact, %ld overstated\n",
            errors, unfounded, overstated);
    CHECK(errors > 0);
    CHECK(unfounded == 0);
    CHECK(overstated == 0);
    /* the program is meant to hit: enough contacts to mean something */
    CHECK(contacts >= 20);

    fm_check_free(c);
    for (int k = 0; k < motion_count; k++) fm_sweep_free(motions[k].flutes);
    for (int i = 0; i < TOOLS; i++) {
        fm_sweep_worker_free(flute_workers[i]);
        for (int p = 0; p < 3; p++) {
            fm_sweep_worker_free(part_workers[i][p]);
            fm_sweep_free(keep[i][p]);
        }
    }
    fprintf(stderr, "%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures != 0;
}
