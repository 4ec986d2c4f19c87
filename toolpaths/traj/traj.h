/* traj.h: the parametric trajectory front end. A JSON document of segments,
 * each a time interval with expressions of t (the expression syntax of the
 * geometry language, lib/hf) for the tool tip position and optionally the
 * tool axis, is validated whole (intervals, expressions, finiteness,
 * continuity) and then streamed as motions (lib/sweep/motion.h): one
 * FM_MOTION_PARAM motion per segment, whose fm_path evaluates the compiled
 * expressions, and one FM_MOTION_RAPID per explicit jump. The format is
 * described in docs/trajectory.md. Nothing here prints. */
#ifndef FM_TRAJ_H
#define FM_TRAJ_H

#include <stddef.h>

#include "core/core.h"
#include "sweep/motion.h"

typedef struct fm_traj_options {
    double rapid_rate;            /* mm/min for rapid segments (default 5000) */
    double tolerance;             /* mm: largest tip gap between consecutive segments
                                     (default 0.001; the document's "tolerance" overrides) */
    double axis_tolerance;        /* radians: largest tool axis jump (default 1e-4) */
    size_t max_document_bytes;    /* default 16 MiB */
    size_t max_segments;          /* default 10000 */
    size_t max_expression_bytes;  /* one expression's text (default 4096) */
    size_t max_expression_nodes;  /* frep nodes one expression may add (default 20000) */
    size_t max_total_nodes;       /* frep nodes of the whole document (default 1000000) */
    int samples;                  /* finiteness samples per segment (default 1000, >= 2) */
    long skip_motions;            /* validate everything, but do not emit motions with
                                     index < skip_motions (resume after a restart) */
} fm_traj_options;

/* Fill *opt with the defaults above. */
void fm_traj_options_default(fm_traj_options *opt);

/* What a run did (may be NULL), in the shape of fm_gcode_summary. */
typedef struct fm_traj_summary {
    long motions;   /* motions produced, including skipped ones */
    long segments;  /* segments in the document */
    double seconds; /* program time at the end */
    int stopped;    /* 1 if the sink asked to stop */
} fm_traj_summary;

/* Parse and validate the trajectory in `path` (read whole, bounded by
 * max_document_bytes), then call sink for each motion in order. Nothing is
 * emitted unless the whole document is valid. A sink that returns non-zero
 * stops the run early (FM_OK).
 *
 * Motions: positions in millimetres (inch documents are converted), unit
 * axes, program time in seconds; `line` is the JSON line of the segment,
 * `block` the 0-based segment index. A parametric motion's `path` (and the
 * ctx inside it) stays valid until fm_traj_run_* returns, not longer; its
 * pose and pose_bounds may be called from several threads at once.
 *
 * On error, err says file:line:column in the JSON (inside the expression's
 * string for expression errors), the segment index and field, and what was
 * expected. opt may be NULL for defaults. */
fm_status fm_traj_run_file(const char *path, const fm_traj_options *opt, fm_motion_sink sink,
                           void *user, fm_traj_summary *summary, fm_error *err);

/* Same for a document held by the caller; `name` is used in error messages. */
fm_status fm_traj_run_string(const char *text, size_t len, const char *name,
                             const fm_traj_options *opt, fm_motion_sink sink, void *user,
                             fm_traj_summary *summary, fm_error *err);

#endif
