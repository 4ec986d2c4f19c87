/* test_tool_colors.c: tool colours through the whole pipeline. A G-code
 * program cuts a slot with T1 (6 mm flat) and drills a hole with T3 (5 mm
 * drill); the job runner and the output writer (as `frepmill simulate
 * --color tool --out part.ply` use them) write a binary PLY, which is read
 * back here. Each vertex is placed by geometry worked out from the program:
 * on the slot (within 3 mm of its centre line, 0 to 3 mm deep), in the hole
 * (within 2.5 mm of its axis, 0 to 8 mm deep) or on the block's uncut faces;
 * the colour must be T1's, T3's or the uncut grey accordingly. Vertices
 * within 3 voxels of an edge between two of these are not judged. Depth
 * colouring greys the same uncut faces. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "job.h"
#include "outputs.h"
#include "test.h"
#include "toolpaths/tooltable/tooltable.h"

static const char *tool_json =
    "{\"units\": \"mm\", \"tools\": ["
    "{\"number\": 1, \"shape\": \"flat\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40},"
    "{\"number\": 3, \"shape\": \"drill\", \"diameter\": 5, \"point_angle\": 118, \"flute_length\": 30,"
    " \"length\": 45}]}";

static const char *program = "G21 G90 T1 M6 S10000 M3\n"
                             "G0 X10 Y10 Z5\n"
                             "G1 Z-3 F300\n"
                             "G1 X50 F800\n"
                             "G0 Z5\n"
                             "T3 M6\n"
                             "G0 X40 Y30\n"
                             "G1 Z-8 F200\n"
                             "G0 Z5\n"
                             "M2\n";

#define VOXEL 0.1
#define MARGIN (3 * VOXEL)

/* Distance in XY from (x, y) to the slot's centre line (10,10)-(50,10). */
static double slot_dist(double x, double y)
{
    double t = fmin(fmax(x, 10), 50);
    return hypot(x - t, y - 10);
}

/* 1: slot (T1), 3: hole (T3), -1: uncut face, 0: not judged. */
static int expected(const float *p)
{
    const double x = p[0], y = p[1], z = p[2];
    const double ds = slot_dist(x, y), dh = hypot(x - 40, y - 30);
    if (z < -MARGIN && z > -3 - MARGIN && ds < 3 + MARGIN) return 1;
    if (z < -MARGIN && z > -8 - MARGIN && dh < 2.5 + MARGIN) return 3;
    const int on_side = x < 0.05 || x > 59.95 || y < 0.05 || y > 39.95 || z < -19.95;
    if (on_side && ds > 3 + MARGIN && dh > 2.5 + MARGIN) return -1;
    if (z > -0.05 && ds > 3 + MARGIN && dh > 2.5 + MARGIN) return -1;
    return 0;
}

typedef struct ply {
    size_t n;
    unsigned char *data; /* n vertices of 27 bytes: xyz, normal, rgb */
    unsigned char *file;
} ply;

/* Read the vertices of a PLY that fm_mesh_encode_ply wrote with normals
 * and colours; 0 on any surprise. */
static int read_ply(const char *path, ply *out)
{
    memset(out, 0, sizeof *out);
    char *text;
    size_t size;
    fm_error err;
    if (fm_file_read(path, "PLY", (size_t)1 << 30, &text, &size, &err) != FM_OK) return 0;
    out->file = (unsigned char *)text;
    const char *h = (const char *)out->file;
    const char *end = strstr(h, "end_header\n");
    const char *ev = strstr(h, "element vertex ");
    if (!end || !ev || !strstr(h, "property float nx\n") || !strstr(h, "property uchar red\n"))
        return 0;
    out->n = strtoul(ev + 15, NULL, 10);
    out->data = out->file + (end - h) + 11;
    return size >= (size_t)(out->data - out->file) + 27 * out->n;
}

static void check_colours(fm_stock *stock, fm_mesh_coloring coloring, const char *path)
{
    fm_output_options oo;
    fm_output_options_default(&oo);
    oo.coloring = coloring;
    oo.top_z = 0;
    fm_error err;
    const char *paths[1] = {path};
    CHECK(fm_outputs_write(paths, 1, stock, &oo, &err) == FM_OK);
    ply p;
    CHECK(read_ply(path, &p));
    uint8_t want1[3], want3[3], grey[3];
    fm_mesh_tool_color(1, want1);
    fm_mesh_tool_color(3, want3);
    fm_mesh_tool_color(-1, grey);
    size_t counts[3] = {0}, wrong = 0;
    for (size_t i = 0; i < p.n; i++) {
        float pos[3];
        memcpy(pos, p.data + 27 * i, sizeof pos);
        const uint8_t *rgb = p.data + 27 * i + 24;
        const int e = expected(pos);
        if (e == 0) continue;
        int ok;
        if (coloring == FM_MESH_COLOR_TOOL)
            ok = !memcmp(rgb, e == 1 ? want1 : e == 3 ? want3 : grey, 3);
        else /* depth: grey exactly on the uncut faces */
            ok = (e == -1) == !memcmp(rgb, grey, 3);
        counts[e == 1 ? 0 : e == 3 ? 1 : 2]++;
        if (!ok && wrong++ < 5)
            fprintf(stderr, "vertex %.2f %.2f %.2f: colour %d %d %d, expected %d\n", pos[0], pos[1],
                    pos[2], rgb[0], rgb[1], rgb[2], e);
    }
    printf("%s colours: %zu vertices; judged %zu slot, %zu hole, %zu uncut; %zu wrong\n",
           coloring == FM_MESH_COLOR_TOOL ? "tool" : "depth", p.n, counts[0], counts[1], counts[2],
           wrong);
    CHECK(wrong == 0);
    CHECK(counts[0] > 5000 && counts[1] > 1000 && counts[2] > 20000);
    free(p.file);
    unlink(path);
}

int main(void)
{
    fm_error err;
    fm_tool_table tools;
    if (fm_tooltable_parse_json(tool_json, strlen(tool_json), "tools.json", &tools, &err) != FM_OK)
        return 1;
    fm_job_spec spec;
    fm_job_spec_default(&spec);
    spec.program_text = program;
    spec.program_length = strlen(program);
    spec.program_name = "colors.ngc";
    spec.stock_spec = "box:0,0,-20,60,40,0";
    spec.tools = &tools;
    spec.stock.voxel_mm = VOXEL;
    fm_job_result result;
    CHECK(fm_job_run(&spec, NULL, &result, &err) == FM_OK);
    if (!result.stock) return test_summary("simulate_tool_colors");
    char path[] = "/tmp/fm_colors_XXXXXX";
    int fd = mkstemp(path);
    if (fd >= 0) close(fd);
    char ply_path[64];
    snprintf(ply_path, sizeof ply_path, "%s.ply", path);
    check_colours(result.stock, FM_MESH_COLOR_TOOL, ply_path);
    check_colours(result.stock, FM_MESH_COLOR_DEPTH, ply_path);
    unlink(path);
    fm_stock_free(result.stock);
    fm_tool_table_free(&tools);
    return test_summary("simulate_tool_colors");
}
