/* test_design.c: the design comparison through the whole pipeline (G-code ->
 * stock -> comparison -> blame -> report), against closed forms computed here
 * from the geometry the test builds, never from the library's output.
 *
 * 1. Pocket: a 60 x 40 x 10 mm block whose design has a 40 x 20 mm pocket 5 mm
 *    deep with corners of radius 3.4 (a closed, oriented STL the test writes:
 *    32 chords per corner, vertices on the arc). A 6 mm flat end mill clears
 *    it 0.4 mm short of every wall (path inset 3.4 mm: the cut pocket is the
 *    path's rectangle grown by 3 mm, corners of radius 3), then cuts a strip
 *    0.2 mm too deep (from (20, 20) to (35, 20)) and plunges 0.5 mm too deep
 *    at (44, 20). Expected: gouges of 0.5 mm (pi 3^2 0.5 mm3) and 0.2 mm
 *    ((15 x 6 + pi 3^2) 0.2 mm3), deepest first, each blamed on a line that
 *    cut at that depth; one excess region 0.4 mm thick of (design pocket area,
 *    by the shoelace formula - cut pocket area) x 5 mm3. Depths within half a
 *    voxel, volumes within 2%.
 * 2. Scallops: a 6 mm ball end mill rasters a block 1 mm deep with a step-over
 *    of 2.5 mm; the design is the block 1 mm lower (a HyperFun model). The
 *    ridges left stand h = R - sqrt(R^2 - (s/2)^2) above the design face
 *    (within half a voxel, at 0.05 mm); their cross-section is
 *    s R - (s/2) sqrt(R^2 - s^2/4) - R^2 asin(s / 2R), and a region holds the
 *    part of it higher than the tolerance (2% each).
 * 3. --stop-at: the pocket program stopped after its clearing pass leaves no
 *    gouge, and the report says where it stopped; its stock saved as a .vdb
 *    and cut by the rest of the program ends as the whole program does.
 * 4. Deviation colours on the pocket's mesh: the strip's floor red, the
 *    walls left short blue, the top green; the picture carries the key.
 * 5. Blame on a rotary table (--rotary): an A table (around X, through the
 *    origin, no TCP) turns a block 80..100 mm from its axis by 90 degrees;
 *    the vertical 6 mm flat end mill then plunges 1.5 mm into the block's
 *    face y = 100 and cuts a slot 1 mm deep along it. The design is the
 *    block: one gouge, 1.5 mm deep (the plunge), of (10 x 6 + pi 3^2) 1 +
 *    pi 3^2 0.5 mm3, on the face, blamed on the plunge's line. The joint
 *    values of a table move are no workpiece positions: the machine's
 *    Z 130..98.5 is the workpiece's y, more than the tool's reach from its
 *    y = 0. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include <jansson.h>

#include "job.h"
#include "mesh/mesh.h"
#include "report_json.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"flat\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40},"
    "{\"number\": 2, \"shape\": \"ball\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

static fm_tool_table tools;
static char dir[256];
static const fm_machine *run_machine; /* the next run's machine (NULL: 3 axes) */

/* ------------------------------------------------------ pocket design -- */

#define CORNER_SEGMENTS 32
#define RC 3.4 /* design corner radius: tool radius 3 + 0.4 */

/* The pocket's outline, counter-clockwise seen from +z, starting at the
 * middle of its bottom edge; vertex indices of the four edge midpoints and
 * of the corner arcs' 45-degree points go to mid[] and diag[]. */
static int pocket_outline(double (*p)[2], int mid[4], int diag[4])
{
    const double cx[4] = {46.6, 46.6, 13.4, 13.4}, cy[4] = {13.4, 26.6, 26.6, 13.4};
    const double mids[4][2] = {{30, 10}, {50, 20}, {30, 30}, {10, 20}};
    int n = 0;
    for (int c = 0; c < 4; c++) {
        /* the edge before corner c (from its midpoint), then the arc */
        mid[c] = n;
        p[n][0] = mids[c][0];
        p[n][1] = mids[c][1];
        n++;
        const double a0 = -FM_PI / 2 + c * FM_PI / 2;
        for (int i = 0; i <= CORNER_SEGMENTS; i++) {
            const double a = a0 + (FM_PI / 2) * i / CORNER_SEGMENTS;
            if (i == CORNER_SEGMENTS / 2) diag[c] = n;
            p[n][0] = cx[c] + RC * cos(a);
            p[n][1] = cy[c] + RC * sin(a);
            n++;
        }
    }
    return n;
}

static double shoelace(const double (*p)[2], int n)
{
    double a = 0;
    for (int i = 0; i < n; i++) {
        const int j = (i + 1) % n;
        a += p[i][0] * p[j][1] - p[j][0] * p[i][1];
    }
    return 0.5 * a;
}

typedef struct builder {
    fm_mesh *mesh;
    fm_error err;
    int failed;
} builder;

static uint32_t vertex(builder *b, double x, double y, double z)
{
    const float p[3] = {(float)x, (float)y, (float)z};
    /* identical positions share one vertex, so that the topology check
     * sees the edges joined */
    for (size_t i = 0; i < b->mesh->vertex_count; i++)
        if (!memcmp(b->mesh->positions + 3 * i, p, sizeof p)) return (uint32_t)i;
    size_t v = fm_mesh_add_vertex(b->mesh, p, NULL, NULL, &b->err);
    if (v == (size_t)-1) b->failed = 1;
    return (uint32_t)v;
}

/* A triangle turned so that its normal points along out. */
static void triangle(builder *b, uint32_t i, uint32_t j, uint32_t k, const double out[3])
{
    const float *p = b->mesh->positions;
    double u[3], v[3];
    for (int a = 0; a < 3; a++) {
        u[a] = p[3 * j + a] - p[3 * i + a];
        v[a] = p[3 * k + a] - p[3 * i + a];
    }
    const double n[3] = {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2],
                         u[0] * v[1] - u[1] * v[0]};
    if (n[0] * out[0] + n[1] * out[1] + n[2] * out[2] < 0) {
        const uint32_t t = j;
        j = k;
        k = t;
    }
    if (fm_mesh_add_triangle(b->mesh, i, j, k, &b->err) == (size_t)-1) b->failed = 1;
}

static void quad(builder *b, uint32_t a, uint32_t c, uint32_t d, uint32_t e, const double out[3])
{
    triangle(b, a, c, d, out);
    triangle(b, a, d, e, out);
}

/* The design part as a closed, oriented mesh written to path; its pocket
 * area (shoelace) goes to *area. */
static int write_pocket_design(const char *path, double *area)
{
    double p[4 * (CORNER_SEGMENTS + 2)][2];
    int mid[4], diag[4];
    const int n = pocket_outline(p, mid, diag);
    *area = shoelace((const double(*)[2])p, n);
    builder b = {0};
    b.mesh = fm_mesh_new(0, 0, 0, NULL, &b.err);
    if (!b.mesh) return 0;
    const double X = 60, Y = 40, Z0 = -10, ZF = -5;
    const double up[3] = {0, 0, 1}, down[3] = {0, 0, -1};
    uint32_t top[4 * (CORNER_SEGMENTS + 2)], floor_[4 * (CORNER_SEGMENTS + 2)];
    for (int i = 0; i < n; i++) {
        top[i] = vertex(&b, p[i][0], p[i][1], 0);
        floor_[i] = vertex(&b, p[i][0], p[i][1], ZF);
    }
    /* block corners, counter-clockwise from (0, 0), and their bottoms */
    const double cx[4] = {0, X, X, 0}, cy[4] = {0, 0, Y, Y};
    uint32_t ct[4], cb[4];
    for (int c = 0; c < 4; c++) {
        ct[c] = vertex(&b, cx[c], cy[c], 0);
        cb[c] = vertex(&b, cx[c], cy[c], Z0);
    }
    /* top face: four quadrants between block corners c and c+1 and the
     * outline from diag[c-1] through mid[c] to diag[c] */
    for (int c = 0; c < 4; c++) {
        const int first = diag[(c + 3) % 4], last = diag[c];
        const uint32_t A = ct[c], B = ct[(c + 1) % 4];
        for (int i = first; i != mid[c]; i = (i + 1) % n)
            triangle(&b, A, top[i], top[(i + 1) % n], up);
        for (int i = mid[c]; i != last; i = (i + 1) % n)
            triangle(&b, B, top[i], top[(i + 1) % n], up);
        triangle(&b, A, B, top[mid[c]], up);
    }
    /* pocket walls (outward: into the pocket, left of the outline) and floor */
    double fx = 0, fy = 0;
    for (int i = 0; i < n; i++) {
        const int j = (i + 1) % n;
        const double out[3] = {-(p[j][1] - p[i][1]), p[j][0] - p[i][0], 0};
        quad(&b, top[i], top[j], floor_[j], floor_[i], out);
        fx += p[i][0] / n;
        fy += p[i][1] / n;
    }
    const uint32_t centre = vertex(&b, fx, fy, ZF);
    for (int i = 0; i < n; i++) triangle(&b, centre, floor_[i], floor_[(i + 1) % n], up);
    /* block sides and bottom */
    for (int c = 0; c < 4; c++) {
        const int d = (c + 1) % 4;
        const double out[3] = {cy[d] - cy[c], -(cx[d] - cx[c]), 0};
        quad(&b, ct[c], ct[d], cb[d], cb[c], out);
    }
    quad(&b, cb[0], cb[1], cb[2], cb[3], down);

    int ok = !b.failed;
    fm_mesh_topology topo;
    if (ok && fm_mesh_topology_check(b.mesh, &topo, &b.err) == FM_OK) {
        CHECK(topo.boundary_edges == 0 && topo.nonmanifold_edges == 0 &&
              topo.misoriented_edges == 0 && topo.degenerate_triangles == 0);
        /* outward and closed: it encloses the block less the pocket */
        CHECK_NEAR(fm_mesh_volume(b.mesh), X * Y * (0 - Z0) - *area * (0 - ZF), 1e-3);
    } else {
        ok = 0;
    }
    if (ok && fm_mesh_write_stl(b.mesh, path, &b.err) != FM_OK) ok = 0;
    if (!ok) fprintf(stderr, "pocket design: %s\n", b.err.message);
    fm_mesh_free(b.mesh);
    return ok;
}

/* ---------------------------------------------------------------- run -- */

static int run(const char *program, const char *stock, const char *design, double voxel,
               double tolerance, int stop_at, fm_job_result *r)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "design.ngc";
    spec.stock_spec = stock;
    spec.tools = &tools;
    spec.stock.voxel_mm = voxel;
    spec.design_path = design;
    spec.tolerance_mm = tolerance;
    spec.stop_at_line = stop_at;
    spec.machine = run_machine;
    fm_error err;
    if (fm_job_run(&spec, NULL, r, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "job failed: %s\n", fm_error_format(&err, buf, sizeof buf));
        return 0;
    }
    return 1;
}

/* The pocket program; line numbers below are its lines. */
static const char *pocket_program =
    "G21 G90 G17\n"               /* 1 */
    "T1 M6\n"                     /* 2 */
    "S10000 M3\n"                 /* 3 */
    "G0 X13.4 Y13.4 Z5\n"         /* 4 */
    "G1 Z-5 F300\n"               /* 5 */
    "G1 X46.6 F1000\n"            /* 6 */
    "G1 Y17.8\n"                  /* 7 */
    "G1 X13.4\n"                  /* 8 */
    "G1 Y22.2\n"                  /* 9 */
    "G1 X46.6\n"                  /* 10 */
    "G1 Y26.6\n"                  /* 11 */
    "G1 X13.4\n"                  /* 12 */
    "G1 Y13.4\n"                  /* 13 */
    "G1 X46.6\n"                  /* 14 */
    "G1 Y26.6\n"                  /* 15 */
    "G0 Z5\n"                     /* 16 */
    "(a strip 0.2 mm too deep)\n" /* 17 */
    "G0 X20 Y20\n"                /* 18 */
    "G1 Z-5.2 F300\n"             /* 19 */
    "G1 X35 F1000\n"              /* 20 */
    "G0 Z5\n"                     /* 21 */
    "(a plunge 0.5 mm too deep)\n" /* 22 */
    "G0 X44 Y20\n"                /* 23 */
    "G1 Z-5.5 F300\n"             /* 24 */
    "G0 Z5\n"                     /* 25 */
    "M5 M30\n";                   /* 26 */

/* Vertices of the pocket's mesh whose place is unambiguous get the colour
 * their deviation asks for: on the strip's floor (gouge 0.2 mm) red, on the
 * cut pocket's long walls (excess 0.4 mm) blue, on the block's top away
 * from the pocket green. The key is in the picture's corner. */
static void check_colors(fm_job_result *r, double tol)
{
    fm_mesh_extract_options eo;
    fm_mesh_extract_default(&eo);
    eo.coloring = FM_MESH_COLOR_DEVIATION;
    eo.design = r->design;
    fm_error err;
    fm_mesh *m = fm_mesh_from_stock(r->stock, &eo, &err);
    CHECK(m != NULL);
    if (!m) return;
    uint8_t red[3], blue[3], green[3];
    fm_mesh_deviation_color(-0.2, tol, 10 * tol, red);
    fm_mesh_deviation_color(0.4, tol, 10 * tol, blue);
    fm_mesh_deviation_color(0, tol, 10 * tol, green);
    CHECK(red[0] > red[2] && blue[2] > blue[0] && green[1] > green[0] && green[1] > green[2]);
    size_t n[3] = {0, 0, 0}, wrong = 0;
    for (size_t i = 0; i < m->vertex_count; i++) {
        const float *p = m->positions + 3 * i;
        const uint8_t *c = m->colors + 3 * i;
        const uint8_t *want = NULL;
        int k = -1;
        if (fabs(p[2] + 5.2) < 0.02 && p[0] > 21 && p[0] < 34 && fabs(p[1] - 20) < 2)
            want = red, k = 0;
        else if ((fabs(p[1] - 10.4) < 0.02 || fabs(p[1] - 29.6) < 0.02) && p[0] > 15 &&
                 p[0] < 45 && p[2] < -0.5 && p[2] > -4.5)
            want = blue, k = 1;
        else if (fabs(p[2]) < 0.02 && (p[0] < 8 || p[0] > 52) && p[1] > 2 && p[1] < 38)
            want = green, k = 2;
        if (!want) continue;
        n[k]++;
        if (memcmp(c, want, 3)) wrong++;
    }
    printf("deviation colours: %zu red, %zu blue, %zu green vertices judged, %zu wrong\n", n[0],
           n[1], n[2], wrong);
    CHECK(n[0] > 100 && n[1] > 100 && n[2] > 100);
    CHECK(wrong == 0);
    fm_render_options ro;
    fm_render_default(&ro);
    fm_render_legend key;
    fm_mesh_deviation_legend(tol, 10 * tol, &key);
    ro.legend = &key;
    CHECK(key.count == 7 && !strcmp(key.labels[0], "+0.50") && !strcmp(key.labels[2], "+0.05") &&
          !strcmp(key.labels[3], "0") && !strcmp(key.labels[6], "-0.50"));
    uint8_t *rgb = malloc((size_t)ro.width * ro.height * 3);
    if (rgb && fm_render_rgb(m, &ro, rgb, &err) == FM_OK) {
        /* each swatch's middle pixel has its colour (layout in render.c:
         * panel at 6, 6; swatches from y = 12 + 18 (i + 1), x = 12..44) */
        int ok = 1;
        for (size_t i = 0; i < key.count; i++) {
            const int x = 20, y = 12 + 18 * (int)(i + 1) + 8;
            ok &= !memcmp(rgb + 3 * ((size_t)y * ro.width + x), key.colors[i], 3);
        }
        CHECK(ok);
    } else {
        CHECK(0);
    }
    free(rgb);
    fm_mesh_free(m);
}

static void test_pocket(void)
{
    const double h = 0.1, tol = 0.05;
    char design[512];
    snprintf(design, sizeof design, "%s/pocket.stl", dir);
    double a_design;
    if (!write_pocket_design(design, &a_design)) {
        CHECK(0);
        return;
    }
    /* the cut pocket: the path's rectangle 33.2 x 13.2 grown by r = 3 */
    const double a_cut = (33.2 + 6) * (13.2 + 6) - (4 - FM_PI) * 9;
    const double v_excess = (a_design - a_cut) * 5;
    const double v_strip = (15 * 6 + FM_PI * 9) * 0.2, v_plunge = FM_PI * 9 * 0.5;
    fm_job_result r;
    if (!run(pocket_program, "box:0,0,-10,60,40,0", design, h, tol, 0, &r)) {
        CHECK(0);
        return;
    }
    CHECK(r.has_deviation);
    const fm_deviation *d = &r.deviation;
    printf("pocket: %zu gouges, max %.4f mm (0.5), %.3f mm3 (%.3f); %zu excess, max %.4f mm (0.4), "
           "%.3f mm3 (%.3f); compared in %.2f s wall, %.2f s CPU (job %.2f s)\n",
           d->gouge_total, d->max_gouge_mm, d->gouge_volume_mm3, v_strip + v_plunge,
           d->excess_total, d->max_excess_mm, d->excess_volume_mm3, v_excess, r.design_wall_s,
           r.design_cpu_s, r.wall_time_s);
    CHECK_NEAR(d->tolerance_mm, tol, 1e-12);
    CHECK(d->gouge_total == 2);
    CHECK(d->excess_total == 1);
    CHECK_NEAR(d->max_gouge_mm, 0.5, h / 2);
    CHECK_NEAR(d->max_excess_mm, 0.4, h / 2);
    CHECK_NEAR(d->gouge_volume_mm3, v_strip + v_plunge, 0.02 * (v_strip + v_plunge));
    CHECK_NEAR(d->excess_volume_mm3, v_excess, 0.02 * v_excess);
    if (d->gouge_count == 2) {
        const fm_deviation_region *g0 = &d->gouges[0], *g1 = &d->gouges[1];
        for (int i = 0; i < 2; i++)
            printf("  gouge %.4f mm, %.3f mm3 at (%.2f, %.2f, %.2f): line %d tool %d\n",
                   d->gouges[i].depth_mm, d->gouges[i].volume_mm3, d->gouges[i].position[0],
                   d->gouges[i].position[1], d->gouges[i].position[2], r.gouge_blame[i].line,
                   r.gouge_blame[i].tool);
        CHECK_NEAR(g0->depth_mm, 0.5, h / 2);
        CHECK_NEAR(g0->volume_mm3, v_plunge, 0.02 * v_plunge);
        CHECK(hypot(g0->position[0] - 44, g0->position[1] - 20) <= 3 + h);
        CHECK_NEAR(g0->position[2], -5.5, h / 2);
        /* only line 24 reaches 0.5 mm below the floor there */
        CHECK(r.gouge_blame[0].line == 24 && r.gouge_blame[0].tool == 1);
        CHECK_NEAR(g1->depth_mm, 0.2, h / 2);
        CHECK_NEAR(g1->volume_mm3, v_strip, 0.02 * v_strip);
        CHECK_NEAR(g1->position[2], -5.2, h / 2);
        /* the strip's plunge (19) and its feed (20) cut at -5.2 */
        CHECK((r.gouge_blame[1].line == 19 || r.gouge_blame[1].line == 20) &&
              r.gouge_blame[1].tool == 1);
        /* line 19 cuts only its own disc: a point of the strip beyond it
         * must be blamed on line 20 */
        if (g1->position[0] > 23 + h) CHECK(r.gouge_blame[1].line == 20);
    }
    if (d->excess_count == 1) {
        const fm_deviation_region *e = &d->excess[0];
        printf("  excess %.4f mm, %.3f mm3 at (%.2f, %.2f, %.2f)\n", e->depth_mm, e->volume_mm3,
               e->position[0], e->position[1], e->position[2]);
        CHECK_NEAR(e->depth_mm, 0.4, h / 2);
        CHECK_NEAR(e->volume_mm3, v_excess, 0.02 * v_excess);
        /* on a wall of the cut pocket */
        const double x = e->position[0], y = e->position[1];
        CHECK(fabs(x - 10.4) < h || fabs(x - 49.6) < h || fabs(y - 10.4) < h ||
              fabs(y - 29.6) < h || hypot(fabs(x - 30) - 16.6, fabs(y - 20) - 6.6) > 2.9);
    }

    /* the report carries the same figures */
    json_t *rep = fm_job_report_json(&r);
    json_t *dj = json_object_get(rep, "design");
    CHECK(json_is_object(dj));
    CHECK_NEAR(json_number_value(json_object_get(dj, "max_gouge_mm")), d->max_gouge_mm, 1e-9);
    CHECK_NEAR(json_number_value(json_object_get(dj, "tolerance_mm")), tol, 1e-12);
    json_t *gouges = json_object_get(dj, "gouges");
    CHECK(json_array_size(gouges) == d->gouge_count);
    json_t *g0 = json_array_get(gouges, 0);
    CHECK(json_integer_value(json_object_get(g0, "line")) == r.gouge_blame[0].line);
    CHECK(json_integer_value(json_object_get(g0, "tool")) == 1);
    CHECK(json_array_size(json_object_get(g0, "position")) == 3);
    json_t *e0 = json_array_get(json_object_get(dj, "excess"), 0);
    CHECK(json_is_object(e0) && !json_object_get(e0, "line"));
    CHECK(json_number_value(json_object_get(e0, "volume_mm3")) > 0);
    json_decref(rep);
    check_colors(&r, tol);
    const double final_whole = r.final_volume_mm3;
    fm_job_result_release(&r);

    /* stopped after the clearing pass (line 15): the walls' excess, no gouge */
    if (!run(pocket_program, "box:0,0,-10,60,40,0", design, h, tol, 15, &r)) {
        CHECK(0);
        return;
    }
    printf("pocket stopped at line 15: %zu gouges (max %.4f mm), %zu excess (max %.4f mm), "
           "%ld motions\n",
           r.deviation.gouge_total, r.deviation.max_gouge_mm, r.deviation.excess_total,
           r.deviation.max_excess_mm, r.motions);
    CHECK(r.stopped_at_line == 15 && !r.stopped);
    CHECK(r.deviation.gouge_total == 0);
    CHECK(r.deviation.max_gouge_mm < h / 2);
    CHECK(r.deviation.excess_total == 1);
    CHECK_NEAR(r.deviation.max_excess_mm, 0.4, h / 2);
    rep = fm_job_report_json(&r);
    CHECK(json_integer_value(json_object_get(rep, "stopped_at_line")) == 15);
    json_decref(rep);
    /* the in-process stock, cut by the rest of the program (lines 16 on) */
    char saved[512];
    snprintf(saved, sizeof saved, "%s/after15.vdb", dir);
    fm_error err;
    CHECK(fm_stock_save(r.stock, saved, NULL, &err) == FM_OK);
    fm_job_result_release(&r);
    const char *rest = strstr(pocket_program, "G0 Z5\n(a strip");
    char program[2048];
    snprintf(program, sizeof program, "G21 G90 G17\nT1 M6\nS10000 M3\n%s", rest ? rest : "");
    if (!run(program, saved, design, h, tol, 0, &r)) {
        CHECK(0);
        return;
    }
    printf("rest of the program on the saved stock: final %.3f mm3 (whole program %.3f), %zu gouges\n",
           r.final_volume_mm3, final_whole, r.deviation.gouge_total);
    CHECK_NEAR(r.final_volume_mm3, final_whole, 1e-6 * final_whole);
    CHECK(r.deviation.gouge_total == 2);
    fm_job_result_release(&r);
}

/* ------------------------------------------------------------ scallops -- */

static void test_scallops(void)
{
    const double h = 0.05, tol = 0.02, R = 3, s = 2.5, z0 = -1;
    const double scallop = R - sqrt(R * R - s * s / 4);
    /* F(u): the area between the design face and the groove's circle from
     * the groove's centre out to u; a ridge is two half grooves */
#define F(u) (R * (u) - 0.5 * (u) * sqrt(R * R - (u) * (u)) - 0.5 * R * R * asin((u) / R))
    const double section = 2 * F(s / 2);
    /* a region is the part beyond the tolerance: where the groove's circle
     * is more than tol above the face, u > sqrt(R^2 - (R - tol)^2) */
    const double u_tol = sqrt(R * R - (R - tol) * (R - tol));
    const double region_section = 2 * (F(s / 2) - F(u_tol));
#undef F
    /* passes at y = 0, 2.5, ..., 20 over a 30 x 20 block: 8 ridges, 30 long */
    char program[4096];
    int n = snprintf(program, sizeof program, "G21 G90 G17\nT2 M6\nS10000 M3\nG0 X-5 Y0 Z5\n");
    for (int k = 0; k <= 8; k++) {
        const double y = k * s;
        n += snprintf(program + n, sizeof program - (size_t)n,
                      "G0 X%s Y%.4f\nG1 Z%.4f F500\nG1 X%s F1500\nG0 Z5\n", k % 2 ? "35" : "-5",
                      y, z0, k % 2 ? "-5" : "35");
    }
    snprintf(program + n, sizeof program - (size_t)n, "M5 M30\n");
    char design[512];
    snprintf(design, sizeof design, "%s/flat.hf", dir);
    FILE *f = fopen(design, "w");
    /* the block 1 mm lower, as a HyperFun model */
    fprintf(f, "flat(x[3], a[1])\n{\n  array corner[3];\n  corner = [0, 0, -10];\n"
               "  flat = hfBlock(x, corner, 30, 20, %g);\n}\n",
            z0 + 10);
    fclose(f);
    fm_job_result r;
    if (!run(program, "box:0,0,-10,30,20,0", design, h, tol, 0, &r)) {
        CHECK(0);
        return;
    }
    const fm_deviation *d = &r.deviation;
    const double v = 8 * section * 30;
    printf("scallops: h = %.4f mm expected; %zu excess regions, max %.4f mm, %.3f mm3 (%.3f); "
           "max gouge %.4f mm\n",
           scallop, d->excess_total, d->max_excess_mm, d->excess_volume_mm3, v, d->max_gouge_mm);
    for (size_t i = 0; i < d->gouge_count; i++)
        printf("  gouge %.4f mm %.4f mm3 %zu voxels at (%.3f, %.3f, %.3f)\n", d->gouges[i].depth_mm,
               d->gouges[i].volume_mm3, d->gouges[i].voxels, d->gouges[i].position[0],
               d->gouges[i].position[1], d->gouges[i].position[2]);
    printf("  job %.2f s wall, comparison %.2f s wall %.2f s CPU\n", r.wall_time_s, r.design_wall_s,
           r.design_cpu_s);
    CHECK(d->excess_total == 8);
    CHECK_NEAR(d->max_excess_mm, scallop, h / 2);
    CHECK(d->max_gouge_mm < h / 2);
    CHECK(d->gouge_total == 0);
    CHECK_NEAR(d->excess_volume_mm3, v, 0.02 * v);
    for (size_t i = 0; i < d->excess_count; i++) {
        const fm_deviation_region *e = &d->excess[i];
        CHECK_NEAR(e->depth_mm, scallop, h / 2);
        CHECK_NEAR(e->volume_mm3, region_section * 30, 0.02 * region_section * 30);
        /* on a ridge: halfway between two passes, at the scallop's top */
        const double k = e->position[1] / s - 0.5;
        CHECK(fabs(k - round(k)) * s < 2 * h);
        CHECK_NEAR(e->position[2], z0 + scallop, h);
    }
    fm_job_result_release(&r);
}

/* ------------------------------------------------------ rotary blame -- */

/* The box lo..hi as a closed, oriented STL at path. */
static int write_box_design(const char *path, const double lo[3], const double hi[3])
{
    builder b = {0};
    b.mesh = fm_mesh_new(0, 0, 0, NULL, &b.err);
    if (!b.mesh) return 0;
    uint32_t v[8];
    for (int i = 0; i < 8; i++)
        v[i] = vertex(&b, (i & 1) ? hi[0] : lo[0], (i & 2) ? hi[1] : lo[1], (i & 4) ? hi[2] : lo[2]);
    const double nx[3] = {-1, 0, 0}, px[3] = {1, 0, 0}, ny[3] = {0, -1, 0}, py[3] = {0, 1, 0},
                 nz[3] = {0, 0, -1}, pz[3] = {0, 0, 1};
    quad(&b, v[0], v[2], v[6], v[4], nx);
    quad(&b, v[1], v[3], v[7], v[5], px);
    quad(&b, v[0], v[1], v[5], v[4], ny);
    quad(&b, v[2], v[3], v[7], v[6], py);
    quad(&b, v[0], v[1], v[3], v[2], nz);
    quad(&b, v[4], v[5], v[7], v[6], pz);
    int ok = !b.failed;
    fm_mesh_topology topo;
    if (ok && fm_mesh_topology_check(b.mesh, &topo, &b.err) == FM_OK) {
        CHECK(topo.boundary_edges == 0 && topo.misoriented_edges == 0);
        CHECK_NEAR(fm_mesh_volume(b.mesh), (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]), 1e-3);
    } else {
        ok = 0;
    }
    if (ok && fm_mesh_write_stl(b.mesh, path, &b.err) != FM_OK) ok = 0;
    if (!ok) fprintf(stderr, "box design: %s\n", b.err.message);
    fm_mesh_free(b.mesh);
    return ok;
}

/* Lines: 5 plunges 1.5 mm deep, 6 rises to 1 mm, 7 cuts the slot. A turned
 * by a puts the machine's point X at Rx(-a) X on the workpiece: at 90
 * degrees (x, y, z) -> (x, z, -y), so Z99 is the workpiece's y = 99, and
 * the tool's axis (machine +Z) is the workpiece's +y, normal to the face. */
static const char *rotary_program = "G21 G90 G94\n"
                                    "T1 M6\n"
                                    "G0 X20 Y0 Z130\n"
                                    "G0 A90\n"
                                    "G1 Z98.5 F300\n"
                                    "G1 Z99\n"
                                    "G1 X30 F600\n"
                                    "G0 Z130\n"
                                    "M2\n";

static void test_rotary_blame(void)
{
    const double lo[3] = {0, 80, -10}, hi[3] = {40, 100, 10};
    char design[300];
    snprintf(design, sizeof design, "%s/block.stl", dir);
    if (!write_box_design(design, lo, hi)) {
        CHECK(0);
        return;
    }
    fm_machine mc;
    memset(&mc, 0, sizeof mc);
    mc.rotary_count = 1;
    mc.rotary[0].letter = 0;
    mc.rotary[0].carries = FM_ROTARY_TABLE;
    mc.rotary[0].around[0] = 1;
    const double h = 0.2;
    fm_job_result r;
    run_machine = &mc;
    const int ran = run(rotary_program, "box:0,80,-10,40,100,10", design, h, 0, 0, &r);
    run_machine = NULL;
    CHECK(ran);
    if (!ran) return;
    const double disk = FM_PI * 9;
    const double v_expect = (10 * 6 + disk) * 1 + disk * 0.5;
    const fm_deviation *d = &r.deviation;
    printf("rotary blame: %zu gouges (max %.4f mm, %.3f mm3; expected 1.5 mm, %.3f mm3), "
           "%zu excess (max %.4f mm)\n",
           d->gouge_total, d->max_gouge_mm, d->gouge_volume_mm3, v_expect, d->excess_total,
           d->max_excess_mm);
    CHECK(r.has_deviation);
    CHECK(d->gouge_total == 1);
    CHECK(d->excess_total == 0);
    CHECK_NEAR(d->max_gouge_mm, 1.5, h / 2);
    CHECK_NEAR(d->gouge_volume_mm3, v_expect, 0.02 * v_expect);
    if (d->gouge_count == 1) {
        const fm_deviation_region *g = &d->gouges[0];
        printf("  gouge %.4f mm %.3f mm3 at (%.2f, %.2f, %.2f), line %d tool %d\n", g->depth_mm,
               g->volume_mm3, g->position[0], g->position[1], g->position[2], r.gouge_blame[0].line,
               r.gouge_blame[0].tool);
        CHECK_NEAR(g->depth_mm, 1.5, h / 2);
        /* on the plunge's floor: y = 98.5, within its disk about (20, 0) */
        CHECK_NEAR(g->position[1], 98.5, h);
        CHECK(hypot(g->position[0] - 20, g->position[2]) <= 3 + h);
        CHECK(r.gouge_blame[0].line == 5);
        CHECK(r.gouge_blame[0].tool == 1);
    }
    fm_job_result_release(&r);
}

int main(int argc, char **argv)
{
    /* --pocket, --scallops or --rotary: one case alone (profiling) */
    const int only_scallops = argc > 1 && !strcmp(argv[1], "--scallops");
    const int only_pocket = argc > 1 && !strcmp(argv[1], "--pocket");
    const int only_rotary = argc > 1 && !strcmp(argv[1], "--rotary");
    fm_error err;
    if (fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) != FM_OK) {
        fprintf(stderr, "tools: %s\n", err.message);
        return 1;
    }
    snprintf(dir, sizeof dir, "/tmp/fm-design-XXXXXX");
    if (!mkdtemp(dir)) return 1;
    if (!only_scallops && !only_rotary) test_pocket();
    if (!only_pocket && !only_rotary) test_scallops();
    if (!only_pocket && !only_scallops) test_rotary_blame();
    fm_tool_table_free(&tools);
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0) perror("rm");
    return test_summary("simulate_design");
}
