/* test_machine_pose.c: the workpiece in its machine position at a chosen
 * time (issue 17). A C table turns the stock one full turn at 60 degrees a
 * second before a slot is cut; the joints tracked from the job's motions
 * must be C = 60 t at t = 1.5 and 3 s and 360 at the end, the placement
 * Rz(C) written out here, and a picture rendered with that rotation must
 * be the picture of the mesh turned by this test itself (vertices and
 * normals), pixel for pixel up to rounding. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"
#include "outputs.h"
#include "mesh/mesh.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"ball\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

/* The turn first (6 s at F3600 degrees per minute, the tool in the air),
 * then a slot on the -X half so that the part has no symmetry. */
static const char *program = "G21 G90 G94\nT1 M6\nG1 C360 F3600\nG0 X-20 Y0 Z0\nG1 Z-12 F600\n"
                             "G1 X0\nG0 Z0\nM2\n";

#define POSES 4
static fm_machine_pose poses[POSES];

static void track(void *user, const fm_motion *motion)
{
    (void)user;
    for (int i = 0; i < POSES; i++) fm_machine_pose_track(&poses[i], motion);
}

static void rz(double deg, double R[9])
{
    double c = cos(deg * FM_PI / 180), s = sin(deg * FM_PI / 180);
    const double r[9] = {c, -s, 0, s, c, 0, 0, 0, 1};
    memcpy(R, r, sizeof r);
}

static uint8_t *render(const fm_mesh *mesh, const double *rotation)
{
    fm_render_options ro;
    fm_render_default(&ro);
    ro.width = 320;
    ro.height = 240;
    ro.rotation = rotation;
    uint8_t *rgb = malloc(3u * 320 * 240);
    fm_error err;
    if (!rgb || fm_render_rgb(mesh, &ro, rgb, &err) != FM_OK) {
        free(rgb);
        return NULL;
    }
    return rgb;
}

/* pixels whose colour differs by more than 8 in a channel, and pixels not background */
static void compare(const uint8_t *a, const uint8_t *b, size_t *differ, size_t *drawn)
{
    *differ = *drawn = 0;
    for (size_t i = 0; i < 320u * 240; i++) {
        int d = 0, fg = 0;
        for (int k = 0; k < 3; k++) {
            if (abs((int)a[3 * i + k] - (int)b[3 * i + k]) > 8) d = 1;
            if (a[3 * i + k] != 255) fg = 1;
        }
        *differ += (size_t)d;
        *drawn += (size_t)fg;
    }
}

int main(void)
{
    fm_tool_table tools;
    fm_error err;
    if (fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) != FM_OK) {
        fprintf(stderr, "tool table: %s\n", err.message);
        return 1;
    }
    fm_machine mc;
    memset(&mc, 0, sizeof mc);
    mc.rotary_count = 1;
    mc.rotary[0].letter = 2;
    mc.rotary[0].carries = FM_ROTARY_TABLE;
    mc.rotary[0].around[2] = 1;

    const double times[POSES] = {0, 1.5, 3.0, INFINITY};
    const double expect_c[POSES] = {0, 90, 180, 360};
    for (int i = 0; i < POSES; i++) poses[i] = (fm_machine_pose){.machine = &mc, .time_s = times[i]};

    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "pose.ngc";
    spec.stock_spec = "box:-30,-5,-20,30,5,-10";
    spec.tools = &tools;
    spec.stock.voxel_mm = 0.25;
    spec.machine = &mc;
    fm_job_hooks hooks = {.on_motion = track};
    fm_job_result result;
    if (fm_job_run(&spec, &hooks, &result, &err) != FM_OK) {
        fprintf(stderr, "job failed: %s\n", err.message);
        return 1;
    }
    /* the slot: 20 mm long, a 6 mm ball 2 mm deep: the turn cut nothing */
    CHECK(result.removed_volume_mm3 > 100);

    for (int i = 0; i < POSES; i++) {
        CHECK_NEAR(poses[i].joints[0], 0, 0);
        CHECK_NEAR(poses[i].joints[1], 0, 0);
        CHECK_NEAR(poses[i].joints[2], expect_c[i], 1e-9);
        double R[9], T[3], E[9];
        fm_machine_pose_transform(&poses[i], R, T);
        rz(expect_c[i], E);
        for (int k = 0; k < 9; k++) CHECK_NEAR(R[k], E[k], 1e-12);
        for (int k = 0; k < 3; k++) CHECK_NEAR(T[k], 0, 1e-12);
    }

    /* The picture at C = 90: rendered with the rotation, and of a mesh the
     * test turned itself. */
    fm_mesh_extract_options eo;
    fm_mesh_extract_default(&eo);
    fm_mesh *mesh = fm_mesh_from_stock(result.stock, &eo, &err);
    CHECK(mesh != NULL && mesh->normals != NULL);
    if (mesh && mesh->normals) {
        double R[9], T[3];
        fm_machine_pose_transform(&poses[1], R, T);
        fm_mesh *turned = fm_mesh_new(mesh->vertex_count, mesh->triangle_count, FM_MESH_NORMALS, NULL, &err);
        CHECK(turned != NULL);
        if (turned && fm_mesh_append(turned, mesh, &err) == FM_OK) {
            for (size_t v = 0; v < turned->vertex_count; v++) {
                float *p = turned->positions + 3 * v, *n = turned->normals + 3 * v;
                /* Rz(90): (x, y, z) -> (-y, x, z), written out */
                float px = p[0], nx = n[0];
                p[0] = -p[1], p[1] = px;
                n[0] = -n[1], n[1] = nx;
            }
            uint8_t *plain = render(mesh, NULL), *posed = render(mesh, R), *mine = render(turned, NULL);
            CHECK(plain && posed && mine);
            if (plain && posed && mine) {
                size_t differ, drawn;
                compare(posed, mine, &differ, &drawn);
                fprintf(stderr, "posed vs turned mesh: %zu of %zu drawn pixels differ\n", differ, drawn);
                CHECK(drawn > 5000);
                CHECK(differ <= drawn / 200);
                /* and the rotation changed the picture */
                compare(posed, plain, &differ, &drawn);
                fprintf(stderr, "posed vs unposed: %zu of %zu drawn pixels differ\n", differ, drawn);
                CHECK(differ > drawn / 5);
            }
            free(plain);
            free(posed);
            free(mine);
        }
        fm_mesh_free(turned);
    }
    fm_mesh_free(mesh);
    fm_job_result_release(&result);
    fm_tool_table_free(&tools);
    fprintf(stderr, "%d checks, %d failed\n", fm_test_checks, fm_test_failures);
    return fm_test_failures ? 1 : 0;
}
