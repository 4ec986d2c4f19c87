/* bench_sweep.c: swept-volume evaluations per second, per motion kind and
 * cutter, in batch and interval form, and the ratio to evaluating the
 * static tool alone at the same points (the floor). Points lie in a 1 mm
 * band round the envelope, where lib/stock evaluates; interval boxes are
 * 0.8 mm leaves (8 voxels of 0.1 mm). Usage: bench_sweep [points]. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <time.h>

#include "sweep/sweep_cases.h"
#include "bench_clock.h"

static unsigned long long rng = 88172645463325252ULL;
static double urand(double lo, double hi)
{
    rng ^= rng << 13;
    rng ^= rng >> 7;
    rng ^= rng << 17;
    return lo + (hi - lo) * ((rng >> 11) * (1.0 / 9007199254740992.0));
}

/* Points in a band round the envelope: on the moving tool's surface at a
 * random time, pushed up to 0.5 mm in a random direction. */
static int band_points(const fm_sweep *s, const fm_motion *m, const fm_tool_part *part, int n, double *x,
                       double *y, double *z)
{
    for (int k = 0; k < n; k++) {
        double zc = part->z_lo + urand(0.02, 0.98) * (part->z_hi - part->z_lo), r = 0, rr = part->r_max + 1;
        for (int it = 0; it < 40; it++) {
            double mid = 0.5 * (r + rr);
            if (fm_tool_profile_eval(part, NULL, mid, zc, NULL) >= 0) r = mid; else rr = mid;
        }
        double c[3], a[3], e1[3], e2[3];
        fm_sweep_pose(s, m->t0 + urand(0, 1) * (m->t1 - m->t0), c, a);
        double ref[3] = {fabs(a[0]) < 0.9 ? 1 : 0, fabs(a[0]) < 0.9 ? 0 : 1, 0};
        double d = ref[0] * a[0] + ref[1] * a[1] + ref[2] * a[2];
        for (int i = 0; i < 3; i++) e1[i] = ref[i] - d * a[i];
        double l = sqrt(e1[0] * e1[0] + e1[1] * e1[1] + e1[2] * e1[2]);
        for (int i = 0; i < 3; i++) e1[i] /= l;
        e2[0] = a[1] * e1[2] - a[2] * e1[1];
        e2[1] = a[2] * e1[0] - a[0] * e1[2];
        e2[2] = a[0] * e1[1] - a[1] * e1[0];
        double ang = urand(0, 2 * FM_PI), p[3];
        for (int i = 0; i < 3; i++)
            p[i] = c[i] + zc * a[i] + r * (cos(ang) * e1[i] + sin(ang) * e2[i]) + urand(-0.5, 0.5);
        x[k] = p[0], y[k] = p[1], z[k] = p[2];
    }
    return n;
}

static void bench(const char *cutter, const char *kind, const fm_motion *m, const fm_tool_part *part, int n)
{
    fm_sweep *s;
    fm_error err;
    if (fm_sweep_new(m, part, NULL, &s, &err) != FM_OK) {
        printf("%s %s: %s\n", cutter, kind, err.message);
        return;
    }
    fm_sweep_worker *w = fm_sweep_worker_new(s);
    double *x = malloc(sizeof(double) * n * 4), *y = x + n, *z = y + n, *out = z + n;
    n = band_points(s, m, part, n, x, y, z);
    /* Batch. */
    double t0 = bench_wall_s();
    fm_sweep_eval_batch(s, w, n, x, y, z, out);
    double tb = bench_wall_s() - t0;
    /* Interval over 0.8 mm boxes centred on the same points. */
    t0 = bench_wall_s();
    double sink = 0;
    for (int i = 0; i < n; i++) {
        fm_interval box[3] = {{x[i] - 0.4, x[i] + 0.4}, {y[i] - 0.4, y[i] + 0.4}, {z[i] - 0.4, z[i] + 0.4}};
        sink += fm_sweep_interval(s, w, box).hi;
    }
    double ti = bench_wall_s() - t0;
    /* The floor: the static tool at its start pose, at the same points. */
    double c[3], a[3];
    fm_sweep_pose(s, m->t0, c, a);
    t0 = bench_wall_s();
    for (int i = 0; i < n; i++) {
        double p[3] = {x[i] - c[0], y[i] - c[1], z[i] - c[2]};
        out[i] = fm_tool_part_eval(part, NULL, p);
    }
    double tf = bench_wall_s() - t0;
    /* Part evaluations per point in the search. */
    size_t evals = 0;
    for (int i = 0; i < n && i < 2000; i++) {
        fm_sweep_value v;
        double p[3] = {x[i], y[i], z[i]};
        fm_sweep_eval_ex(s, w, p, &v);
        evals += v.evaluations;
    }
    static const char *methods[] = {"static", "planar-line", "planar-arc", "capsule", "concave", "search", "helix"};
    fflush(stdout);
    printf("%-13s %-11s %-12s %10.0f %10.0f %8.1f %7.1f\n", cutter, kind, methods[fm_sweep_method_of(s)], n / tb,
           n / ti, tb / tf, (double)evals / (n < 2000 ? n : 2000));
    (void)sink;
    free(x);
    fm_sweep_worker_free(w);
    fm_sweep_free(s);
}

int main(int argc, char **argv)
{
    int n = argc > 1 ? atoi(argv[1]) : 20000;
    printf("%-13s %-11s %-12s %10s %10s %8s %7s\n", "cutter", "motion", "method", "batch/s", "interval/s",
           "x floor", "evals");
    sc_cutter cut[9];
    int nc = sc_cutters(cut);
    for (int c = 0; c < nc; c++) {
        fm_tool t;
        fm_error err;
        if (fm_tool_build(&cut[c].spec, &t, &err) != FM_OK) continue;
        for (int k = 0; k < SC_KINDS; k++) {
            fm_motion m = sc_motion(k);
            bench(cut[c].name, sc_kind_names[k], &m, &t.flutes, n);
        }
    }
    /* The 3D_Chips case: a 10 mm ball on a short 3D move. */
    fm_tool_spec b = sc_spec(FM_TOOL_BALL);
    b.diameter = 10;
    b.flute_length = 20;
    b.length = 40;
    fm_tool t;
    if (fm_tool_build(&b, &t, NULL) == FM_OK) {
        fm_motion m = sc_line(0, 0, 0, 0.8, 0.5, -0.3);
        bench("ball-10mm", "short-3D", &m, &t.flutes, n);
        m = sc_line(0, 0, 0, 0.8, 0.5, 0);
        bench("ball-10mm", "short-XY", &m, &t.flutes, n);
    }
    /* Issue 17: a 5-axis move on an AC trunnion (A about X, C about Z,
     * through the origin) against the 3-axis move of the same tip path
     * (the 13 mm XY line): A 0 -> 20, C 0 -> 45 degrees, with TCP (the tip
     * on the line) and without (the joints linear). */
    fm_machine trt;
    memset(&trt, 0, sizeof trt);
    trt.rotary_count = 2;
    trt.rotary[0].letter = 0;
    trt.rotary[0].around[0] = 1;
    trt.rotary[1].letter = 2;
    trt.rotary[1].around[2] = 1;
    static const fm_tool_shape shapes[2] = {FM_TOOL_FLAT, FM_TOOL_BALL};
    static const char *const names[2] = {"flat-6mm", "ball-6mm"};
    for (int c = 0; c < 2; c++) {
        fm_tool_spec spec = sc_spec(shapes[c]);
        fm_tool tool;
        if (fm_tool_build(&spec, &tool, NULL) != FM_OK) continue;
        fm_motion m = sc_line(0, 0, 0, 12, 5, 0);
        bench(names[c], "3-axis", &m, &tool.flutes, n);
        for (int tcp = 1; tcp >= 0; tcp--) {
            fm_motion r = m;
            r.machine = &trt;
            r.rotary_end[0] = 20;
            r.rotary_end[2] = 45;
            r.tcp = tcp;
            bench(names[c], tcp ? "5-axis-tcp" : "5-axis", &r, &tool.flutes, n);
        }
    }
    return 0;
}
