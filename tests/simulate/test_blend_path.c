/* test_blend_path: where the tool really goes (docs/plan.md, "Where the
 * tool goes"). A slot with a 90 degree corner at G64 P2, cut by a 6 mm
 * flat end mill 2 mm deep, with the machine's dynamics: the runner cuts
 * along LinuxCNC's blend arc, whose radius follows docs/plan.md's formulas
 * by hand, so material is left at the slot's outer corner and the inner
 * corner is rounded. Checked against closed forms: the arc the runner cuts
 * (radius, centre, ends), the removed volume's difference from the sharp
 * corner (two annulus/box areas times the depth), and the stock probed on
 * either side of the corner; with "follow_blends" off, and without
 * dynamics, the programmed corner is cut. */
#include <math.h>
#include <stdio.h>
#include <string.h>

#include "job.h"
#include "runner/dynamics.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"flat\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

/* In from the left, below the stock's top, along X to the corner at the
 * origin, up Y and out: the corner is a left turn. The plunge's own
 * blend lies outside the stock (x < -32). */
static const char *program = "G21 G90 G17 G64 P2\n"
                             "T1 M6\n"
                             "G0 X-40 Y0 Z5\n"
                             "S10000 M3\n"
                             "G1 Z-2 F1200\n"
                             "G1 X0\n"
                             "G1 Y40\n"
                             "G0 Z5\n"
                             "M2\n";
static const char *stock = "box:-30,-10,-5,10,30,0";
static const double depth = 2.0; /* the tool's radius is 3 mm */

typedef struct arcs_seen {
    int count;
    fm_motion arc;
    int in_stock_corner;
    /* the progress reports: where the tool was, where a resume would start */
    int reports;
    double where[16][3];
    long resume_from[16];
} arcs_seen;

static int record_progress(void *user, const fm_job_progress *p)
{
    arcs_seen *a = user;
    if (a->reports < 16) {
        memcpy(a->where[a->reports], p->position, sizeof a->where[0]);
        a->resume_from[a->reports] = p->resume_from;
    }
    a->reports++;
    return 0;
}

static void record_arc(void *user, const fm_motion *m)
{
    arcs_seen *a = user;
    if (m->kind != FM_MOTION_ARC) return;
    a->count++;
    /* the corner's arc: the one in the XY plane near the origin */
    if (m->plane_axis == 2 && fabs(m->start[1]) < 1e-9 && m->start[0] > -10.0) {
        a->arc = *m;
        a->in_stock_corner++;
    }
}

typedef struct run_out {
    double removed;
    double outer, inner; /* the stock's signed distance at the probes (> 0: material) */
} run_out;

static run_out run(const fm_plan_machine *dyn, arcs_seen *arcs, double batch_diameters)
{
    static fm_tool_table tools;
    static int loaded;
    fm_error err;
    if (!loaded) {
        CHECK(fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) == FM_OK);
        loaded = 1;
    }
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "corner.ngc";
    spec.stock_spec = stock;
    spec.tools = &tools;
    spec.stock.voxel_mm = 0.1;
    spec.dynamics = dyn;
    spec.batch_diameters = batch_diameters;
    fm_job_hooks hooks = {.user = arcs, .on_motion = record_arc, .progress = record_progress};
    fm_job_result result;
    run_out out = {NAN, NAN, NAN};
    if (fm_job_run(&spec, &hooks, &result, &err) != FM_OK) {
        char buf[700];
        fprintf(stderr, "job failed: %s\n", fm_error_format(&err, buf, sizeof buf));
        CHECK(0);
        return out;
    }
    out.removed = result.removed_volume_mm3;
    /* beyond the outer corner: 2.12 mm from the programmed corner (cut by
     * the sharp path), 8.95 mm from the blend arc's centre (R + 3 = 7.83:
     * left by the blend); inside the inner corner: beyond both walls of
     * the sharp slot, 2.16 mm from the arc's centre (R - 3 = 1.83: cut) */
    const double outer[3] = {1.5, -1.5, -1.0}, inner[3] = {-3.3, 3.3, -1.0};
    out.outer = fm_stock_sample(result.stock, outer);
    out.inner = fm_stock_sample(result.stock, inner);
    fm_job_result_release(&result);
    return out;
}

int main(void)
{
    fm_plan_machine dyn;
    fm_plan_machine_default(&dyn);
    dyn.given = 1;
    for (int i = 0; i < 3; i++) {
        dyn.linear[i].max_velocity = 100.0;
        dyn.linear[i].max_acceleration = 50.0;
    }
    /* docs/plan.md's blend arc by hand: theta = 45 degrees (half the angle
     * between the directions), T = P = 2 (a quarter of either 40 mm line
     * is more), d = cos(theta) T / (1 - sin(theta)) = 4.8284 mm (half a
     * line is more), R_geom = tan(theta) d; the normal acceleration allows
     * sqrt(0.866 * 50 * R_geom) = 14.46 mm/s, below the feed's 20 mm/s, so
     * the radius v^2 / (0.866 a) is R_geom itself. */
    const double th = FM_PI / 4.0, T = 2.0;
    const double d = cos(th) * T / (1.0 - sin(th));
    const double R = tan(th) * d;
    CHECK(sqrt(sqrt(3.0) / 2.0 * 50.0 * R) < 1200.0 / 60.0);
    CHECK_NEAR(R, 4.828427, 1e-6);

    arcs_seen blended = {0};
    run_out b = run(&dyn, &blended, 1.0);
    CHECK(blended.in_stock_corner == 1);
    CHECK(blended.count == 2); /* the corner's, and the plunge's in the air (XZ) */
    const fm_motion *arc = &blended.arc;
    double r0 = hypot(arc->start[0] - arc->center[0], arc->start[1] - arc->center[1]);
    double r1 = hypot(arc->end[0] - arc->center[0], arc->end[1] - arc->center[1]);
    printf("blend arc: R %.9f (by hand %.9f), centre (%.6f, %.6f), from (%.6f, %.6f) to (%.6f, %.6f)\n",
           r0, R, arc->center[0], arc->center[1], arc->start[0], arc->start[1], arc->end[0], arc->end[1]);
    CHECK_NEAR(r0, R, 1e-9);
    CHECK_NEAR(r1, R, 1e-9);
    CHECK_NEAR(arc->center[0], -R, 1e-9);
    CHECK_NEAR(arc->center[1], R, 1e-9);
    CHECK_NEAR(arc->start[0], -d, 1e-9);
    CHECK_NEAR(arc->end[0], 0.0, 1e-9);
    CHECK_NEAR(arc->end[1], d, 1e-9);
    CHECK_NEAR(arc->start[2], -2.0, 1e-12);
    CHECK(arc->turns == 1); /* a left turn: counter-clockwise (G3) */
    CHECK(arc->line == 6);  /* the motion before the corner's */

    /* The programmed corner: with follow_blends off (read from the
     * dynamics' JSON as a machine file gives it), and without dynamics */
    fm_plan_machine off;
    fm_error jerr;
    json_t *doc = json_loads("{\"follow_blends\": false, \"axes\": {"
                             "\"x\": {\"max_velocity\": 100, \"max_acceleration\": 50},"
                             "\"y\": {\"max_velocity\": 100, \"max_acceleration\": 50},"
                             "\"z\": {\"max_velocity\": 100, \"max_acceleration\": 50}}}",
                             0, NULL);
    CHECK(doc && fm_plan_machine_from_json(doc, "m.json", &off, &jerr) == FM_OK);
    CHECK(off.given && off.programmed_path == 1);
    json_decref(doc);
    fm_plan_machine bad;
    doc = json_loads("{\"follow_blends\": 1}", 0, NULL);
    CHECK(fm_plan_machine_from_json(doc, "m.json", &bad, &jerr) == FM_ERR_INPUT);
    CHECK(strstr(jerr.message, "follow_blends") != NULL);
    json_decref(doc);
    arcs_seen none = {0};
    run_out s = run(&off, &none, 1.0);
    CHECK(none.count == 0);
    arcs_seen none2 = {0};
    run_out f = run(NULL, &none2, 1.0);
    CHECK(none2.count == 0);
    CHECK_NEAR(s.removed, f.removed, 1e-9);

    /* Outside the box [-R, 3] x [-3, R] both paths sweep the same slot.
     * Inside it the blend sweeps a quarter annulus of radii R -+ 3 about
     * (-R, R): 3 pi R; the sharp corner the box less its outer corner
     * square beyond the quarter disc of radius 3, and less the inner
     * square [-R, -3] x [3, R]: (R + 3)^2 - (9 - 9 pi / 4) - (R - 3)^2. */
    double area_blend = FM_PI * ((R + 3) * (R + 3) - (R - 3) * (R - 3)) / 4.0;
    double area_sharp = (R + 3) * (R + 3) - (9.0 - 9.0 * FM_PI / 4.0) - (R - 3) * (R - 3);
    double expected = depth * (area_sharp - area_blend);
    printf("removed: sharp %.3f mm3, blended %.3f mm3, difference %.4f mm3 (closed form %.4f)\n",
           s.removed, b.removed, s.removed - b.removed, expected);
    CHECK(expected > 20.0);
    /* each run within the README's 0.022% of its volume at 0.1 mm voxels */
    CHECK_NEAR(s.removed - b.removed, expected, 0.00022 * (s.removed + b.removed));

    /* Cut piece by piece (each its own batch): the report after the line
     * into the corner says a resume starts with that motion again (its arc
     * is not cut yet), the one after the arc with the next motion. */
    arcs_seen each = {0};
    run_out e = run(&dyn, &each, -1.0);
    CHECK_NEAR(e.removed, b.removed, 1e-6 * b.removed);
    int before_arc = 0, after_arc = 0;
    for (int i = 0; i < each.reports && i < 16; i++) {
        const double *w = each.where[i];
        if (fabs(w[0] + d) < 1e-9 && fabs(w[1]) < 1e-9 && fabs(w[2] + 2.0) < 1e-9) {
            before_arc++;
            CHECK(each.resume_from[i] == arc->index);
        }
        if (fabs(w[0]) < 1e-9 && fabs(w[1] - d) < 1e-9 && fabs(w[2] + 2.0) < 1e-9) {
            after_arc++;
            CHECK(each.resume_from[i] == arc->index + 1);
        }
    }
    CHECK(before_arc == 1 && after_arc == 1);

    /* The stock at the probes */
    printf("outer probe: sharp %.3f, blended %.3f; inner probe: sharp %.3f, blended %.3f\n", s.outer,
           b.outer, s.inner, b.inner);
    CHECK(s.outer < 0.0 && b.outer > 0.0);
    CHECK(s.inner > 0.0 && b.inner < 0.0);
    return test_summary("blend_path");
}
