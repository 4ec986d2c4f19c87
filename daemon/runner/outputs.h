/* outputs.h: writing a job's final stock in the formats its file names ask
 * for: a frepmill .vdb snapshot, meshes (.drc, .stl, .ply, .obj) and a
 * shaded picture (.png) with the toolpath drawn over it. The stock is
 * meshed once for all mesh and picture outputs. */
#ifndef FM_OUTPUTS_H
#define FM_OUTPUTS_H

#include <stddef.h>

#include "core/core.h"
#include "mesh/mesh.h"
#include "stock/stock.h"
#include "sweep/motion.h"
#include "toolpath.h"

/* Where the workpiece stands on the machine at a chosen program time, found
 * from the motion stream: set machine and time_s, zero the rest, and feed
 * every motion in order to fm_machine_pose_track. Before the first motion
 * every joint is at 0; past the last, the joints stay where it left them. */
typedef struct fm_machine_pose {
    const fm_machine *machine;
    double time_s;
    double joints[3]; /* degrees, A B C */
} fm_machine_pose;
void fm_machine_pose_track(fm_machine_pose *pose, const fm_motion *motion);
/* x_machine = rot x_workpiece + trans (rot row-major) at the pose. */
void fm_machine_pose_transform(const fm_machine_pose *pose, double rot[9], double trans[3]);

typedef struct fm_output_options {
    fm_mesh_coloring coloring; /* default FM_MESH_COLOR_DEPTH */
    double top_z;              /* original stock top for depth colours; surface no cut
                                  reached is grey with either colouring */
    int png_width, png_height; /* default 1024 x 768 */
    const fm_design *design;   /* FM_MESH_COLOR_DEVIATION: the design; pictures get its key */
    const fm_toolpath *toolpath; /* overlay for pictures; may be NULL */
    const double *rotation;    /* pictures: the workpiece turned into its machine
                                  position (fm_machine_pose_transform); NULL: as it is */
} fm_output_options;
void fm_output_options_default(fm_output_options *opt);

/* "a, b, c" list of the extensions understood, for messages. */
const char *fm_output_formats(void);
int fm_output_format_known(const char *path);
/* Write every path; stops at the first failure (err names the file). */
fm_status fm_outputs_write(const char *const *paths, size_t count, fm_stock *stock,
                           const fm_output_options *opt, fm_error *err);

#endif
