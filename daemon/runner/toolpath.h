/* toolpath.h: the toolpath drawn once (toolpath.c): the motion stream
 * collected into tool tip points, one record per motion, for both of its
 * readers: the polylines drawn over `frepmill simulate --png` pictures
 * (outputs.c) and the document of GET /v1/jobs/{id}/toolpath that the
 * viewer draws and replays (docs/api.md), with the table's placement of
 * the workpiece at every point on a rotary-table machine. */
#ifndef FM_TOOLPATH_H
#define FM_TOOLPATH_H

#include <stddef.h>

#include "core/core.h"
#include "mesh/mesh.h"
#include "sweep/motion.h"

/* Every motion through lib/sweep's motion geometry, in the workpiece
 * frame: lines whole, arcs and rotary moves with a point every 5 degrees
 * (arcs at least 2 pieces), parametric segments in 32 pieces, a dwell one
 * point; each motion's points include its start. Once more than
 * max_points points are kept (0: 4,000,000) further motions are dropped
 * (fm_toolpath_truncated). */
typedef struct fm_toolpath fm_toolpath;
fm_toolpath *fm_toolpath_new(size_t max_points);
void fm_toolpath_free(fm_toolpath *path);
void fm_toolpath_add(fm_toolpath *path, const fm_motion *motion);
int fm_toolpath_truncated(const fm_toolpath *path);

/* Polylines for fm_render_png (rapids apart from feeds; a motion that
 * starts where the last one ended, of the same kind, continues it): an
 * array of *count polylines pointing into path (free() the array only);
 * NULL with *count 0 when there are none. FM_ERR_LIMIT out of memory. */
fm_status fm_toolpath_polylines(const fm_toolpath *path, fm_render_polyline **out, size_t *count,
                                fm_error *err);

/* The toolpath's part of the toolpath document, the members (without the
 * braces around them):
 *   "machine": {"table": [{"axis", "around", "through"}, ...]},  when the
 *       machine has axes that turn the workpiece (chain order from the base)
 *   "motions": [[kind, line, t0, t1, tool, first, count], ...]
 *       kind 0 rapid, 1 feed line, 2 arc, 3 parametric, 4 dwell; the
 *       motion's points are points[3*first ..], count of them; on a machine
 *       with rotary axes the joints at its start and end follow
 *       (a0, b0, c0, a1, b1, c1, degrees)
 *   "points": [x, y, z, ...]
 *   "placements": [r00, r01, r02, r10, ..., r22, tx, ty, tz, ...]  with a
 *       table: where the table puts the workpiece at each point (12 numbers
 *       a point: x_machine = R x + t, R row-major; fm_machine_table_transform
 *       at the point's joints)
 *   "truncated": bool
 * machine may be NULL. A malloc'd string (*len bytes), NULL out of memory. */
char *fm_toolpath_json_members(const fm_toolpath *path, const fm_machine *machine, size_t *len);

#endif
