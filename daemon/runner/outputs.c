/* outputs.c: the final stock to files, by extension: .vdb snapshots through
 * lib/stock, meshes and pictures through lib/mesh, with the toolpath's
 * polylines (toolpath.c) drawn over pictures. */
#include "outputs.h"

#include "job.h"
#include "sweep/sweep.h"

#include <ctype.h>
#include <math.h>
#include <stdlib.h>
#include <string.h>

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
    if (fm_toolpath_polylines(opt->toolpath, &lines, &ro.path_count, err) != FM_OK) return err->code;
    ro.paths = lines;
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
