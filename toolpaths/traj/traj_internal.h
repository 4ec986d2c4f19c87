/* traj_internal.h: what the trajectory front end's files share: the
 * compiled segment (expressions as tapes, an evaluator pool for concurrent
 * pose calls) and the JSON position helpers. Not a public header. */
#ifndef FM_TRAJ_INTERNAL_H
#define FM_TRAJ_INTERNAL_H

#include <stdatomic.h>
#include <stddef.h>

#include "frep/frep.h"
#include "toolpaths/traj/traj.h"

/* Components of a segment: x, y, z of the tip, a, b, c of the axis. */
enum { TRAJ_COMPONENTS = 6 };

/* Evaluators are per-thread scratch; a segment keeps a few, each taken by
 * one caller at a time, so that the sweep's worker threads can evaluate the
 * same path at once. */
enum { TRAJ_POOL = 8 };

typedef struct traj_slot {
    atomic_int busy;
    fm_evaluator *ev[TRAJ_COMPONENTS];
} traj_slot;

typedef struct traj_seg {
    fm_path path;                     /* ctx points back at this segment */
    int rapid;
    int has_to;
    double to[3];                     /* rapid target, mm */
    double t0, t1;                    /* document time of the expressions */
    double shift;                     /* program time = document time + shift */
    double scale;                     /* mm per document unit */
    fm_tape *tape[TRAJ_COMPONENTS];   /* NULL: the component is the constant cval, */
    double cval[TRAJ_COMPONENTS];
    unsigned char is_t[TRAJ_COMPONENTS]; /* or t itself (a tape of no instructions
                                            is not evaluated: lib/frep's point
                                            evaluator offsets its NULL array) */
    traj_slot slot[TRAJ_POOL];
    int tool;
    double feed, spindle;             /* mm/min; rpm, negative counter-clockwise */
    int line;
} traj_seg;

/* Smallest tool axis length accepted before normalization. */
#define TRAJ_MIN_AXIS 1e-9

/* Set up s->path; free the tapes and evaluators. */
void traj_seg_init_path(traj_seg *s);
void traj_seg_free(traj_seg *s);

/* The pose at document time t (clamped to [t0, t1]): tip in mm, unit axis. */
void traj_seg_pose_doc(traj_seg *s, double t, double pos[3], double axis[3]);

/* Validate the expressions on [t0, t1]: samples + 1 points, then interval
 * checks by bisection. Returns -1 when fine, -2 when out of memory;
 * otherwise the failing component (0..5, or 6 for a zero axis), with *t_bad
 * where, *value the sampled value, and *how which check failed. */
enum { TRAJ_CHECK_SAMPLE = 0, TRAJ_CHECK_INTERVAL = 1, TRAJ_CHECK_BUDGET = 2 };
#define TRAJ_CHECK_MAX 20000 /* interval evaluations per segment */
int traj_seg_check(traj_seg *s, int samples, double *t_bad, double *value, int *how);

/* JSON positions (offsets into the text, -1 when not found). */
long traj_json_member(const char *s, size_t n, long obj, const char *key);
long traj_json_element(const char *s, size_t n, long arr, size_t index);
size_t traj_json_elements(const char *s, size_t n, long arr, long *offsets, size_t max);
void traj_json_position(const char *s, size_t n, long off, int *line, int *column);
void traj_json_lines(const char *s, size_t n, const long *offsets, size_t count, int *lines);
/* Offset of the character at 1-based decoded column `column` inside the
 * JSON string that starts (with its quote) at str. */
long traj_json_string_char(const char *s, size_t n, long str, int column);

#endif
