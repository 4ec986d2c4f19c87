/* check_internal.h: what the files of lib/check share and nobody else sees:
 * the check's state, the targets a swept part is related to (the stock's
 * distance bound, fixtures) and the branch-and-bound over boxes. */
#ifndef FM_CHECK_INTERNAL_H
#define FM_CHECK_INTERNAL_H

#include "check/check.h"
#include "frep/frep.h"
#include "sweep/sweep.h"

/* A motion that cut the stock: -S is an upper bound of the stock's
 * distance from then on. */
typedef struct check_history {
    fm_sweep *sweep;
    fm_sweep_worker *worker;
    double lo[3], hi[3];
    int straight;           /* a line with a fixed axis: retracing it is free */
    double tip0[3], tip1[3], axis[3];
} check_history;

/* A worker points into the sweep it was made from: each is made from a
 * sweep of its own that lives as long as it does. */
typedef struct check_workers {
    int tool;
    fm_sweep_worker *w[FM_CHECK_PART_COUNT];
    fm_sweep *keep[FM_CHECK_PART_COUNT];
} check_workers;

typedef struct check_fixture {
    char name[256];
    /* HyperFun: a compiled model */
    fm_graph *graph;
    fm_tape *tape;
    fm_evaluator *ev;
    /* STL: a level set */
    fm_stock *grid;
    double lo[3], hi[3]; /* where it can be positive */
} check_fixture;

void check_fixture_free(check_fixture *fx);

/* A level set (the stock or an STL fixture) read as an upper bound of a
 * 1-Lipschitz distance: G(p) <= I(p) + e(p) while that stays below the
 * band (docs/check.md). */
typedef struct check_grid {
    const fm_stock *stock;
    double voxel, band, origin[3];
    double lo[3], hi[3]; /* world box of the active voxels, widened by a voxel */
} check_grid;

int check_grid_init(check_grid *g, const fm_stock *stock);

typedef struct check_target {
    fm_check *check;
    check_grid grid;
    int has_grid;
    check_fixture *fixture; /* NULL: the stock */
    int have_box;
    double box_lo[3], box_hi[3];
    const check_history *history;
    const size_t *pick;
    size_t pick_count;
    double lo[3], hi[3]; /* region searched */
} check_target;

typedef struct check_bb {
    fm_check *check;
    const fm_sweep *sweep;
    fm_sweep_worker *worker;
    int custom;    /* the part is not a distance: use the sweep's interval */
    double clear;  /* S + clear is related */
    check_target *target;
    double tol;
} check_bb;

typedef struct check_bb_result {
    int found;
    double value; /* detect: a value above the threshold; maximize: the maximum (upper bound) */
    double at[3];
} check_bb_result;

/* Is max over the region of min(S + clear, F) above 3/4 of the tolerance?
 * Never misses a maximum above the tolerance. */
fm_status check_bb_detect(check_bb *bb, const double lo[3], const double hi[3],
                          check_bb_result *out, fm_error *err);
/* The maximum of min(S + clear, F) over the region, from above, within a
 * quarter of the tolerance. */
fm_status check_bb_maximize(check_bb *bb, const double lo[3], const double hi[3],
                            check_bb_result *out, fm_error *err);
/* Detect for the part standing still at the pose of motion m at parameter
 * u in [0, 1]. */
fm_status check_static_detect(check_bb *bb, const fm_motion *m, const fm_tool_part *part, double u,
                              check_bb_result *out, int *found, fm_error *err);

typedef struct check_box {
    double lo[3], hi[3];
} check_box;

struct fm_check {
    fm_check_options opt;
    int started;
    int have_box;
    double box_lo[3], box_hi[3];

    check_fixture *fixtures;
    size_t fixture_count;

    check_history *history;
    size_t history_count, history_cap;
    size_t *pick;
    size_t pick_cap;

    check_workers *workers;
    size_t worker_count, worker_cap;

    fm_check_finding *findings;
    unsigned char *hit_now;
    size_t finding_count, finding_cap;
    int open[FM_CHECK_KIND_COUNT][FM_CHECK_PART_COUNT];
    int *open_fixture; /* fixture * FM_CHECK_PART_COUNT + part */

    /* the stock's active box, cached per stock version */
    const fm_stock *bounds_stock;
    uint64_t bounds_version;
    int bounds_ok;
    double bounds_lo[3], bounds_hi[3];

    int need_first; /* the relation being run must find its first contact */
    check_box *stack;
    size_t stack_cap;
    fm_check_stats stats;
};

#endif
