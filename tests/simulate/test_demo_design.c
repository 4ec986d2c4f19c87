/* test_demo_design.c: the design comparison on HyperFun designs whose
 * min/max ties fall on voxel centres, and on the demo job.
 *
 * 1. An uncut 20 x 20 x 10 mm box stock against the same box as a HyperFun
 *    design (its exact distance, written here): the box's faces lie half a
 *    voxel off the grid, so voxel centres sit on the ties of its max along
 *    the edges, where forward differences of the field were all 0 and the
 *    design read deep inside (a false 0.22 mm gouge at a corner). Expected:
 *    nothing beyond the tolerance, deviations under half a voxel.
 * 2. The demo job (deploy/demo/pocket.ngc, the README's) against the part it
 *    is meant to make, deploy/demo/part.hf (written from the drawing the
 *    program follows, not from a simulation). Expected: no gouge region and
 *    no excess region at the default tolerance (half a voxel, 0.05 mm). The
 *    largest deviation the program leaves by design is the scallop between
 *    the zigzag's row ends on the pocket's walls (6 mm cutter, rows 1 mm
 *    apart): h = 3 - sqrt(9 - 0.5^2) = 0.042 mm, under the tolerance.
 * 3. The same job cutting 1 mm too deep (G92 Z1 after the program's G54, so
 *    every programmed Z lands 1 mm lower) on a 0.2 mm grid: a comparison that
 *    found nothing would pass case 2, so here it must find the floors 1 mm
 *    under the design. By hand: the deepest gouge is 1 mm (the floors; the
 *    V groove's 45 degree faces move 1/sqrt(2) mm, the drill points' 59
 *    degree cones sin(31 deg) mm), within half a voxel; the gouged volume
 *    holds at least the floors moved down: the rectangular pocket
 *    50 x 40 less its four 3 mm corner roundings (4 * 9 (1 - pi / 4)), the
 *    circular pocket pi 12^2 and the front ledge 100 x 11, each 1 mm thick,
 *    3544 mm^3, less a voxel layer of slack on their outlines. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "core/core.h"
#include "job.h"
#include "test.h"

static char dir[256];

static int write_file(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    if (!f) return 0;
    const int ok = fputs(text, f) >= 0;
    return fclose(f) == 0 && ok;
}

static int run(const char *program, const char *tools, const char *stock, const char *design,
               double voxel, fm_job_result *r)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_path = program;
    spec.tools_path = tools;
    spec.stock_spec = stock;
    spec.stock.voxel_mm = voxel;
    spec.design_path = design;
    fm_error err;
    fm_error_clear(&err);
    if (fm_job_run(&spec, NULL, r, &err) != FM_OK) {
        fprintf(stderr, "job: %s\n", err.message);
        return 0;
    }
    return 1;
}

static void print_deviation(const char *what, const fm_job_result *r)
{
    const fm_deviation *d = &r->deviation;
    printf("%s: max gouge %.4f mm (%zu regions), max excess %.4f mm (%zu regions), tolerance "
           "%.3f mm; gouge %.3f mm3, excess %.3f mm3\n",
           what, d->max_gouge_mm, d->gouge_total, d->max_excess_mm, d->excess_total,
           d->tolerance_mm, d->gouge_volume_mm3, d->excess_volume_mm3);
    for (size_t i = 0; i < d->gouge_count && i < 5; i++)
        printf("  gouge %.4f mm at (%.3f, %.3f, %.3f)\n", d->gouges[i].depth_mm,
               d->gouges[i].position[0], d->gouges[i].position[1], d->gouges[i].position[2]);
    for (size_t i = 0; i < d->excess_count && i < 5; i++)
        printf("  excess %.4f mm at (%.3f, %.3f, %.3f)\n", d->excess[i].depth_mm,
               d->excess[i].position[0], d->excess[i].position[1], d->excess[i].position[2]);
}

static void test_box_ties(void)
{
    char program[300], tools[300], design[300];
    snprintf(program, sizeof program, "%s/nocut.ngc", dir);
    snprintf(tools, sizeof tools, "%s/tools.json", dir);
    snprintf(design, sizeof design, "%s/box.hf", dir);
    CHECK(write_file(program, "G21 G90\nT1 M6\nG0 Z10\nM30\n"));
    CHECK(write_file(tools, "{\"units\": \"mm\", \"tools\": [{\"number\": 1, \"shape\": \"flat\", "
                            "\"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}"));
    /* the exact distance to the box 0..20 x 0..20 x -10..0, positive inside */
    CHECK(write_file(design,
                     "box(x[3], a[1])\n{\n"
                     "  b1 = abs(x[1] - 10) - 10; b2 = abs(x[2] - 10) - 10; b3 = abs(x[3] + 5) - 5;\n"
                     "  box = -(sqrt(max(b1, 0)^2 + max(b2, 0)^2 + max(b3, 0)^2)"
                     " + min(max(b1, max(b2, b3)), 0));\n}\n"));
    fm_job_result r;
    if (!run(program, tools, "box:0,0,-10,20,20,0", design, 0.1, &r)) {
        CHECK(0);
        return;
    }
    CHECK(r.has_deviation);
    print_deviation("box against itself", &r);
    const double h = 0.1;
    CHECK(r.deviation.gouge_total == 0);
    CHECK(r.deviation.excess_total == 0);
    CHECK(r.deviation.max_gouge_mm < h / 2);
    CHECK(r.deviation.max_excess_mm < h / 2);
    fm_job_result_release(&r);
}

static void test_demo(void)
{
    fm_job_result r;
    if (!run("../deploy/demo/pocket.ngc", "../deploy/demo/tools.json", "box:0,0,-30,100,60,0",
             "../deploy/demo/part.hf", 0.1, &r)) {
        CHECK(0);
        return;
    }
    CHECK(r.has_deviation);
    print_deviation("demo against deploy/demo/part.hf", &r);
    const double tol = r.deviation.tolerance_mm;
    CHECK_NEAR(tol, 0.05, 1e-12);
    CHECK(r.deviation.gouge_total == 0);
    CHECK(r.deviation.max_gouge_mm <= tol);
    CHECK(r.deviation.excess_total == 0);
    CHECK(r.deviation.max_excess_mm <= tol);
    fm_job_result_release(&r);
}

static void test_demo_too_deep(void)
{
    char *text = NULL;
    size_t size = 0;
    fm_error err;
    fm_error_clear(&err);
    if (fm_file_read("../deploy/demo/pocket.ngc", "program", 1 << 20, &text, &size, &err) != FM_OK) {
        fprintf(stderr, "%s\n", err.message);
        CHECK(0);
        return;
    }
    const char *g54 = strstr(text, "G54\n");
    CHECK(g54 != NULL);
    char program[300];
    snprintf(program, sizeof program, "%s/too_deep.ngc", dir);
    FILE *f = fopen(program, "w");
    CHECK(f != NULL);
    if (!g54 || !f) {
        if (f) fclose(f);
        free(text);
        return;
    }
    const size_t head = (size_t)(g54 + 4 - text);
    CHECK(fwrite(text, 1, head, f) == head);
    CHECK(fputs("G92 Z1\n", f) >= 0);
    CHECK(fwrite(text + head, 1, size - head, f) == size - head);
    CHECK(fclose(f) == 0);
    free(text);

    const double h = 0.2;
    fm_job_result r;
    if (!run(program, "../deploy/demo/tools.json", "box:0,0,-30,100,60,0", "../deploy/demo/part.hf",
             h, &r)) {
        CHECK(0);
        return;
    }
    CHECK(r.has_deviation);
    print_deviation("demo 1 mm too deep against deploy/demo/part.hf", &r);
    const double floors = 50.0 * 40.0 - 4 * 9 * (1 - FM_PI / 4) + FM_PI * 144 + 100.0 * 11;
    /* the floors' outlines, one voxel wide, 1 mm thick */
    const double slack = (2 * (50 + 40) + 2 * FM_PI * 12 + 2 * 100 + 2 * 11) * h;
    CHECK(fabs(r.deviation.max_gouge_mm - 1.0) <= h / 2);
    CHECK(r.deviation.gouge_total >= 1);
    CHECK(r.deviation.gouge_volume_mm3 >= floors - slack);
    CHECK(r.deviation.gouge_count >= 1 && r.gouge_blame[0].line > 0);
    fm_job_result_release(&r);
}

int main(int argc, char **argv)
{
    /* --box: the first case alone */
    const int only_box = argc > 1 && !strcmp(argv[1], "--box");
    snprintf(dir, sizeof dir, "/tmp/fm-demo-design-XXXXXX");
    if (!mkdtemp(dir)) return 1;
    test_box_ties();
    if (!only_box) {
        test_demo();
        test_demo_too_deep();
    }
    char cmd[300];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0) perror("rm");
    return test_summary("simulate_demo_design");
}
