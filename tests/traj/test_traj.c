/* test_traj.c: the parametric trajectory front end: poses against closed
 * forms computed here, soundness of pose_bounds, the motion stream (times,
 * rapids, inch), and every validation error with its message and position. */
#include <math.h>
#include <pthread.h>
#include <stdlib.h>
#include <string.h>

#include "test.h"
#include "toolpaths/traj/traj.h"

#define MAXM 64

static fm_motion got[MAXM];
static int ngot;
/* Checks that need the path run inside the sink (it lives only until the
 * run returns). */
static void (*in_sink)(const fm_motion *m);

static int collect(void *user, const fm_motion *m)
{
    (void)user;
    if (ngot < MAXM) got[ngot++] = *m;
    if (in_sink) in_sink(m);
    return 0;
}

static fm_status run(const char *text, const fm_traj_options *opt, fm_error *err)
{
    ngot = 0;
    return fm_traj_run_string(text, strlen(text), "doc.json", opt, collect, NULL, NULL, err);
}

/* 1-based line and column (characters) of the first occurrence of needle
 * in text, counted here independently of the library. */
static void where(const char *text, const char *needle, int *line, int *col)
{
    const char *p = strstr(text, needle);
    *line = 1;
    *col = 1;
    if (!p) {
        *line = *col = -1;
        return;
    }
    for (const char *q = text; q < p; q++) {
        if (*q == '\n') {
            (*line)++;
            *col = 1;
        } else {
            (*col)++;
        }
    }
}

/* Runs a document that must fail with `code`, a message containing `msg`
 * and a position at the first occurrence of `at` (NULL: no position). */
static void expect_error(const char *text, const fm_traj_options *opt, fm_status code,
                         const char *msg, const char *at, int line)
{
    fm_error err;
    fm_status st = run(text, opt, &err);
    if (st != code || !strstr(err.message, msg))
        fprintf(stderr, "test line %d: status %d, message: %s\n", line, (int)st, err.message);
    CHECK(st == code);
    CHECK_STR_CONTAINS(err.message, msg);
    CHECK(ngot == 0); /* nothing is emitted from a refused document */
    if (at) {
        int l, c;
        where(text, at, &l, &c);
        if (err.line != l || err.column != c)
            fprintf(stderr, "test line %d: position %d:%d, expected %d:%d (%s)\n", line, err.line,
                    err.column, l, c, err.message);
        CHECK(err.line == l);
        CHECK(err.column == c);
        CHECK(!strcmp(err.file, "doc.json"));
    }
}
#define EXPECT_ERROR(text, opt, code, msg, at) expect_error(text, opt, code, msg, at, __LINE__)

/* ------------------------------------------------------------- helix -- */

static const char *helix_doc =
    "{\"units\": \"mm\", \"tool\": 3,\n"
    " \"segments\": [\n"
    "  {\"t\": [0, 6.283185307179586], \"x\": \"10*cos(t)\", \"y\": \"10*sin(t)\", \"z\": \"-t\",\n"
    "   \"axis\": [\"0\", \"sin(0.2*t)\", \"cos(0.2*t)\"], \"feed\": 600, \"spindle\": -12000}\n"
    " ]}\n";

static void helix_closed(double t, double p[3], double a[3])
{
    p[0] = 10 * cos(t);
    p[1] = 10 * sin(t);
    p[2] = -t;
    a[0] = 0;
    a[1] = sin(0.2 * t);
    a[2] = cos(0.2 * t);
}

static void check_helix(const fm_motion *m)
{
    CHECK(m->kind == FM_MOTION_PARAM);
    CHECK(m->path && m->path->pose && m->path->pose_bounds);
    if (!m->path) return;
    for (int k = 0; k < 300; k++) {
        double t = test_uniform(m->t0, m->t1), p[3], a[3], q[3], b[3];
        m->path->pose(m->path->ctx, t, p, a);
        helix_closed(t, q, b);
        for (int i = 0; i < 3; i++) {
            CHECK_NEAR(p[i], q[i], 1e-12);
            CHECK_NEAR(a[i], b[i], 1e-12);
        }
    }
    /* pose_bounds is sound on random sub-intervals: every sampled pose
     * (library and closed form) lies inside; and it is reasonably tight. */
    for (int k = 0; k < 200; k++) {
        double ta = test_uniform(m->t0, m->t1), tb = test_uniform(m->t0, m->t1);
        if (ta > tb) {
            double x = ta;
            ta = tb;
            tb = x;
        }
        if (k % 10 == 0) tb = ta; /* degenerate intervals too */
        double plo[3], phi[3], alo[3], ahi[3];
        m->path->pose_bounds(m->path->ctx, ta, tb, plo, phi, alo, ahi);
        for (int j = 0; j <= 50; j++) {
            double t = ta + (tb - ta) * j / 50.0, p[3], a[3], q[3], b[3];
            m->path->pose(m->path->ctx, t, p, a);
            helix_closed(t, q, b);
            for (int i = 0; i < 3; i++) {
                CHECK(plo[i] <= p[i] && p[i] <= phi[i]);
                CHECK(alo[i] <= a[i] && a[i] <= ahi[i]);
                CHECK(plo[i] <= q[i] + 1e-12 && q[i] - 1e-12 <= phi[i]);
            }
        }
        /* |d/dt| <= 10 for x and y, 1 for z: an enclosure no wider than a
         * few times the Lipschitz bound. */
        CHECK(phi[0] - plo[0] <= 3 * 10 * (tb - ta) + 1e-9);
        CHECK(phi[2] - plo[2] <= 3 * (tb - ta) + 1e-9);
        for (int i = 0; i < 3; i++) CHECK(alo[i] >= -1 && ahi[i] <= 1);
    }
}

static void test_helix(void)
{
    in_sink = check_helix;
    fm_error err;
    fm_traj_summary sum;
    ngot = 0;
    fm_status st = fm_traj_run_string(helix_doc, strlen(helix_doc), "helix", NULL, collect, NULL,
                                      &sum, &err);
    in_sink = NULL;
    CHECK(st == FM_OK);
    if (st) fprintf(stderr, "%s\n", err.message);
    CHECK(ngot == 1);
    CHECK(sum.motions == 1 && sum.segments == 1 && !sum.stopped);
    CHECK_NEAR(sum.seconds, 2 * FM_PI, 1e-12);
    const fm_motion *m = &got[0];
    CHECK_NEAR(m->t0, 0, 0);
    CHECK_NEAR(m->t1, 2 * FM_PI, 1e-15);
    CHECK_NEAR(m->start[0], 10, 1e-12);
    CHECK_NEAR(m->end[2], -2 * FM_PI, 1e-12);
    CHECK_NEAR(m->axis_end[1], sin(0.4 * FM_PI), 1e-12);
    CHECK(m->tool == 3);
    CHECK_NEAR(m->feed, 600, 0);
    CHECK(m->spindle_dir == -1);
    CHECK_NEAR(m->spindle_rpm, 12000, 0);
    CHECK(m->line == 3); /* the segment's object starts on line 3 */
    CHECK(m->block == 0 && m->index == 0);
}

/* Several threads evaluate the same path at once (the sweep's workers). */
static const fm_motion *thread_motion;
static int thread_errors;
static void *thread_body(void *arg)
{
    unsigned seed = (unsigned)(size_t)arg;
    int bad = 0;
    for (int k = 0; k < 4000; k++) {
        seed = seed * 1103515245u + 12345u;
        double t = 2 * FM_PI * (seed >> 8) / 16777216.0, p[3], a[3], q[3], b[3];
        thread_motion->path->pose(thread_motion->path->ctx, t, p, a);
        helix_closed(t, q, b);
        for (int i = 0; i < 3; i++) bad += fabs(p[i] - q[i]) > 1e-12 || fabs(a[i] - b[i]) > 1e-12;
    }
    __atomic_add_fetch(&thread_errors, bad, __ATOMIC_RELAXED);
    return NULL;
}

static void check_threads(const fm_motion *m)
{
    enum { N = 12 }; /* more threads than the evaluator pool */
    pthread_t th[N];
    thread_motion = m;
    thread_errors = 0;
    for (int i = 0; i < N; i++) pthread_create(&th[i], NULL, thread_body, (void *)(size_t)(i + 1));
    for (int i = 0; i < N; i++) pthread_join(th[i], NULL);
    CHECK(thread_errors == 0);
}

static void test_threads(void)
{
    in_sink = check_threads;
    fm_error err;
    CHECK(run(helix_doc, NULL, &err) == FM_OK);
    in_sink = NULL;
}

/* ----------------------------------------- u, axis normalization, inch -- */

static void check_u(const fm_motion *m)
{
    double p[3], a[3];
    m->path->pose(m->path->ctx, 3, p, a);
    CHECK_NEAR(p[0], 5, 1e-12);           /* 10*u with u = (3-2)/(4-2) */
    CHECK_NEAR(p[1], 3 * 3, 1e-12);       /* t^2 */
    CHECK_NEAR(a[0], 1 / sqrt(2), 1e-15); /* (1, 1, 0) normalized */
    CHECK_NEAR(a[1], 1 / sqrt(2), 1e-15);
    CHECK_NEAR(a[2], 0, 0);
}

static void test_u_and_axis(void)
{
    const char *doc = "{\"segments\": [{\"t\": [2, 4], \"x\": \"10*u\", \"y\": \"t^2\", \"z\": 7,"
                      " \"axis\": [1, \"1\", 0]}]}";
    in_sink = check_u;
    fm_error err;
    CHECK(run(doc, NULL, &err) == FM_OK);
    in_sink = NULL;
    CHECK(ngot == 1);
    CHECK_NEAR(got[0].start[0], 0, 0);
    CHECK_NEAR(got[0].end[0], 10, 1e-12);
    CHECK_NEAR(got[0].end[2], 7, 0);
    CHECK_NEAR(got[0].t0, 2, 0); /* program time starts at the document's first time */
    CHECK_NEAR(got[0].t1, 4, 0);
}

/* Axis components far above 1e154, where their squares overflow: the axis
 * is still (0, 0, 1), and pose_bounds still hold it with lo <= hi (fuzz_traj
 * once found the z bound [0.99999999999999, 1e-14]; the document is kept
 * as tests/traj/corpus/regress_axis_overflow.json). An axis of 1e200 mm
 * normalizes like any other; one of 5e-200 (squares that vanish) is refused
 * as shorter than TRAJ_MIN_AXIS, as it should be. */
static int huge_checked;

static void check_huge_axis(const fm_motion *m)
{
    const fm_path *p = m->path;
    for (int k = 0; k < 8; k++) {
        double ta = m->t0 + (m->t1 - m->t0) * k / 8, tb = m->t0 + (m->t1 - m->t0) * (k + 1) / 8;
        double lo[3], hi[3], alo[3], ahi[3];
        p->pose_bounds(p->ctx, ta, tb, lo, hi, alo, ahi);
        for (int i = 0; i < 3; i++) CHECK(alo[i] <= ahi[i]);
        for (int j = 0; j <= 4; j++) {
            double pos[3], ax[3];
            p->pose(p->ctx, ta + (tb - ta) * j / 4, pos, ax);
            CHECK_NEAR(ax[0], 0, 1e-15);
            CHECK_NEAR(ax[1], 0, 1e-15);
            CHECK_NEAR(ax[2], 1, 1e-15);
            for (int i = 0; i < 3; i++) CHECK(ax[i] >= alo[i] && ax[i] <= ahi[i]);
        }
        CHECK(ahi[2] == 1 && alo[2] > 0.99);
    }
    huge_checked++;
}

static void check_scaled_axis(const fm_motion *m)
{
    double pos[3], ax[3];
    m->path->pose(m->path->ctx, 0.5 * (m->t0 + m->t1), pos, ax);
    CHECK_NEAR(ax[0], 0.6, 1e-15); /* (3, 4, 0) scaled by 1e200 or 1e-200 */
    CHECK_NEAR(ax[1], 0.8, 1e-15);
    CHECK_NEAR(ax[2], 0, 0);
    double lo[3], hi[3], alo[3], ahi[3];
    m->path->pose_bounds(m->path->ctx, m->t0, m->t1, lo, hi, alo, ahi);
    CHECK(alo[0] <= 0.6 && ahi[0] >= 0.6 && ahi[0] - alo[0] < 1e-12);
    CHECK(alo[1] <= 0.8 && ahi[1] >= 0.8 && ahi[1] - alo[1] < 1e-12);
    huge_checked++;
}

static void test_axis_overflow(void)
{
    const char *doc = "{\"segments\":[{\"t\":[4,5],\"x\":1,\"y\":0,\"z\":3,"
                      "\"axis\":[\"(0)\",\"0\",\"exp(620*u)\"]}]}";
    CHECK(strlen(doc) == 76);
    fm_error err;
    huge_checked = 0;
    in_sink = check_huge_axis;
    CHECK(run(doc, NULL, &err) == FM_OK);
    in_sink = check_scaled_axis;
    CHECK(run("{\"segments\":[{\"t\":[0,1],\"x\":\"t\",\"y\":0,\"z\":0,"
              "\"axis\":[\"3e200+0*t\",\"4e200\",0]}]}", NULL, &err) == FM_OK);
    CHECK(run("{\"segments\":[{\"t\":[0,1],\"x\":\"t\",\"y\":0,\"z\":0,"
              "\"axis\":[\"3e-200+0*t\",\"4e-200\",0]}]}", NULL, &err) == FM_ERR_INPUT);
    in_sink = NULL;
    CHECK(huge_checked == 2);
}

static void check_inch(const fm_motion *m)
{
    if (m->block != 0) return;
    double p[3], a[3], plo[3], phi[3], alo[3], ahi[3];
    m->path->pose(m->path->ctx, 0.5, p, a);
    CHECK_NEAR(p[0], 0.5 * 25.4, 1e-12);
    CHECK_NEAR(p[2], -0.25 * 25.4, 1e-12);
    m->path->pose_bounds(m->path->ctx, 0.25, 0.75, plo, phi, alo, ahi);
    CHECK(plo[0] <= 0.25 * 25.4 && phi[0] >= 0.75 * 25.4);
    CHECK(phi[0] - plo[0] < 0.5 * 25.4 + 1e-9);
}

static void test_inch(void)
{
    const char *doc = "{\"units\": \"inch\", \"tolerance\": 0.0001, \"segments\": [\n"
                      " {\"t\": [0, 1], \"x\": \"t\", \"y\": 0, \"z\": \"-t/2\", \"feed\": 10},\n"
                      " {\"t\": [1, 2], \"x\": 1.00001, \"y\": 0, \"z\": -0.5},\n"
                      " {\"rapid\": true, \"to\": [1, 0, 1]}]}";
    in_sink = check_inch;
    fm_error err;
    fm_status st = run(doc, NULL, &err);
    in_sink = NULL;
    CHECK(st == FM_OK);
    if (st) fprintf(stderr, "%s\n", err.message);
    CHECK(ngot == 3);
    CHECK_NEAR(got[0].feed, 254, 1e-12);
    CHECK_NEAR(got[1].feed, 254, 1e-12); /* feed carries over */
    CHECK_NEAR(got[0].end[0], 25.4, 1e-12);
    CHECK(got[2].kind == FM_MOTION_RAPID);
    CHECK_NEAR(got[2].end[2], 25.4, 1e-12);
    /* rapid from (1.00001, 0, -0.5) in to (1, 0, 1) in at 5000 mm/min */
    CHECK_NEAR(got[2].t1 - got[2].t0, sqrt(1e-5 * 1e-5 + 1.5 * 1.5) * 25.4 / 5000 * 60, 1e-12);
    /* A gap of 0.00001 in passes a 0.0001 in tolerance; in mm it would not
     * pass 0.0001 mm. */
    const char *doc_mm = "{\"tolerance\": 0.0001, \"segments\": [\n"
                         " {\"t\": [0, 1], \"x\": \"t\", \"y\": 0, \"z\": 0},\n"
                         " {\"t\": [1, 2], \"x\": 1.001, \"y\": 0, \"z\": 0}]}";
    EXPECT_ERROR(doc_mm, NULL, FM_ERR_INPUT, "gap 0.001 mm exceeds the tolerance 0.0001 mm",
                 "{\"t\": [1, 2]");
}

/* ------------------------------------------------------------- rapids -- */

static void check_after_rapid(const fm_motion *m)
{
    if (m->kind != FM_MOTION_PARAM || m->block != 2) return;
    /* document time 5 is program time m->t0; z = 30 - (t - 5) */
    double p[3], a[3];
    m->path->pose(m->path->ctx, m->t0 + 0.5, p, a);
    CHECK_NEAR(p[0], 10, 0);
    CHECK_NEAR(p[2], 29.5, 1e-9);
    double plo[3], phi[3], alo[3], ahi[3];
    m->path->pose_bounds(m->path->ctx, m->t0, m->t1, plo, phi, alo, ahi);
    CHECK(plo[2] <= 29 && phi[2] >= 30);
    CHECK(phi[2] - plo[2] < 1 + 1e-6);
}

static void test_rapid(void)
{
    const char *doc = "{\"segments\": [\n"
                      " {\"t\": [0, 1], \"x\": \"10*t\", \"y\": 0, \"z\": 0, \"tool\": 2},\n"
                      " {\"rapid\": true},\n"
                      " {\"t\": [5, 6], \"x\": 10, \"y\": 0, \"z\": \"30 - (t - 5)\"},\n"
                      " {\"rapid\": true, \"to\": [10, 0, 50]},\n"
                      " {\"rapid\": true, \"to\": [0, 0, 50]}]}";
    in_sink = check_after_rapid;
    fm_error err;
    fm_traj_summary sum;
    ngot = 0;
    fm_status st = fm_traj_run_string(doc, strlen(doc), "r", NULL, collect, NULL, &sum, &err);
    in_sink = NULL;
    CHECK(st == FM_OK);
    if (st) fprintf(stderr, "%s\n", err.message);
    CHECK(ngot == 5);
    if (ngot != 5) return;
    const fm_motion *r = &got[1];
    CHECK(r->kind == FM_MOTION_RAPID && r->path == NULL);
    CHECK_NEAR(r->start[0], 10, 1e-12);
    CHECK_NEAR(r->end[2], 30, 1e-12);
    CHECK_NEAR(r->t0, 1, 0);
    CHECK_NEAR(r->t1, 1 + 30.0 / 5000 * 60, 1e-12);
    CHECK(r->tool == 2);
    CHECK(r->line == 3);
    /* the next segment follows the rapid at once */
    CHECK_NEAR(got[2].t0, r->t1, 0);
    CHECK_NEAR(got[2].t1 - got[2].t0, 1, 1e-12);
    CHECK_NEAR(got[3].t1 - got[3].t0, 21.0 / 5000 * 60, 1e-12);
    CHECK_NEAR(got[4].start[2], 50, 0);
    CHECK_NEAR(got[4].end[0], 0, 0);
    CHECK_NEAR(sum.seconds, got[4].t1, 0);
    for (int i = 0; i < 5; i++) CHECK(got[i].index == i);
    /* a different rapid rate changes only the rapids' times */
    fm_traj_options opt;
    fm_traj_options_default(&opt);
    opt.rapid_rate = 1000;
    CHECK(run(doc, &opt, &err) == FM_OK);
    CHECK_NEAR(got[1].t1 - got[1].t0, 30.0 / 1000 * 60, 1e-12);
    /* skip and stop */
    opt.skip_motions = 3;
    CHECK(run(doc, &opt, &err) == FM_OK);
    CHECK(ngot == 2 && got[0].index == 3);
}

static int stop_after_one(void *user, const fm_motion *m)
{
    (*(int *)user)++;
    return m->index == 0;
}

static void test_stop(void)
{
    int n = 0;
    fm_traj_summary sum;
    fm_error err;
    const char *doc = "{\"segments\": [{\"t\": [0, 1], \"x\": \"t\", \"y\": 0, \"z\": 0},"
                      "{\"t\": [1, 2], \"x\": \"t\", \"y\": 0, \"z\": 0}]}";
    CHECK(fm_traj_run_string(doc, strlen(doc), "s", NULL, stop_after_one, &n, &sum, &err) == FM_OK);
    CHECK(n == 1 && sum.stopped == 1);
}

/* -------------------------------------------------------- validation -- */

static void test_errors(void)
{
    EXPECT_ERROR("{\"segments\": [\n  {\"t\": [0, 1],, }]}", NULL, FM_ERR_INPUT, "invalid JSON",
                 ", }"); /* jansson points at the second comma */
    EXPECT_ERROR("[1, 2]", NULL, FM_ERR_INPUT, "expected a JSON object", "[1");
    EXPECT_ERROR("{\"segments\": [], \"unit\": \"mm\"}", NULL, FM_ERR_INPUT,
                 "unknown field \"unit\"", "\"mm\"");
    EXPECT_ERROR("{\"units\": \"cm\", \"segments\": []}", NULL, FM_ERR_INPUT,
                 "\"units\": expected \"mm\" or \"inch\"", "\"cm\"");
    EXPECT_ERROR("{\"segments\": []}", NULL, FM_ERR_INPUT, "non-empty array", "[]");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [1, 1], \"x\": 0, \"y\": 0, \"z\": 0}]}", NULL,
                 FM_ERR_INPUT, "segment 0: \"t\": the interval [1, 1] is empty", "[1, 1]");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [2, 1], \"x\": 0, \"y\": 0, \"z\": 0}]}", NULL,
                 FM_ERR_INPUT, "expected t0 < t1", "[2, 1]");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0], \"x\": 0, \"y\": 0, \"z\": 0}]}", NULL,
                 FM_ERR_INPUT, "expected [t0, t1]", "[0]");
    EXPECT_ERROR("{\"segments\": [\n {\"x\": 0, \"y\": 0, \"z\": 0}]}", NULL, FM_ERR_INPUT,
                 "segment 0: missing \"t\"", "{\"x\"");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"z\": 0}]}", NULL, FM_ERR_INPUT,
                 "segment 0: missing \"y\"", "{\"t\"");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0, \"fed\": 1}]}",
                 NULL, FM_ERR_INPUT, "segment 0: unknown field \"fed\"", "1}");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": true, \"y\": 0, \"z\": 0}]}", NULL,
                 FM_ERR_INPUT, "segment 0: \"x\": expected an expression", "true");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0, \"tool\": 1.5}]}",
                 NULL, FM_ERR_INPUT, "\"tool\": expected an integer", "1.5");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0, \"feed\": -1}]}",
                 NULL, FM_ERR_INPUT, "\"feed\": expected a number >= 0", "-1}");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0, \"rapid\": 1}]}",
                 NULL, FM_ERR_INPUT, "\"rapid\": expected true or false", "1}");
    /* expression errors point inside the string: the column of the fault */
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": \"10*cos(t)\",\n"
                 "  \"y\": \"10 * sinn(t)\", \"z\": 0}]}",
                 NULL, FM_ERR_INPUT, "segment 0: \"y\": expression column 6", "sinn");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": \"t + q\", \"y\": 0, \"z\": 0}]}",
                 NULL, FM_ERR_INPUT, "segment 0: \"x\": expression column 5", "q\"");
    /* an escape before the fault: the column is still the raw character */
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": \"\\u0074 + )\", \"y\": 0, \"z\": 0}]}",
                 NULL, FM_ERR_INPUT, "segment 0: \"x\": expression column 5", ")\"");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0,\n"
                 "  \"axis\": [\"0\", \"1 +\", \"1\"]}]}",
                 NULL, FM_ERR_INPUT, "segment 0: \"axis[1]\": expression column 4", "\", \"1\"]");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0, \"axis\": [0, 2]}]}",
                 NULL, FM_ERR_INPUT, "\"axis\": expected [a, b, c]", "[0, 2]");
    /* non-finite expressions: sampled and by intervals */
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": \"log(t)\", \"z\": 0}]}", NULL,
                 FM_ERR_INPUT, "segment 0: \"y\" is not finite at t = 0 (-inf)", "\"log");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 2], \"x\": 0, \"y\": 0, \"z\": \"1/(t-1)\"}]}", NULL,
                 FM_ERR_INPUT, "segment 0: \"z\" is not finite at t = 1 (inf)", "\"1/");
    /* 1000 samples of [0, 2.1] miss t = 1; the interval check finds it */
    {
        fm_error err;
        const char *doc = "{\"segments\": [{\"t\": [0, 2.1], \"x\": \"1/(t-1)\", \"y\": 0, \"z\": 0}]}";
        CHECK(run(doc, NULL, &err) == FM_ERR_INPUT);
        CHECK_STR_CONTAINS(err.message, "\"x\" is unbounded near t = 1");
        double t = atof(strstr(err.message, "t = ") + 4);
        CHECK_NEAR(t, 1, 1e-9);
    }
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 2], \"x\": \"sqrt(t-1)\", \"y\": 0, \"z\": 0}]}", NULL,
                 FM_ERR_INPUT, "\"x\" is not finite at t = 0 (NaN)", "\"sqrt");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0,"
                 " \"axis\": [0, 0, 0]}]}",
                 NULL, FM_ERR_INPUT, "the tool axis is zero at t = 0", "[0, 0, 0]");
    {
        fm_error err;
        const char *doc = "{\"segments\": [{\"t\": [0, 2.1], \"x\": 0, \"y\": 0, \"z\": 0,"
                          " \"axis\": [\"t-1\", 0, 0]}]}";
        CHECK(run(doc, NULL, &err) == FM_ERR_INPUT);
        CHECK_STR_CONTAINS(err.message, "the tool axis may be zero near t = ");
        const char *at = strstr(err.message, "t = ");
        CHECK(at && fabs(atof(at + 4) - 1) < 1e-8);
    }
    /* order and continuity */
    const char *gap = "{\"segments\": [\n {\"t\": [0, 1], \"x\": \"t\", \"y\": 0, \"z\": 0},\n"
                      " {\"t\": [1, 2], \"x\": \"t + 0.5\", \"y\": 0, \"z\": 0}]}";
    EXPECT_ERROR(gap, NULL, FM_ERR_INPUT,
                 "segment 1 starts at (1.5, 0, 0) but segment 0 ends at (1, 0, 0) mm: gap 0.5 mm",
                 "{\"t\": [1, 2]");
    const char *turn = "{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0},\n"
                       " {\"t\": [1, 2], \"x\": 0, \"y\": 0, \"z\": 0, \"axis\": [0, 0.01, 1]}]}";
    EXPECT_ERROR(turn, NULL, FM_ERR_INPUT, "segment 1 starts with the tool axis", "[0, 0.01");
    fm_traj_options loose;
    fm_traj_options_default(&loose);
    loose.axis_tolerance = 0.02; /* atan(0.01) < 0.02 rad */
    {
        fm_error err;
        CHECK(run(turn, &loose, &err) == FM_OK);
    }
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 2], \"x\": 0, \"y\": 0, \"z\": 0},\n"
                 " {\"t\": [1, 3], \"x\": 0, \"y\": 0, \"z\": 0}]}",
                 NULL, FM_ERR_INPUT, "segment 1: \"t\" starts at 1, before segment 0 ends", "1, 3");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0},\n"
                 " {\"t\": [2, 3], \"x\": 0, \"y\": 0, \"z\": 0}]}",
                 NULL, FM_ERR_INPUT, "consecutive segments must meet in time", "2, 3");
    EXPECT_ERROR("{\"segments\": [\n {\"rapid\": true, \"to\": [0, 0, 0]}]}", NULL, FM_ERR_INPUT,
                 "a rapid cannot be the first segment", "{\"rapid");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0},\n {\"rapid\": true}]}",
                 NULL, FM_ERR_INPUT, "segment 1: a rapid at the end needs \"to\"", "{\"rapid");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0},\n"
                 " {\"rapid\": true},\n {\"rapid\": true, \"to\": [1, 2, 3]}]}",
                 NULL, FM_ERR_INPUT, "segment 1: a rapid without \"to\" must be followed",
                 "{\"rapid\": true},");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0},\n"
                 " {\"rapid\": true, \"to\": [1, 2]}]}",
                 NULL, FM_ERR_INPUT, "\"to\": expected [x, y, z]", "[1, 2]");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0},\n"
                 " {\"rapid\": true, \"x\": 1}]}",
                 NULL, FM_ERR_INPUT, "segment 1: unknown field \"x\"", "1}");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0},\n"
                 " {\"rapid\": true, \"to\": [0, 0, 5]},\n {\"t\": [1, 2], \"x\": 0, \"y\": 0, \"z\": 4}]}",
                 NULL, FM_ERR_INPUT, "but the rapid 1 ends at (0, 0, 5) mm: gap 1 mm",
                 "{\"t\": [1, 2]");
    EXPECT_ERROR("{\"segments\": [\n {\"t\": [0, 1], \"x\": 0, \"y\": 0, \"z\": 0},\n"
                 " {\"rapid\": true},\n {\"t\": [1, 2], \"x\": 0, \"y\": 0, \"z\": 4,"
                 " \"axis\": [0, 0, -1]}]}",
                 NULL, FM_ERR_INPUT, "the rapid would turn the tool axis by 180 degrees",
                 "{\"rapid");
}

static void test_budgets(void)
{
    fm_traj_options opt;
    fm_traj_options_default(&opt);
    const char *two = "{\"segments\": [{\"t\": [0, 1], \"x\": \"t\", \"y\": 0, \"z\": 0},"
                      "{\"t\": [1, 2], \"x\": \"t\", \"y\": 0, \"z\": 0}]}";
    opt.max_segments = 1;
    EXPECT_ERROR(two, &opt, FM_ERR_LIMIT, "2 segments; the limit is 1", "[{");
    fm_traj_options_default(&opt);
    opt.max_document_bytes = 20;
    EXPECT_ERROR(two, &opt, FM_ERR_LIMIT, "the limit is 20", NULL);
    fm_traj_options_default(&opt);
    opt.max_expression_bytes = 3;
    EXPECT_ERROR("{\"segments\": [{\"t\": [0, 1], \"x\": \"t+t+t\", \"y\": 0, \"z\": 0}]}", &opt,
                 FM_ERR_LIMIT, "\"x\": expression of 5 bytes; the limit is 3", "\"t+t+t\"");
    fm_traj_options_default(&opt);
    opt.max_expression_nodes = 10;
    EXPECT_ERROR("{\"segments\": [{\"t\": [0, 1], \"x\": \"sin(t)+cos(t)+exp(t)+sin(2*t)+cos(3*t)"
                 "+sin(4*t)+cos(5*t)\", \"y\": 0, \"z\": 0}]}",
                 &opt, FM_ERR_LIMIT, "frep nodes; the limit is 10", "\"sin");
    fm_traj_options_default(&opt);
    opt.max_total_nodes = 12;
    EXPECT_ERROR("{\"segments\": [{\"t\": [0, 1], \"x\": \"sin(t)+cos(t)+exp(t)+sin(2*t)+cos(3*t)"
                 "+sin(4*t)+cos(5*t)\", \"y\": 0, \"z\": 0}]}",
                 &opt, FM_ERR_LIMIT, "need more than 12 frep nodes", "\"sin");
}

/* ------------------------------------------------------------- files -- */

static int count_sink(void *user, const fm_motion *m)
{
    (*(int *)user)++;
    return m->t1 < m->t0;
}

static void test_files(void)
{
    static const char *good[] = {"../examples/helix_tilt.json", "traj/docs/helix.json",
                                 "traj/docs/inch_rapid.json"};
    for (size_t i = 0; i < sizeof good / sizeof *good; i++) {
        int n = 0;
        fm_error err;
        fm_traj_summary sum;
        fm_status st = fm_traj_run_file(good[i], NULL, count_sink, &n, &sum, &err);
        if (st) fprintf(stderr, "%s: %s\n", good[i], err.message);
        CHECK(st == FM_OK);
        CHECK(n > 0 && n == sum.motions);
    }
    fm_error err;
    CHECK(fm_traj_run_file("traj/docs/no_such_file.json", NULL, count_sink, NULL, NULL, &err) ==
          FM_ERR_IO);
    CHECK(fm_traj_run_file("traj/docs/bad_expression.json", NULL, count_sink, NULL, NULL, &err) ==
          FM_ERR_INPUT);
    CHECK(!strcmp(err.file, "traj/docs/bad_expression.json"));
    CHECK(err.line == 4 && err.column == 35); /* the t after "sin" */
}

int main(void)
{
    test_helix();
    test_threads();
    test_u_and_axis();
    test_axis_overflow();
    test_inch();
    test_rapid();
    test_stop();
    test_errors();
    test_budgets();
    test_files();
    return test_summary("traj");
}
