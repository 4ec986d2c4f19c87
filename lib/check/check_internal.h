/* check_internal.h: what the files of lib/check share and nobody else sees:
 * the check's state, the flute sweeps not yet cut from the grid, fixtures
 * as grids, and one relation of a swept part to a grid (relate.c). */
#ifndef FM_CHECK_INTERNAL_H
#define FM_CHECK_INTERNAL_H

#include "check/check.h"
#include "frep/frep.h"
#include "sweep/sweep.h"

/* A motion fed but not yet cut from the grid: -S of its flutes is an exact
 * term of the stock's distance until the caller cuts it. */
typedef struct check_pending {
    fm_sweep *sweep;
    fm_sweep_worker *worker; /* the check's worker for that tool's flutes */
    double lo[3], hi[3];
} check_pending;

/* A worker points into the sweep it was made from: each is made from a
 * sweep of its own that lives as long as it does. */
typedef struct check_workers {
    int tool;
    fm_sweep_worker *w[FM_CHECK_PART_COUNT];
    fm_sweep *keep[FM_CHECK_PART_COUNT];
    int head_state; /* 0: not built yet; 1: head holds the machine's head for this tool; -1: none */
    fm_tool_part head;
} check_workers;

typedef struct check_fixture {
    char name[256];
    fm_stock *grid; /* true distances in its band, mm */
    int machine;    /* a machine component: its contacts are machine_contact */
    int frame_up;   /* its link, table axes nearer the base than the workpiece's */
} check_fixture;

void check_fixture_free(check_fixture *fx);

/* The options every sweep the check makes gets (the evaluation budget). */
const fm_sweep_options *check_sweep_options(const fm_check *c);

/* A leaf copied from the grid for a relation: its values and where. */
typedef struct check_leaf {
    int32_t lo[3];
    float max;      /* largest value in it */
    float values[512];
} check_leaf;

typedef struct check_box {
    int32_t lo[3], hi[3];
} check_box;

/* A contact voxel whose grid value is clamped at the band: its depth is
 * searched for in the grid afterwards. cap is min of the exact terms (the
 * flutes not yet cut, the flutes' sweep up to the contact time); part the
 * part's value then (negative: the point lies that far outside it). */
typedef struct check_deep {
    double p[3];
    double cap, part, t;
} check_deep;

/* One relation: a part swept over a motion against a grid (the stock or a
 * fixture). For every voxel centre v near the part, with G the grid's
 * distance there less the flutes not yet cut,
 *     Q(v) = min(G(v), -M(v, t)) + min(0, P_t(v))
 * is a lower bound of the depth of a point of the part at time t below the
 * grid's surface (P the part, 1-Lipschitz; M the flutes' sweep up to t
 * when they lead, else nothing): Q above the threshold proves a contact. */
typedef struct check_rel {
    fm_check *check;
    const fm_stock *grid;
    int is_stock;           /* pending cuts and the initial box apply */
    double voxel, band, origin[3];
    const fm_motion *motion;
    const fm_tool_part *shape;
    const fm_sweep *sweep;  /* the part over the motion */
    fm_sweep_worker *worker;
    int custom;             /* the part is not a distance: only points inside it count */
    /* the flutes leading the part within the motion (NULL: no time order) */
    const fm_tool_part *flutes_shape;
    const fm_sweep *flutes;
    fm_sweep_worker *flutes_worker; /* also evaluates the flutes' sweeps up to a time */
    double threshold;       /* Q above it is reported (a contact, or a near miss) */
    double reach;           /* voxels farther outside the part are not looked at */
    double known;           /* depth already known (an open finding) */
    int need_first;         /* find the first contact's time and place */

    int found;
    double depth;           /* the largest Q proven (then searched beyond the band) */
    double depth_at[3], depth_t;
    double first_t, first_at[3];
    long uncertain;
    double uncertain_at[3], uncertain_t;
} check_rel;

fm_status check_relate(check_rel *r, fm_error *err);

/* The distance from p to the grid's surface, from above: the smallest
 * |p - u| + G(u) over voxels u within the band (and outside tiles), found
 * within limit; returns limit when nothing is nearer. */
double check_grid_depth(fm_check *c, const fm_stock *grid, const double p[3], double limit,
                        fm_error *err);

/* geometry.c: the motion up to parameter u in [0, 1] (a prefix of it, as
 * lib/sweep parameterizes it); an arc's swept angle (radians, positive),
 * start radius, start angle and direction; the descent of a feed motion
 * along the tool axis (degrees; 0 level or climbing, 90 a plunge); the box
 * of the programmed point over a motion. */
void check_motion_prefix(const fm_motion *m, double u, fm_motion *out);
double check_arc_angle(const fm_motion *m, double *radius, double *a0, int *ccw);
double check_descent_deg(const fm_motion *m);
void check_motion_point_bounds(const fm_motion *m, double lo[3], double hi[3]);

struct fm_check {
    fm_check_options opt;
    fm_sweep_options sweep_opt;
    int started;
    int have_box;
    double box_lo[3], box_hi[3];
    int have_region;
    double region_lo[3], region_hi[3];

    check_fixture *fixtures;
    size_t fixture_count;

    check_pending *pending;
    size_t pending_count, pending_cap;

    check_workers *workers;
    size_t worker_count, worker_cap;

    fm_check_finding *findings;
    unsigned char *hit_now;
    size_t finding_count, finding_cap;
    int open[FM_CHECK_KIND_COUNT][FM_CHECK_PART_COUNT];
    int *open_fixture; /* fixture * FM_CHECK_PART_COUNT + part */

    /* scratch of the relations, kept between them */
    check_leaf *leaves;
    size_t leaf_count, leaf_cap;
    check_box *tiles;
    size_t tile_count, tile_cap;
    check_deep *deep;
    size_t deep_count, deep_cap;
    fm_status scratch_status;

    fm_check_stats stats;
};

#endif
