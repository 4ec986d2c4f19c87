/* test_kinematics.c: machine kinematics (lib/sweep/kinematics.c) against
 * the chains written out here with explicit rotation matrices: a table-
 * table AC trunnion, a head-head BC head and a head-table B/C machine,
 * with and without TCP, at 100 points of a 5-axis move; sound pose boxes
 * and speed constants on random machines and motions; joints that stand
 * still fold to 3-axis motions; poses in the frame of a link nearer the
 * base (frame_up); the sweep of rotary motions against a
 * brute-force maximum; the 4D DAG against the native pose. */
#include "test.h"
#include "sweep/kin_internal.h"
#include "sweep/sweep_cases.h"
#include "tools/dag_eval.h"

#include <stdlib.h>

/* ------------------------------------------- the chains, written out -- */

static void Rx(double th, const double v[3], double out[3])
{
    double c = cos(th), s = sin(th), y = c * v[1] - s * v[2], z = s * v[1] + c * v[2];
    out[0] = v[0], out[1] = y, out[2] = z;
}
static void Ry(double th, const double v[3], double out[3])
{
    double c = cos(th), s = sin(th), x = c * v[0] + s * v[2], z = -s * v[0] + c * v[2];
    out[0] = x, out[1] = v[1], out[2] = z;
}
static void Rz(double th, const double v[3], double out[3])
{
    double c = cos(th), s = sin(th), x = c * v[0] - s * v[1], y = s * v[0] + c * v[1];
    out[0] = x, out[1] = y, out[2] = v[2];
}
/* A point turned about the line through b along a coordinate axis. */
static void about(void (*R)(double, const double *, double *), const double b[3], double th, const double p[3],
                  double out[3])
{
    double q[3] = {p[0] - b[0], p[1] - b[1], p[2] - b[2]};
    R(th, q, q);
    for (int i = 0; i < 3; i++) out[i] = b[i] + q[i];
}

static const double TRT_A_THROUGH[3] = {0, 10, -40}, TRT_C_THROUGH[3] = {5, 10, 0};

/* AC trunnion: A (table, about X through TRT_A_THROUGH) on the base, C
 * (table, about Z through TRT_C_THROUGH) on A. x_machine = R_A R_C
 * x_workpiece, so x_workpiece = R_C(-c) R_A(-a) x_machine. */
static fm_machine trunnion(int tcp)
{
    fm_machine mc;
    memset(&mc, 0, sizeof mc);
    mc.rotary_count = 2;
    mc.rotary[0] = (fm_rotary_axis){.letter = 0, .carries = FM_ROTARY_TABLE, .around = {1, 0, 0}};
    memcpy(mc.rotary[0].through, TRT_A_THROUGH, sizeof TRT_A_THROUGH);
    mc.rotary[1] = (fm_rotary_axis){.letter = 2, .carries = FM_ROTARY_TABLE, .around = {0, 0, 1}};
    memcpy(mc.rotary[1].through, TRT_C_THROUGH, sizeof TRT_C_THROUGH);
    mc.tcp = tcp;
    return mc;
}

static void trunnion_written(double a, double c, const double tip_machine[3], double tip[3], double axis[3])
{
    double z[3] = {0, 0, 1}, q[3];
    about(Rx, TRT_A_THROUGH, -a, tip_machine, q);
    about(Rz, TRT_C_THROUGH, -c, q, tip);
    Rx(-a, z, q);
    Rz(-c, q, axis);
}

/* BC head: C (head, about Z) on the base, B (head, about Y, pivot 80 mm
 * above the gauge line) on C. Tool length 50, tip offset o. */
#define HEAD_PIVOT 80.0
#define HEAD_TOOL 50.0
static fm_machine bc_head(int tcp)
{
    fm_machine mc;
    memset(&mc, 0, sizeof mc);
    mc.rotary_count = 2;
    mc.rotary[0] = (fm_rotary_axis){.letter = 2, .carries = FM_ROTARY_HEAD, .around = {0, 0, 1}, .pivot_length = 30};
    mc.rotary[1] = (fm_rotary_axis){.letter = 1, .carries = FM_ROTARY_HEAD, .around = {0, 1, 0},
                                    .pivot_length = HEAD_PIVOT};
    mc.tcp = tcp;
    return mc;
}

/* x_machine = X + H_C(c) H_B(b) x_spindle: the tip at X = 0 is o, B turns
 * about the line through o + (0, 0, L + 80) along Y, C about the line
 * through o + (0, 0, L + 30) along Z. */
static void bc_head_written(double b, double c, const double X[3], const double o[3], double tip[3], double axis[3])
{
    double bB[3] = {o[0], o[1], o[2] + HEAD_TOOL + HEAD_PIVOT}, bC[3] = {o[0], o[1], o[2] + HEAD_TOOL + 30};
    double q[3], z[3] = {0, 0, 1};
    about(Ry, bB, b, o, q);
    about(Rz, bC, c, q, q);
    for (int i = 0; i < 3; i++) tip[i] = X[i] + q[i];
    Ry(b, z, q);
    Rz(c, q, axis);
}

/* B head (about Y, pivot 60) and C table (about Z through (3, -2, 0)). */
static fm_machine b_head_c_table(int tcp)
{
    fm_machine mc;
    memset(&mc, 0, sizeof mc);
    mc.rotary_count = 2;
    mc.rotary[0] = (fm_rotary_axis){.letter = 2, .carries = FM_ROTARY_TABLE, .around = {0, 0, 1}, .through = {3, -2, 0}};
    mc.rotary[1] = (fm_rotary_axis){.letter = 1, .carries = FM_ROTARY_HEAD, .around = {0, 1, 0}, .pivot_length = 60};
    mc.tcp = tcp;
    return mc;
}

static fm_motion rotary_line(const fm_machine *mc, const double from[3], const double to[3], const double r0[3],
                             const double r1[3], int tcp)
{
    fm_motion m = sc_line(from[0], from[1], from[2], to[0], to[1], to[2]);
    m.machine = mc;
    memcpy(m.rotary_start, r0, sizeof m.rotary_start);
    memcpy(m.rotary_end, r1, sizeof m.rotary_end);
    m.tcp = tcp;
    return m;
}

/* The tool's pose in the frame of a link nearer the base (frame_up, for
 * the check's machine components): on the AC trunnion, the cradle A
 * rides on (frame_up 1: x_cradle = R_C x_workpiece = R_A^-1 x_machine)
 * and the machine table (frame_up 2: x_machine), with and without TCP, at
 * 100 points of a move of all five axes; and a motion whose joints stand
 * still folds to the same 3-axis motion in that frame. */
static void check_frame_up(void)
{
    double from[3] = {12, -7, 20}, to[3] = {-15, 9, 4};
    double r0[3] = {-10, 0, 15}, r1[3] = {35, 0, 120};
    double worst = 0;
    for (int tcp = 0; tcp <= 1; tcp++)
        for (int up = 1; up <= 2; up++) {
            fm_machine mc = trunnion(tcp);
            mc.frame_up = up;
            CHECK(fm_machine_validate(&mc, NULL) == FM_OK);
            fm_motion m = rotary_line(&mc, from, to, r0, r1, tcp);
            m.tip_offset[2] = -0.7;
            for (int i = 0; i < 100; i++) {
                double u = i / 99.0, a = (r0[0] + u * (r1[0] - r0[0])) * FM_DEG, c = (r0[2] + u * (r1[2] - r0[2])) * FM_DEG;
                double X[3], tip_m[3], axis_m[3], z[3] = {0, 0, 1}, q[3];
                for (int k = 0; k < 3; k++) X[k] = from[k] + u * (to[k] - from[k]);
                if (tcp) {
                    /* the tip P + W o in the workpiece frame, carried to the machine */
                    double wtip[3], waxis[3], dummy[3];
                    trunnion_written(a, c, X, dummy, waxis);
                    for (int k = 0; k < 3; k++) wtip[k] = X[k] - 0.7 * waxis[k];
                    about(Rz, TRT_C_THROUGH, c, wtip, q);
                    about(Rx, TRT_A_THROUGH, a, q, tip_m);
                } else {
                    tip_m[0] = X[0], tip_m[1] = X[1], tip_m[2] = X[2] - 0.7;
                }
                memcpy(axis_m, z, sizeof z);
                double want_tip[3], want_axis[3];
                if (up == 2) {
                    memcpy(want_tip, tip_m, sizeof want_tip);
                    memcpy(want_axis, axis_m, sizeof want_axis);
                } else {
                    about(Rx, TRT_A_THROUGH, -a, tip_m, want_tip);
                    Rx(-a, axis_m, want_axis);
                }
                double tip[3], axis[3];
                fm_motion_pose_at(&m, u, tip, axis);
                for (int k = 0; k < 3; k++) {
                    CHECK_NEAR(tip[k], want_tip[k], 1e-9);
                    CHECK_NEAR(axis[k], want_axis[k], 1e-12);
                    worst = fmax(worst, fabs(tip[k] - want_tip[k]));
                }
            }
            /* joints standing still: the folded 3-axis motion has the same pose */
            fm_motion still = rotary_line(&mc, from, to, r1, r1, tcp), f;
            still.tip_offset[2] = -0.7;
            CHECK(fm_kin_fold(&still, &f));
            for (int i = 0; i <= 10; i++) {
                double u = i / 10.0, t1[3], a1[3], t2[3], a2[3];
                fm_motion_pose_at(&still, u, t1, a1);
                fm_motion_pose_at(&f, u, t2, a2);
                for (int k = 0; k < 3; k++) {
                    CHECK_NEAR(t1[k], t2[k], 1e-9);
                    CHECK_NEAR(a1[k], a2[k], 1e-12);
                }
            }
        }
    printf("poses in the cradle's and the machine's frames: off the written-out chain by at most %.3g mm\n", worst);
    fm_machine bad = trunnion(0);
    bad.frame_up = 3;
    CHECK(fm_machine_validate(&bad, NULL) != FM_OK);
}

/* ------------------------------------------- Done when: 100 points -- */

static void check_five_axis_move(void)
{
    double from[3] = {12, -7, 20}, to[3] = {-15, 9, 4};
    double r0[3] = {-10, 0, 15}, r1[3] = {35, 0, 120}; /* A, B, C in degrees */
    double worst_line = 0, worst_curve = 0;
    for (int tcp = 0; tcp <= 1; tcp++) {
        fm_machine mc = trunnion(tcp);
        fm_motion m = rotary_line(&mc, from, to, r0, r1, tcp);
        m.tip_offset[2] = tcp ? 0 : -0.7;
        fm_tool t;
        fm_tool_spec spec = sc_spec(FM_TOOL_FLAT);
        CHECK(fm_tool_build(&spec, &t, NULL) == FM_OK);
        fm_sweep *s;
        CHECK(fm_sweep_new(&m, &t.flutes, NULL, &s, NULL) == FM_OK);
        for (int i = 0; i < 100; i++) {
            double u = i / 99.0, a = (r0[0] + u * (r1[0] - r0[0])) * FM_DEG, c = (r0[2] + u * (r1[2] - r0[2])) * FM_DEG;
            double X[3], tip[3], axis[3], want_tip[3], want_axis[3];
            for (int k = 0; k < 3; k++) X[k] = from[k] + u * (to[k] - from[k]);
            if (tcp) {
                /* The tip on the straight line in the workpiece frame. */
                double dummy[3];
                trunnion_written(a, c, X, dummy, want_axis);
                memcpy(want_tip, X, sizeof X);
            } else {
                double tm[3] = {X[0], X[1], X[2] - 0.7};
                trunnion_written(a, c, tm, want_tip, want_axis);
            }
            fm_motion_pose_at(&m, u, tip, axis);
            double sw_tip[3], sw_axis[3];
            fm_sweep_pose(s, m.t0 + u * (m.t1 - m.t0), sw_tip, sw_axis);
            for (int k = 0; k < 3; k++) {
                CHECK_NEAR(tip[k], want_tip[k], 1e-9);
                CHECK_NEAR(axis[k], want_axis[k], 1e-12);
                CHECK_NEAR(sw_tip[k], want_tip[k], 1e-9);
                CHECK_NEAR(sw_axis[k], want_axis[k], 1e-12);
            }
            /* How far the non-TCP tip strays from the chord of its ends. */
            double d = 0;
            for (int k = 0; k < 3; k++) d += pow(tip[k] - want_tip[k], 2);
            if (tcp) worst_line = fmax(worst_line, sqrt(d));
            else worst_curve = fmax(worst_curve, sqrt(d));
        }
        fm_sweep_free(s);
    }
    printf("AC trunnion, 100 points: TCP tip off its line by at most %.3g mm; joint-space curve off the "
           "written-out chain by at most %.3g mm\n", worst_line, worst_curve);
    /* Without TCP the tip really curves: the midpoint is far from the chord. */
    fm_machine mc = trunnion(0);
    fm_motion m = rotary_line(&mc, from, to, r0, r1, 0);
    double p0[3], p1[3], pm[3], ax[3];
    fm_motion_pose_at(&m, 0, p0, ax);
    fm_motion_pose_at(&m, 1, p1, ax);
    fm_motion_pose_at(&m, 0.5, pm, ax);
    double dev = 0;
    for (int k = 0; k < 3; k++) dev += pow(pm[k] - 0.5 * (p0[k] + p1[k]), 2);
    CHECK(sqrt(dev) > 5);

    /* BC head and B head + C table, both ways. */
    double hr0[3] = {0, -20, 10}, hr1[3] = {0, 45, -80};
    for (int tcp = 0; tcp <= 1; tcp++) {
        fm_machine hm = bc_head(tcp);
        fm_motion hmo = rotary_line(&hm, from, to, hr0, hr1, tcp);
        double o[3] = {0.2, -0.1, -0.5};
        memcpy(hmo.tip_offset, o, sizeof o);
        hmo.tool_length = HEAD_TOOL;
        for (int i = 0; i < 100; i++) {
            double u = i / 99.0, b = (hr0[1] + u * (hr1[1] - hr0[1])) * FM_DEG, c = (hr0[2] + u * (hr1[2] - hr0[2])) * FM_DEG;
            double X[3], tip[3], axis[3], want_tip[3], want_axis[3];
            for (int k = 0; k < 3; k++) X[k] = from[k] + u * (to[k] - from[k]);
            double zero[3] = {0, 0, 0};
            if (tcp) {
                /* The tip offset turns with the tool; the tip is X plus it. */
                double q[3], z[3] = {0, 0, 1};
                Ry(b, o, q);
                Rz(c, q, q);
                for (int k = 0; k < 3; k++) want_tip[k] = X[k] + q[k];
                Ry(b, z, q);
                Rz(c, q, want_axis);
            } else {
                bc_head_written(b, c, X, o, want_tip, want_axis);
            }
            (void)zero;
            fm_motion_pose_at(&hmo, u, tip, axis);
            for (int k = 0; k < 3; k++) {
                CHECK_NEAR(tip[k], want_tip[k], 1e-9);
                CHECK_NEAR(axis[k], want_axis[k], 1e-12);
            }
        }
        fm_machine bm = b_head_c_table(tcp);
        fm_motion bmo = rotary_line(&bm, from, to, hr0, hr1, tcp);
        bmo.tool_length = HEAD_TOOL;
        for (int i = 0; i < 100; i++) {
            double u = i / 99.0, b = (hr0[1] + u * (hr1[1] - hr0[1])) * FM_DEG, c = (hr0[2] + u * (hr1[2] - hr0[2])) * FM_DEG;
            double X[3], tip[3], axis[3], want_tip[3], want_axis[3], q[3], z[3] = {0, 0, 1};
            double tc[3] = {3, -2, 0};
            for (int k = 0; k < 3; k++) X[k] = from[k] + u * (to[k] - from[k]);
            Ry(b, z, q);
            Rz(-c, q, want_axis);
            if (tcp) {
                memcpy(want_tip, X, sizeof X);
            } else {
                /* head: the tip turns about the pivot 60 + 50 above it; then
                 * the table's inverse. */
                double piv[3] = {0, 0, HEAD_TOOL + 60}, tip0[3] = {0, 0, 0}, tm[3];
                about(Ry, piv, b, tip0, tm);
                for (int k = 0; k < 3; k++) tm[k] += X[k];
                about(Rz, tc, -c, tm, want_tip);
            }
            fm_motion_pose_at(&bmo, u, tip, axis);
            for (int k = 0; k < 3; k++) {
                CHECK_NEAR(tip[k], want_tip[k], 1e-9);
                CHECK_NEAR(axis[k], want_axis[k], 1e-12);
            }
        }
    }
}

/* ------------------------------------------------- random soundness -- */

static void random_unit(double v[3])
{
    double n;
    do {
        for (int i = 0; i < 3; i++) v[i] = test_uniform(-1, 1);
        n = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    } while (n < 0.2 || n > 1);
    for (int i = 0; i < 3; i++) v[i] /= n;
}

static fm_machine random_machine(void)
{
    fm_machine mc;
    memset(&mc, 0, sizeof mc);
    mc.rotary_count = 1 + (int)(test_rand01() * 3);
    if (mc.rotary_count > 3) mc.rotary_count = 3;
    int letters[3] = {0, 1, 2};
    for (int i = 2; i > 0; i--) {
        int j = (int)(test_rand01() * (i + 1));
        if (j > i) j = i;
        int t = letters[i];
        letters[i] = letters[j];
        letters[j] = t;
    }
    for (int i = 0; i < mc.rotary_count; i++) {
        fm_rotary_axis *ax = &mc.rotary[i];
        ax->letter = letters[i];
        ax->carries = test_rand01() < 0.5 ? FM_ROTARY_TABLE : FM_ROTARY_HEAD;
        random_unit(ax->around);
        for (int k = 0; k < 3; k++) ax->through[k] = test_uniform(-60, 60);
        ax->pivot_length = test_uniform(0, 150);
    }
    mc.tcp = test_rand01() < 0.5;
    /* poses in the frame of any table link (lib/check's machine components) */
    int ntable = 0;
    for (int i = 0; i < mc.rotary_count; i++) ntable += mc.rotary[i].carries == FM_ROTARY_TABLE;
    mc.frame_up = (int)(test_rand01() * (ntable + 1));
    if (mc.frame_up > ntable) mc.frame_up = ntable;
    CHECK(fm_machine_validate(&mc, NULL) == FM_OK);
    return mc;
}

static fm_motion random_rotary_motion(const fm_machine *mc)
{
    fm_motion m;
    if (test_rand01() < 0.3) {
        double c[3] = {test_uniform(-20, 20), test_uniform(-20, 20), test_uniform(-20, 20)};
        int k = (int)(test_rand01() * 3);
        if (k > 2) k = 2;
        m = sc_arc(k, c, test_uniform(1, 30), test_uniform(-3, 3), test_uniform(-3, 3),
                   test_rand01() < 0.5 ? 1 : -2, test_uniform(-5, 5));
        if (test_rand01() < 0.3) { /* a spiral */
            int i = (k + 1) % 3;
            m.end[i] += test_uniform(-2, 2);
        }
    } else {
        m = sc_line(test_uniform(-50, 50), test_uniform(-50, 50), test_uniform(-50, 50), test_uniform(-50, 50),
                    test_uniform(-50, 50), test_uniform(-50, 50));
    }
    m.machine = mc;
    m.tcp = mc->tcp;
    m.tool_length = test_uniform(0, 100);
    for (int k = 0; k < 3; k++) {
        m.tip_offset[k] = test_uniform(-2, 2);
        m.rotary_start[k] = test_uniform(-400, 400);
        m.rotary_end[k] = test_rand01() < 0.2 ? m.rotary_start[k] : m.rotary_start[k] + test_uniform(-400, 400);
    }
    return m;
}

/* The tool's frame R(u) (its columns: the chain's steps applied to the
 * unit vectors) and q(u) = R^T (p - c(u)), the point p seen from the tool. */
static void tool_frame_point(const fm_kin *k, double u, const double p[3], double q[3])
{
    double c[3], a[3], e[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    fm_kin_pose(k, u, c, a, NULL, NULL);
    for (int i = 0; i < k->nsteps; i++) {
        const kin_step *s = &k->step[i];
        double th = s->th0 + u * s->dth, co = cos(th), si = sin(th);
        for (int j = 0; j < 3; j++) {
            double *v = e[j], w[3], d = s->omega[0] * v[0] + s->omega[1] * v[1] + s->omega[2] * v[2];
            w[0] = s->omega[1] * v[2] - s->omega[2] * v[1];
            w[1] = s->omega[2] * v[0] - s->omega[0] * v[2];
            w[2] = s->omega[0] * v[1] - s->omega[1] * v[0];
            for (int m = 0; m < 3; m++) v[m] = v[m] * co + w[m] * si + s->omega[m] * d * (1 - co);
        }
    }
    for (int j = 0; j < 3; j++)
        q[j] = e[j][0] * (p[0] - c[0]) + e[j][1] * (p[1] - c[1]) + e[j][2] * (p[2] - c[2]);
}

static void check_random_soundness(void)
{
    long second_bad = 0;
    long outside = 0, checks = 0, speed_bad = 0, turn_bad = 0, deriv_bad = 0;
    for (int trial = 0; trial < 400; trial++) {
        fm_machine mc = random_machine();
        fm_motion m = random_rotary_motion(&mc);
        fm_kin k;
        CHECK(fm_kin_init(&k, &m, NULL));
        for (int piece = 0; piece < 20; piece++) {
            double w = pow(10, test_uniform(-6, 0));
            double ua = test_uniform(0, 1 - w), ub = ua + w;
            double clo[3], chi[3], alo[3], ahi[3];
            fm_motion_pose_bounds(&m, ua, ub, clo, chi, alo, ahi);
            for (int j = 0; j < 30; j++) {
                double u = j == 0 ? ua : j == 1 ? ub : test_uniform(ua, ub);
                double c[3], a[3];
                fm_motion_pose_at(&m, u, c, a);
                for (int i = 0; i < 3; i++) {
                    checks++;
                    if (c[i] < clo[i] || c[i] > chi[i] || a[i] < alo[i] || a[i] > ahi[i]) outside++;
                }
            }
        }
        /* Speed constants and derivatives (central differences). */
        for (int j = 0; j < 50; j++) {
            double u = test_uniform(1e-4, 1 - 1e-4), h = 1e-6;
            double c[3], a[3], dc[3], da[3], c1[3], a1[3], c2[3], a2[3];
            fm_kin_pose(&k, u, c, a, dc, da);
            fm_kin_pose(&k, u - h, c1, a1, NULL, NULL);
            fm_kin_pose(&k, u + h, c2, a2, NULL, NULL);
            double ndc = sqrt(dc[0] * dc[0] + dc[1] * dc[1] + dc[2] * dc[2]);
            double nda = sqrt(da[0] * da[0] + da[1] * da[1] + da[2] * da[2]);
            if (ndc > k.speed) speed_bad++;
            /* second derivatives: |c''| <= accel, |q''| <= fm_kin_second */
            double dc1[3], dc2[3], tmp[3], tmpa[3], H = 1e-4;
            fm_kin_pose(&k, u - H, tmp, tmpa, dc1, NULL);
            fm_kin_pose(&k, u + H, tmp, tmpa, dc2, NULL);
            double ddc = 0;
            for (int i = 0; i < 3; i++) ddc += pow((dc2[i] - dc1[i]) / (2 * H), 2);
            if (sqrt(ddc) > k.accel * (1 + 1e-6) + 1e-6) second_bad++;
            double p[3], q0[3], q1[3], q2[3], v2 = 0;
            for (int i = 0; i < 3; i++) p[i] = c[i] + test_uniform(-30, 30);
            tool_frame_point(&k, u - H, p, q1);
            tool_frame_point(&k, u, p, q0);
            tool_frame_point(&k, u + H, p, q2);
            double qq = 0;
            for (int i = 0; i < 3; i++) {
                qq += pow((q2[i] - 2 * q0[i] + q1[i]) / (H * H), 2);
                v2 += (p[i] - c[i]) * (p[i] - c[i]);
            }
            /* the finite difference sees |p - c| over u +- H */
            if (sqrt(qq) > fm_kin_second(&k, sqrt(v2) + k.speed * H) * (1 + 1e-4) + 1e-3) second_bad++;
            if (nda > k.turn) turn_bad++;
            for (int i = 0; i < 3; i++) {
                double fc = (c2[i] - c1[i]) / (2 * h), fa = (a2[i] - a1[i]) / (2 * h);
                if (fabs(fc - dc[i]) > 1e-4 * (1 + ndc) || fabs(fa - da[i]) > 1e-4 * (1 + nda)) deriv_bad++;
            }
        }
    }
    printf("random machines: %ld of %ld pose coordinates outside their boxes; speed bound broken %ld, turn bound "
           "broken %ld, derivatives off %ld times\n", outside, checks, speed_bad, turn_bad, deriv_bad);
    CHECK(outside == 0);
    CHECK(speed_bad == 0);
    CHECK(turn_bad == 0);
    CHECK(deriv_bad == 0);
    printf("second-order bounds broken %ld times\n", second_bad);
    CHECK(second_bad == 0);
}

/* The boxes are not just sound but tight as pieces shrink. */
static void check_box_tightness(void)
{
    fm_machine mc = trunnion(0);
    double from[3] = {12, -7, 20}, to[3] = {-15, 9, 4}, r0[3] = {-10, 0, 15}, r1[3] = {35, 0, 120};
    fm_motion m = rotary_line(&mc, from, to, r0, r1, 0);
    double clo[3], chi[3], alo[3], ahi[3];
    fm_motion_pose_bounds(&m, 0.5, 0.5 + 1e-4, clo, chi, alo, ahi);
    double c0[3], c1[3], a[3];
    fm_motion_pose_at(&m, 0.5, c0, a);
    fm_motion_pose_at(&m, 0.5 + 1e-4, c1, a);
    for (int i = 0; i < 3; i++) CHECK(chi[i] - clo[i] <= 4 * fabs(c1[i] - c0[i]) + 0.02);
}

/* ------------------------------------------------------------ folding -- */

static void check_fold(void)
{
    /* A 4-axis indexer: A (table, about X through the origin) at 30
     * degrees, then a straight move: the tip in the workpiece frame is the
     * machine point turned by -30 degrees about X, and the sweep takes a
     * 3-axis fast path. */
    fm_machine mc;
    memset(&mc, 0, sizeof mc);
    mc.rotary_count = 1;
    mc.rotary[0] = (fm_rotary_axis){.letter = 0, .carries = FM_ROTARY_TABLE, .around = {1, 0, 0}};
    double from[3] = {0, 0, 8}, to[3] = {20, 0, 8}, r[3] = {30, 0, 0};
    fm_motion m = rotary_line(&mc, from, to, r, r, 0);
    fm_motion f;
    CHECK(fm_kin_fold(&m, &f));
    double want[3];
    Rx(-30 * FM_DEG, to, want);
    for (int k = 0; k < 3; k++) CHECK_NEAR(f.end[k], want[k], 1e-12);
    fm_tool t;
    fm_tool_spec spec = sc_spec(FM_TOOL_FLAT);
    CHECK(fm_tool_build(&spec, &t, NULL) == FM_OK);
    fm_sweep *s;
    CHECK(fm_sweep_new(&m, &t.flutes, NULL, &s, NULL) == FM_OK);
    CHECK(fm_sweep_method_of(s) == FM_SWEEP_PLANAR_LINE);
    fm_sweep_free(s);
    /* A G17 arc at A = 90 lands in the XZ plane: the planar arc fast path. */
    double c[3] = {5, 0, 8};
    fm_motion arc = sc_arc(2, c, 6, 0, 2, 1, 0);
    arc.machine = &mc;
    arc.rotary_start[0] = arc.rotary_end[0] = 90;
    CHECK(fm_kin_fold(&arc, &f));
    CHECK(f.plane_axis == 1);
    CHECK(fm_sweep_new(&arc, &t.flutes, NULL, &s, NULL) == FM_OK);
    CHECK(fm_sweep_method_of(s) == FM_SWEEP_PLANAR_ARC);
    for (int i = 0; i <= 10; i++) {
        double u = i / 10.0, tip[3], ax[3], P[3], w[3];
        fm_sweep_pose(s, arc.t0 + u * (arc.t1 - arc.t0), tip, ax);
        fm_motion_point_at(&arc, u, P);
        Rx(-FM_PI / 2, P, w);
        for (int k = 0; k < 3; k++) CHECK_NEAR(tip[k], w[k], 1e-9);
    }
    fm_sweep_free(s);
    /* At 30 degrees the arc's plane is oblique: no fold, the search. */
    arc.rotary_start[0] = arc.rotary_end[0] = 30;
    CHECK(!fm_kin_fold(&arc, &f));
    CHECK(fm_sweep_new(&arc, &t.flutes, NULL, &s, NULL) == FM_OK);
    CHECK(fm_sweep_method_of(s) == FM_SWEEP_SEARCH);
    fm_sweep_free(s);
}

/* ----------------------------------------------- sweep vs brute force -- */

/* Points per machine motion and cutter (sweep_cases.h's sparse brute
 * force, held to the dense one on the first 4). */
enum { KIN_BRUTE_POINTS = 1000 };

static void check_sweeps(void)
{
    fm_machine trt = trunnion(0), trt_tcp = trunnion(1), head = bc_head(0);
    fm_machine ind;
    memset(&ind, 0, sizeof ind);
    ind.rotary_count = 1;
    ind.rotary[0] = (fm_rotary_axis){.letter = 0, .carries = FM_ROTARY_TABLE, .around = {1, 0, 0}};
    double z3[3] = {0, 0, 0};
    fm_motion ms[5];
    {
        double f[3] = {2, -3, 14}, to[3] = {-6, 5, 10}, r0[3] = {-10, 0, 15}, r1[3] = {25, 0, 80};
        ms[0] = rotary_line(&trt, f, to, r0, r1, 0);
        ms[1] = rotary_line(&trt_tcp, f, to, r0, r1, 1);
    }
    {
        double f[3] = {2, -3, 4}, to[3] = {-6, 5, -1}, r0[3] = {0, -20, 10}, r1[3] = {0, 30, -40};
        ms[2] = rotary_line(&head, f, to, r0, r1, 0);
        ms[2].tool_length = 20;
    }
    {
        /* the table turns a full turn under a still tool, and X with A */
        double f[3] = {0, 0, 8}, r1[3] = {360, 0, 0}, to[3] = {10, 0, 8}, r2[3] = {-270, 0, 0};
        ms[3] = rotary_line(&ind, f, f, z3, r1, 0);
        ms[4] = rotary_line(&ind, f, to, z3, r2, 0);
    }
    const char *names[5] = {"trunnion", "trunnion-tcp", "bc-head", "indexer-turn", "indexer-helix"};
    fm_tool_shape shapes[2] = {FM_TOOL_FLAT, FM_TOOL_BALL};
    double worst = 0;
    for (int c = 0; c < 2; c++) {
        fm_tool t;
        fm_tool_spec spec = sc_spec(shapes[c]);
        CHECK(fm_tool_build(&spec, &t, NULL) == FM_OK);
        for (int i = 0; i < 5; i++) {
            fm_sweep *s;
            CHECK(fm_sweep_new(&ms[i], &t.flutes, NULL, &s, NULL) == FM_OK);
            if (fm_sweep_method_of(s) != FM_SWEEP_SEARCH) fprintf(stderr, "%s: method %d\n", names[i], (int)fm_sweep_method_of(s));
            CHECK(fm_sweep_method_of(s) == FM_SWEEP_SEARCH);
            fm_sweep_worker *w = fm_sweep_worker_new(s);
            sc_speed speed = sc_motion_speed(&ms[i]);
            double lo[3], hi[3];
            fm_sweep_bounds(s, lo, hi);
            for (int j = 0; j < KIN_BRUTE_POINTS; j++) {
                double p[3], tip[3], ax[3];
                if (j % 2) {
                    for (int k = 0; k < 3; k++) p[k] = test_uniform(lo[k], hi[k]);
                } else {
                    /* near the moving tool's side */
                    fm_motion_pose_at(&ms[i], test_rand01(), tip, ax);
                    double e[3];
                    random_unit(e);
                    double h = test_uniform(0, 8);
                    for (int k = 0; k < 3; k++) p[k] = tip[k] + h * ax[k] + 3 * e[k] + test_uniform(-0.5, 0.5);
                }
                fm_sweep_value v;
                fm_sweep_eval_ex(s, w, p, &v);
                double b = sc_brute_sparse(s, w, &speed, p);
                if (j < 4) CHECK(sc_sparse_equals_dense(names[i], s, w, p, b)); /* on a few points per case */
                double err = fabs(v.value - b);
                if (err > worst) worst = err;
                if (err > FM_SWEEP_TOL + 1e-9)
                    fprintf(stderr, "%s %s at (%g, %g, %g): S %.10g (upper %.10g), brute %.10g\n", spec.shape == FM_TOOL_FLAT ? "flat" : "ball",
                            names[i], p[0], p[1], p[2], v.value, v.upper, b);
                /* certified (docs/sweep.md): value <= brute <= upper, upper - value <= FM_SWEEP_TOL */
                CHECK(v.value <= b + 1e-9);
                CHECK(v.upper >= b - 1e-9);
                CHECK(v.upper - v.value <= FM_SWEEP_TOL + 1e-12); /* + rounding of ~10 mm values */
                /* the box of the sweep holds it: S <= -distance outside */
                double d2 = 0;
                for (int k = 0; k < 3; k++) {
                    double e = p[k] < lo[k] ? lo[k] - p[k] : p[k] > hi[k] ? p[k] - hi[k] : 0;
                    d2 += e * e;
                }
                if (d2 > 0) CHECK(b <= -sqrt(d2) + 1e-9);
                /* interval soundness on a small box round p */
                fm_interval box[3];
                for (int k = 0; k < 3; k++) box[k] = (fm_interval){p[k] - 0.3, p[k] + 0.3};
                fm_interval iv = fm_sweep_interval(s, w, box);
                CHECK(iv.lo <= b + 1e-9 && iv.hi >= b - 1e-9);
            }
            fm_sweep_worker_free(w);
            fm_sweep_free(s);
        }
    }
    printf("rotary sweeps against the brute force, %d points per motion and cutter: worst %.3g mm\n",
           KIN_BRUTE_POINTS, worst);
}

/* ---------------------------------------------------------------- DAG -- */

static void check_dag(void)
{
    fm_machine trt = trunnion(0), trt_tcp = trunnion(1), mix = b_head_c_table(0);
    double f[3] = {2, -3, 14}, to[3] = {-6, 5, 10}, r0[3] = {-10, 20, 15}, r1[3] = {25, -30, 80};
    fm_motion ms[4] = {rotary_line(&trt, f, to, r0, r1, 0), rotary_line(&trt_tcp, f, to, r0, r1, 1),
                       rotary_line(&mix, f, to, r0, r1, 0), {0}};
    double c[3] = {1, 2, 3};
    ms[3] = sc_arc(0, c, 5, 0.2, 2.5, 1, 3);
    ms[3].machine = &trt;
    memcpy(ms[3].rotary_start, r0, sizeof r0);
    memcpy(ms[3].rotary_end, r1, sizeof r1);
    ms[2].tool_length = 30;
    fm_tool t;
    fm_tool_spec spec = sc_spec(FM_TOOL_BALL);
    CHECK(fm_tool_build(&spec, &t, NULL) == FM_OK);
    for (int i = 0; i < 4; i++) {
        fm_graph *g = fm_graph_new(0);
        fm_node T = fm_sweep_build_4d(g, &ms[i], &t.flutes, NULL);
        CHECK(T != FM_NONE);
        fm_sweep *s;
        CHECK(fm_sweep_new(&ms[i], &t.flutes, NULL, &s, NULL) == FM_OK);
        for (int j = 0; j < 100; j++) {
            double p[4], tip[3], ax[3];
            p[3] = test_uniform(ms[i].t0, ms[i].t1);
            fm_sweep_pose(s, p[3], tip, ax);
            for (int k = 0; k < 3; k++) p[k] = tip[k] + test_uniform(-4, 4) + 3 * ax[k];
            double native = fmin(fm_sweep_tool_at(s, NULL, p, p[3]), fmin(p[3] - ms[i].t0, ms[i].t1 - p[3]));
            CHECK_NEAR(test_dag_eval(g, T, p), native, 1e-9);
        }
        fm_sweep_free(s);
        fm_graph_free(g);
    }
}

/* ------------------------------------------------------------ machine -- */

static void check_machine(void)
{
    fm_machine mc = trunnion(0);
    mc.rotary[0].around[0] = 3; /* normalized */
    CHECK(fm_machine_validate(&mc, NULL) == FM_OK);
    CHECK_NEAR(mc.rotary[0].around[0], 1, 0);
    CHECK(fm_machine_axis_of(&mc, 2) == 1 && fm_machine_axis_of(&mc, 1) == -1);
    /* The table transform is the inverse of the chain: a workpiece point
     * placed by it comes back through fm_motion_pose_at. */
    double r[3] = {33, 0, -71}, R[9], T[3], w[3] = {4, -6, 9}, x[3];
    fm_machine_table_transform(&mc, r, -1, R, T);
    for (int i = 0; i < 3; i++) x[i] = R[3 * i] * w[0] + R[3 * i + 1] * w[1] + R[3 * i + 2] * w[2] + T[i];
    double back[3], ax[3];
    trunnion_written(33 * FM_DEG, -71 * FM_DEG, x, back, ax);
    for (int i = 0; i < 3; i++) CHECK_NEAR(back[i], w[i], 1e-12);
    /* Only the base axis: R_A alone. */
    fm_machine_table_transform(&mc, r, 1, R, T);
    for (int i = 0; i < 3; i++) x[i] = R[3 * i] * w[0] + R[3 * i + 1] * w[1] + R[3 * i + 2] * w[2] + T[i];
    double want[3];
    about(Rx, TRT_A_THROUGH, 33 * FM_DEG, w, want);
    for (int i = 0; i < 3; i++) CHECK_NEAR(x[i], want[i], 1e-12);
    fm_error err;
    fm_machine bad = trunnion(0);
    bad.rotary[1].letter = 0;
    CHECK(fm_machine_validate(&bad, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "twice");
    bad = trunnion(0);
    bad.rotary[0].around[0] = 0;
    CHECK(fm_machine_validate(&bad, &err) == FM_ERR_INPUT);
    bad = trunnion(0);
    bad.rotary[0].has_limits = 1;
    bad.rotary[0].limit_lo = 10;
    bad.rotary[0].limit_hi = -10;
    CHECK(fm_machine_validate(&bad, &err) == FM_ERR_INPUT);
    /* Pieces for drawing follow the largest joint turn. */
    double f3[3] = {0, 0, 0}, r0[3] = {0, 0, 0}, r1[3] = {90, 0, 0};
    fm_motion m = rotary_line(&mc, f3, f3, r0, r1, 0);
    CHECK(fm_motion_pieces(&m, 5 * FM_DEG, 32, 1000) == 18);
    CHECK(fm_motion_has_rotary(&m));
    m.machine = NULL;
    CHECK(!fm_motion_has_rotary(&m) && fm_motion_pieces(&m, 5 * FM_DEG, 32, 1000) == 1);
}

int main(void)
{
    check_machine();
    check_five_axis_move();
    check_frame_up();
    check_random_soundness();
    check_box_tightness();
    check_fold();
    check_sweeps();
    check_dag();
    printf("%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures ? 1 : 0;
}
