/* outputs.c: the final stock to files, by extension: .vdb snapshots through
 * lib/stock, meshes and pictures through lib/mesh, and the toolpath
 * polylines drawn over pictures. */
#include "outputs.h"

#include "job.h"
#include "sweep/sweep.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

#define OUT_PI 3.14159265358979323846
/* Arcs and rotary moves are drawn with a chord every 5 degrees at most. */
#define OUT_ARC_STEP (OUT_PI / 36)
#define OUT_PARAM_SAMPLES 32

typedef struct polyline {
    size_t first, count; /* into points */
    int rapid;
} polyline;

struct fm_toolpath {
    double *points;
    size_t count, capacity, max_points;
    polyline *lines;
    size_t line_count, line_capacity;
    int truncated;
    int have_last;
    double last[3];
};

fm_toolpath *fm_toolpath_new(size_t max_points)
{
    fm_toolpath *p = calloc(1, sizeof *p);
    if (p) p->max_points = max_points ? max_points : 4000000;
    return p;
}

void fm_toolpath_free(fm_toolpath *path)
{
    if (!path) return;
    free(path->points);
    free(path->lines);
    free(path);
}

int fm_toolpath_truncated(const fm_toolpath *path)
{
    return path && path->truncated;
}

static int push_point(fm_toolpath *p, const double xyz[3])
{
    if (p->count >= p->max_points) {
        p->truncated = 1;
        return 0;
    }
    if (p->count == p->capacity) {
        size_t cap = p->capacity ? p->capacity * 2 : 1024;
        double *pts = realloc(p->points, cap * 3 * sizeof *pts);
        if (!pts) {
            p->truncated = 1;
            return 0;
        }
        p->points = pts;
        p->capacity = cap;
    }
    memcpy(p->points + 3 * p->count, xyz, 3 * sizeof *xyz);
    p->count++;
    return 1;
}

/* Start a new polyline unless the last one has the same kind and ends
 * where this motion starts. */
static int begin_line(fm_toolpath *p, int rapid, const double start[3])
{
    if (p->line_count > 0) {
        polyline *l = &p->lines[p->line_count - 1];
        if (l->rapid == rapid && p->have_last && start[0] == p->last[0] &&
            start[1] == p->last[1] && start[2] == p->last[2])
            return 1;
    }
    if (p->line_count == p->line_capacity) {
        size_t cap = p->line_capacity ? p->line_capacity * 2 : 256;
        polyline *lines = realloc(p->lines, cap * sizeof *lines);
        if (!lines) {
            p->truncated = 1;
            return 0;
        }
        p->lines = lines;
        p->line_capacity = cap;
    }
    polyline *l = &p->lines[p->line_count++];
    l->first = p->count;
    l->count = 0;
    l->rapid = rapid;
    if (!push_point(p, start)) return 0;
    l->count = 1;
    return 1;
}

static void add_point(fm_toolpath *p, const double xyz[3])
{
    if (!push_point(p, xyz)) return;
    p->lines[p->line_count - 1].count++;
    memcpy(p->last, xyz, sizeof p->last);
    p->have_last = 1;
}

/* Every motion kind through lib/sweep's motion geometry: the tool tip in
 * the workpiece frame at OUT_ARC_STEP of arc or of any rotary joint per
 * piece, parametric paths in OUT_PARAM_SAMPLES pieces, lines whole. */
void fm_toolpath_add(fm_toolpath *path, const fm_motion *m)
{
    if (!path || path->truncated || m->kind == FM_MOTION_DWELL) return;
    double tip[3], axis[3];
    fm_motion_pose_at(m, 0, tip, axis);
    if (!begin_line(path, m->kind == FM_MOTION_RAPID, tip)) return;
    int pieces = fm_motion_pieces(m, OUT_ARC_STEP, OUT_PARAM_SAMPLES, 100000);
    for (int i = 1; i <= pieces; i++) {
        fm_motion_pose_at(m, (double)i / pieces, tip, axis);
        add_point(path, tip);
    }
}

/* ------------------------------------------------------------ writing -- */

void fm_output_options_default(fm_output_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->coloring = FM_MESH_COLOR_DEPTH;
    opt->png_width = 1024;
    opt->png_height = 768;
}

const char *fm_output_formats(void)
{
    return ".vdb, .drc, .stl, .ply, .obj, .png";
}

int fm_output_format_known(const char *path)
{
    return fm_path_has_extension(path, ".vdb") || fm_path_has_extension(path, ".png") ||
           fm_mesh_format_from_path(path) != FM_MESH_FORMAT_UNKNOWN;
}

void fm_machine_pose_track(fm_machine_pose *pose, const fm_motion *motion)
{
    /* motions come in time order: the last one begun by time_s holds it */
    if (!pose->machine || motion->t0 > pose->time_s) return;
    fm_motion_joints_at(motion, pose->time_s, pose->joints);
}

void fm_machine_pose_transform(const fm_machine_pose *pose, double rot[9], double trans[3])
{
    fm_machine_table_transform(pose->machine, pose->joints, -1, rot, trans);
}

static fm_status write_png(const fm_mesh *mesh, const char *path, const fm_output_options *opt,
                           fm_error *err)
{
    fm_render_options ro;
    fm_render_default(&ro);
    ro.width = opt->png_width;
    ro.height = opt->png_height;
    fm_render_legend legend;
    if (opt->coloring == FM_MESH_COLOR_DEVIATION && opt->design) {
        const double tol = fm_design_tolerance(opt->design);
        fm_mesh_deviation_legend(tol, 10 * tol, &legend);
        ro.legend = &legend;
    }
    fm_render_polyline *lines = NULL;
    const fm_toolpath *tp = opt->toolpath;
    if (tp && tp->line_count) {
        lines = calloc(tp->line_count, sizeof *lines);
        if (!lines) return fm_error_set(err, FM_ERR_LIMIT, "out of memory for the toolpath overlay");
        for (size_t i = 0; i < tp->line_count; i++) {
            lines[i].points = tp->points + 3 * tp->lines[i].first;
            lines[i].count = tp->lines[i].count;
            lines[i].rapid = tp->lines[i].rapid;
        }
        ro.paths = lines;
        ro.path_count = tp->line_count;
    }
    ro.rotation = opt->rotation;
    fm_status st = fm_render_png(mesh, &ro, path, err);
    free(lines);
    return st;
}

fm_status fm_outputs_write(const char *const *paths, size_t count, fm_stock *stock,
                           const fm_output_options *opt, fm_error *err)
{
    fm_output_options defaults;
    if (!opt) {
        fm_output_options_default(&defaults);
        opt = &defaults;
    }
    fm_mesh *mesh = NULL;
    fm_status st = FM_OK;
    for (size_t i = 0; i < count && st == FM_OK; i++) {
        const char *path = paths[i];
        if (fm_path_has_extension(path, ".vdb")) {
            st = fm_stock_save(stock, path, NULL, err);
            continue;
        }
        int png = fm_path_has_extension(path, ".png");
        if (!png && fm_mesh_format_from_path(path) == FM_MESH_FORMAT_UNKNOWN) {
            st = fm_error_set(err, FM_ERR_INPUT, "%s: unknown output format (use %s)", path,
                              fm_output_formats());
            break;
        }
        if (!mesh) {
            fm_mesh_extract_options eo;
            fm_mesh_extract_default(&eo);
            eo.coloring = opt->coloring;
            eo.top_z = opt->top_z;
            eo.design = opt->design;
            /* faces no cut reached keep a neutral grey, so that cuts stand out */
            eo.uncut_grey = 1;
            mesh = fm_mesh_from_stock(stock, &eo, err);
            if (!mesh) {
                st = err ? err->code : FM_ERR_INTERNAL;
                break;
            }
        }
        st = png ? write_png(mesh, path, opt, err) : fm_mesh_write_file(mesh, path, NULL, err);
    }
    fm_mesh_free(mesh);
    return st;
}
