/* test_examples.c: the HyperFun examples in the pipeline. The cast stock
 * (examples/cast_stock.hf) as a stock, whose grid volume must match a
 * direct integration of the model; and the corner-rounding form cutter
 * (examples/form_cutter.hf) as a custom tool, whose plunge and slot must
 * remove the volumes its documented profile gives in closed form; the
 * 4-axis indexer example (examples/indexer_4axis.ngc on its machine) against
 * the hexagon's closed form plus its ring groove integrated here. Run from
 * tests/ (ctest does). */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frep/frep.h"
#include "hf/hf.h"
#include "job.h"
#include "runner/machine.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

/* Volume of {f >= 0} by the midpoint rule on cells of size h over a box,
 * evaluating the model's own tape in batches: independent of lib/stock. */
static double integrate_model(const char *path, const double lo[3], const double hi[3], double h)
{
    fm_graph *g = fm_graph_new(0);
    fm_hf_model model;
    fm_error err;
    if (fm_hf_compile_file(g, path, NULL, &model, &err) != FM_OK) {
        fm_graph_free(g);
        return NAN;
    }
    fm_tape *tape = fm_tape_compile(g, model.root, &err);
    fm_evaluator *ev = fm_evaluator_new(tape, &err);
    int n[3];
    for (int k = 0; k < 3; k++) n[k] = (int)ceil((hi[k] - lo[k]) / h);
    double *xs = malloc(sizeof *xs * (size_t)n[0]), *ys = malloc(sizeof *ys * (size_t)n[0]);
    double *zs = malloc(sizeof *zs * (size_t)n[0]), *out = malloc(sizeof *out * (size_t)n[0]);
    long inside = 0;
    for (int k = 0; k < n[2]; k++)
        for (int j = 0; j < n[1]; j++) {
            for (int i = 0; i < n[0]; i++) {
                xs[i] = lo[0] + (i + 0.5) * h;
                ys[i] = lo[1] + (j + 0.5) * h;
                zs[i] = lo[2] + (k + 0.5) * h;
            }
            fm_eval_batch(ev, (size_t)n[0], xs, ys, zs, NULL, out);
            for (int i = 0; i < n[0]; i++) inside += out[i] >= 0;
        }
    free(xs);
    free(ys);
    free(zs);
    free(out);
    fm_evaluator_free(ev);
    fm_tape_free(tape);
    fm_graph_free(g);
    return (double)inside * h * h * h;
}

/* The form cutter's documented profile: flat tip to r = 3, then a concave
 * quarter circle of radius 3 centred at (r 6, z 0): r(h) = 6 - sqrt(9 - h^2). */
static double form_radius(double h)
{
    return 6 - sqrt(9 - h * h);
}

static double simpson(double (*f)(double), double a, double b)
{
    const int n = 20000;
    double step = (b - a) / n, sum = 0;
    for (int i = 0; i <= n; i++) sum += (i == 0 || i == n ? 1 : i % 2 ? 4 : 2) * f(a + i * step);
    return sum * step / 3;
}

static double disk_area(double h)
{
    double r = form_radius(h);
    return FM_PI * r * r;
}

static double chord(double h)
{
    return 2 * form_radius(h);
}

/* The ring groove of indexer_4axis.ngc: a 6 mm ball whose centre stands 20
 * mm from the bar's axis at x = 80 while A turns once sweeps the disc
 * (x - 80)^2 + (r - 20)^2 <= 9 revolved about X; the material there is the
 * hexagon of inradius d, whose polar radius is d / cos(phi) with phi the
 * angle from the nearest flat's normal. Removed: the integral over x and
 * theta of r dr from the disc's inner radius to the hexagon. */
static double hex_groove_volume(double d)
{
    const int nx = 1200, nt = 7200;
    double sum = 0, dx = 6.0 / nx, dt = 2 * FM_PI / nt;
    for (int i = 0; i < nx; i++) {
        double x = -3 + (i + 0.5) * dx;
        double r_lo = 20 - sqrt(9 - x * x);
        for (int j = 0; j < nt; j++) {
            double t = (j + 0.5) * dt;
            double phi = fmod(t, FM_PI / 3) - FM_PI / 6;
            double h = d / cos(phi);
            if (h > r_lo) sum += 0.5 * (h * h - r_lo * r_lo);
        }
    }
    return sum * dx * dt;
}

static double run(const char *program, const char *stock, const fm_tool_table *tools, double voxel,
                  double *initial)
{
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "test.ngc";
    spec.stock_spec = stock;
    spec.tools = tools;
    spec.stock.voxel_mm = voxel;
    fm_job_result result;
    fm_error err;
    if (fm_job_run(&spec, NULL, &result, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "job failed: %s\n", fm_error_format(&err, buf, sizeof buf));
        return NAN;
    }
    if (initial) *initial = result.initial_volume_mm3;
    fm_stock_free(result.stock);
    return result.removed_volume_mm3;
}

int main(void)
{
    const char *flat_json = "{\"units\": \"mm\", \"tools\": [{\"number\": 1, \"shape\": \"flat\", "
                            "\"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";
    const char *form_json = "{\"units\": \"mm\", \"tools\": [{\"number\": 1, \"shape\": \"hyperfun\", "
                            "\"file\": \"../examples/form_cutter.hf\", \"bound_radius\": 6, "
                            "\"diameter\": 12, \"flute_length\": 20, \"length\": 60}]}";
    fm_tool_table flat, form;
    fm_error err;
    char buf[700];
    if (fm_tooltable_parse_json(flat_json, strlen(flat_json), "flat.json", &flat, &err) != FM_OK ||
        fm_tooltable_parse_json(form_json, strlen(form_json), "form.json", &form, &err) != FM_OK) {
        fprintf(stderr, "tool table: %s\n", fm_error_format(&err, buf, sizeof buf));
        return 1;
    }

    /* The cast stock: grid volume against the model integrated directly. */
    double lo[3] = {-1, -1, -1}, hi[3] = {101, 61, 31};
    double direct = integrate_model("../examples/cast_stock.hf", lo, hi, 0.2);
    double initial = NAN;
    /* No motion: the tool would start at the machine origin, which is on
     * the blank's corner. */
    double removed = run("G21 G90\nM2\n", "../examples/cast_stock.hf", &flat, 0.2, &initial);
    printf("cast stock: grid volume %.1f mm3, direct integration %.1f mm3\n", initial, direct);
    CHECK(fabs(initial - direct) <= 0.005 * direct);
    CHECK(removed == 0.0);

    /* The form cutter plunged 2 mm deep: the volume of revolution of its
     * profile up to h = 2; then moved 20 mm along X: plus 20 times the
     * profile's cross-section (chord 2 r(h) over h in [0, 2]). */
    double plunge = simpson(disk_area, 0, 2);
    double slot = plunge + 20 * simpson(chord, 0, 2);
    double v1 = run("G21 G90 T1 M6 S8000 M3\nG0 X50 Y30 Z5\nG1 Z-2 F200\nG0 Z5\nM2\n",
                    "box:40,20,-6,80,40,0", &form, 0.1, NULL);
    printf("form cutter plunge: removed %.3f mm3, profile %.3f mm3\n", v1, plunge);
    CHECK(fabs(v1 - plunge) <= 0.005 * plunge);
    double v2 = run("G21 G90 T1 M6 S8000 M3\nG0 X50 Y30 Z5\nG1 Z-2 F200\nG1 X70 F600\nG0 Z5\nM2\n",
                    "box:40,20,-6,80,40,0", &form, 0.1, NULL);
    printf("form cutter slot: removed %.3f mm3, profile %.3f mm3\n", v2, slot);
    CHECK(fabs(v2 - slot) <= 0.005 * slot);

    /* The 4-axis indexer example: six flats 17.32 mm from the axis of the
     * 100 mm bar of radius 20 leave a hexagon (its corners, 17.32 / cos 30
     * = 19.9994 from the axis, lie inside the bar): 100 (400 pi - 2 sqrt(3)
     * d^2) removed, plus the ring groove. */
    {
        fm_tool_table rt;
        fm_check_machine machine;
        fm_status st = fm_tooltable_load("../examples/rotary_tools.json", &rt, &err);
        int have_tools = st == FM_OK;
        if (st == FM_OK) st = fm_check_machine_load("../examples/indexer_machine.json", &machine, &err);
        CHECK(st == FM_OK);
        if (st != FM_OK) {
            if (have_tools) fm_tool_table_free(&rt);
            fprintf(stderr, "indexer example: %s\n", fm_error_format(&err, buf, sizeof buf));
        } else {
            fm_job_spec spec;
            fm_job_spec_default(&spec);
            spec.program_path = "../examples/indexer_4axis.ngc";
            spec.program_name = spec.program_path;
            spec.stock_spec = "../examples/round_bar.hf";
            spec.tools = &rt;
            spec.stock.voxel_mm = 0.2;
            spec.machine = &machine.chain;
            fm_job_result result;
            st = fm_job_run(&spec, NULL, &result, &err);
            CHECK(st == FM_OK);
            if (st != FM_OK) {
                fprintf(stderr, "indexer example: %s\n", fm_error_format(&err, buf, sizeof buf));
            } else {
                double d = 17.32;
                double groove = hex_groove_volume(d);
                double want = 100 * (400 * FM_PI - 2 * sqrt(3.0) * d * d) + groove;
                printf("indexer example: removed %.1f mm3, closed form + groove %.1f mm3 (groove %.1f)\n",
                       result.removed_volume_mm3, want, groove);
                CHECK(fabs(result.removed_volume_mm3 - want) <= 0.005 * want);
                fm_stock_free(result.stock);
            }
            fm_tool_table_free(&rt);
        }
    }

    fm_tool_table_free(&flat);
    fm_tool_table_free(&form);
    return test_summary("examples in the pipeline");
}
