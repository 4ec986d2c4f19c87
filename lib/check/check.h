/* check.h: collision and safety relations between the moving tool, the
 * stock, fixtures and the machine (issues 8 and 14): rapids into the stock,
 * shank and holder contact, fixture contact, plunges with a tool that cannot
 * cut at its centre, cutting with the spindle stopped, travel limits, a
 * start position inside the stock, feeds into the stock with no tool in
 * the spindle (issue 34), and the places where a search could not decide
 * (uncertain).
 *
 * The check runs in the same pass as the cut (ARCHITECTURE.md, "Checking in the
 * same pass"): the caller feeds every motion in program order with the
 * stock grid as it is then, except for the motions fed since its last
 * fm_check_stock_cut, whose flute sweeps are applied exactly. Within a
 * motion the flutes lead: a point is in contact with the shank or holder at
 * time t when it is inside that part at t and inside the stock before the
 * motion less the flutes' sweep over [t0, t]. The parts are evaluated at
 * the grid's voxel centres, where the grid holds the stock's exact distance
 * (clamped to its band); penetration_mm is how far the part went into what
 * it entered: the largest depth below the surface of the stock (or
 * fixture) of a point of the part, in millimetres. docs/check.md argues
 * what is never reported and what is never missed. No JSON and no
 * printing here: daemon/runner/findings_json.c writes the findings. */
#ifndef FM_CHECK_H
#define FM_CHECK_H

#include <stddef.h>

#include "core/core.h"
#include "stock/stock.h"
#include "sweep/motion.h"
#include "tools/tools.h"

typedef enum fm_check_kind {
    FM_CHECK_RAPID_INTO_STOCK = 0, /* the flutes of a rapid meet the stock */
    FM_CHECK_SHANK_CONTACT,        /* the shank meets the stock (any motion) */
    FM_CHECK_HOLDER_CONTACT,       /* the holder meets the stock (any motion) */
    FM_CHECK_FIXTURE_CONTACT,      /* any part meets a fixture */
    FM_CHECK_NON_CENTER_PLUNGE,    /* steep descent into the stock, center_cutting false */
    FM_CHECK_SPINDLE_OFF_CUT,      /* a feed motion cuts the stock with the spindle stopped */
    FM_CHECK_TRAVEL_LIMIT,         /* a programmed point outside the machine's travel */
    FM_CHECK_START_IN_STOCK,       /* the tool at the start position is in the stock */
    FM_CHECK_UNCERTAIN,            /* a search stopped at its budget where it mattered */
    FM_CHECK_MACHINE_CONTACT,      /* any part meets a machine component (a table, a rotary table),
                                      or the head meets anything */
    FM_CHECK_NO_TOOL,              /* a feed motion with no tool in the spindle drives the tool tip's
                                      programmed point (the spindle's nose) into the stock */
    FM_CHECK_KIND_COUNT
} fm_check_kind;

typedef enum fm_check_severity { FM_CHECK_WARNING = 0, FM_CHECK_ERROR } fm_check_severity;

typedef enum fm_check_part {
    FM_CHECK_PART_FLUTES = 0,
    FM_CHECK_PART_SHANK,
    FM_CHECK_PART_HOLDER,
    FM_CHECK_PART_HEAD, /* the machine's head: its round parts above the holder */
    FM_CHECK_PART_COUNT
} fm_check_part;

/* A machine: travel limits of the programmed point in machine coordinates,
 * and where the tool tip is before the first motion (and which tool the
 * spindle holds then, for the caller's job spec). */
#define FM_CHECK_MAX_COMPONENTS 8
#define FM_CHECK_COMPONENT_PATH 512

typedef struct fm_check_machine {
    int has_limit[3];        /* 0: that axis is not limited */
    double limit_lo[3], limit_hi[3];
    double start[3];         /* default: the machine origin */
    int has_start;           /* start was given (the machine file's "start"): the caller starts
                                its interpreter there too */
    int initial_tool;        /* the tool in the spindle before the first M6 (the machine file's
                                "initial_tool"), for the caller's job spec; 0: not given */
    double rapid_rate;       /* mm/min; 0: not given (for the caller's job spec) */
    /* Fanuc G28/G30's 1st-4th reference points (mm; not given: the origin),
     * for the caller's job spec; the check itself does not use them. */
    double reference_points[4][3];
    int reference_point_count;
    fm_machine chain;        /* rotary axes (lib/sweep), with their travel limits; none: 3-axis */
    /* Machine components (a .hf model or an .stl mesh, machine
     * coordinates with every joint at 0, where the workpiece frame is the
     * machine frame) on a table link: the caller adds each with
     * fm_check_add_component. component_frame_up is the link: 0 the one
     * that carries the workpiece (the component stays put in the workpiece
     * frame), k the link k table axes nearer the base (the cradle under an
     * AC trunnion's C table: 1; the machine table: every table axis), where
     * the tool is swept in that link's frame (fm_machine.frame_up). */
    int component_count;
    char component_path[FM_CHECK_MAX_COMPONENTS][FM_CHECK_COMPONENT_PATH];
    int component_frame_up[FM_CHECK_MAX_COMPONENTS];
    /* The head's round parts (a spindle nose, a housing: solids of
     * revolution about the spindle), stacked up from the top of each tool's
     * holder (the spindle's face): the part FM_CHECK_PART_HEAD, whose
     * contacts with anything are machine_contact. None: not checked. */
    int head_count;
    fm_holder_segment head[FM_TOOL_MAX_HOLDER];
} fm_check_machine;

typedef struct fm_check_options {
    /* Contact deeper than this is an error, shallower a warning (mm). */
    double tolerance_mm;
    /* Coming within this distance of the stock or a fixture is a warning,
     * per part (mm). The flutes' clearance applies to rapids and fixtures
     * only: feed motions are meant to touch the stock. */
    double clearance_mm[FM_CHECK_PART_COUNT];
    /* A feed motion descending along the tool axis at more than this angle
     * from the plane normal to the axis is a plunge (degrees). */
    double max_ramp_deg;
    fm_check_machine machine;
    /* Evaluations of a tool part a swept volume's search may spend per
     * point (0: lib/sweep's default). Where a search stops at it before its
     * proof closes, and the answer depended on it, the point counts as
     * uncertain. For tests. */
    size_t sweep_evaluations;
} fm_check_options;

void fm_check_options_default(fm_check_options *opt);

/* The band (voxels) a grid of this voxel size needs for these options: the
 * clearances must lie inside it. */
int fm_check_band_voxels(const fm_check_options *opt, double voxel_mm);

typedef struct fm_check_finding {
    fm_check_kind kind;
    fm_check_severity severity;
    fm_check_part part;
    int fixture;            /* FIXTURE_/MACHINE_CONTACT: index of the fixture; else -1 */
    int line;               /* source line where it first happens (0: before the first motion) */
    long block;             /* N number there, -1 if none */
    double time_s;          /* program time of the first contact */
    double position[3];     /* tool tip then */
    double penetration_mm;  /* deepest over the finding (0 for a near miss) */
    double contact[3];      /* first contact point */
    int last_line;          /* source line of the last motion grouped into it */
    long motions;           /* motions grouped into it */
    long points;            /* FM_CHECK_UNCERTAIN: the points left undecided; else 0 */
} fm_check_finding;

typedef struct fm_check fm_check;

/* opt may be NULL (defaults). NULL on error (bad options, out of memory). */
fm_check *fm_check_new(const fm_check_options *opt, fm_error *err);
void fm_check_free(fm_check *check);

/* The stock as first created, as an exact field (a box: positive inside,
 * its true distance): bounds depths beyond the grid's band without a
 * search. Optional. */
void fm_check_set_initial_box(fm_check *check, const double lo[3], const double hi[3]);

/* Where the tool can go (the box of every part over the whole program):
 * fixtures that are not bounded (a table as a half-space) are kept within
 * it, widened by FM_CHECK_FIXTURE_MARGIN_MM. Set it before adding them. */
#define FM_CHECK_FIXTURE_MARGIN_MM 20.0
void fm_check_set_region(fm_check *check, const double lo[3], const double hi[3]);

/* Fixtures become level sets of voxel_mm whose band holds true distances:
 * a HyperFun model (positive inside, any scale: its zero set is the
 * surface; the last or the named object) or a closed STL mesh. Add them
 * before the first motion. */
fm_status fm_check_add_fixture_hf(fm_check *check, const char *path, const char *model_name,
                                  double voxel_mm, fm_error *err);
fm_status fm_check_add_fixture_stl(fm_check *check, const char *path, double voxel_mm,
                                   fm_error *err);
size_t fm_check_fixture_count(const fm_check *check);
/* The machine's component i (options.machine.component_path[i], on the
 * link component_frame_up[i]) as a fixture whose contacts are
 * FM_CHECK_MACHINE_CONTACT: placed after the fixtures the caller added
 * before it, in that order ("fixture" in findings counts both). A
 * component on a link nearer the base than the workpiece's moves against
 * the workpiece: it is checked against motions that carry joint values
 * (G-code; a parametric trajectory carries none and is not checked against
 * it), and G38 probing does not see it. */
fm_status fm_check_add_component(fm_check *check, int i, double voxel_mm, fm_error *err);
/* The largest signed distance (mm, positive inside) at p over the
 * fixtures that stay put in the workpiece frame: the distance to the nearest fixture's surface outside them all.
 * True within the grids' band (32 voxels), and beyond it no larger in size
 * than the truth, so a probe may step by it without crossing a surface.
 * -HUGE_VAL when no fixture lies within the tool's reach. G38 probing
 * (daemon/runner/probe.c) stops at fixtures with it. */
double fm_check_fixture_distance(const fm_check *check, const double p[3]);

/* Check one motion (tool NULL: nothing in the spindle; a feed motion then
 * is related as FM_CHECK_NO_TOOL). stock is the grid
 * with every motion before this one cut, except those fed since the last
 * fm_check_stock_cut (at most FM_CHECK_MAX_PENDING). The motion's flutes
 * then count as not yet cut until the next fm_check_stock_cut. A PARAM
 * motion's path must stay valid until then. */
#define FM_CHECK_MAX_PENDING 1024
fm_status fm_check_motion(fm_check *check, const fm_motion *motion, const fm_tool *tool,
                          const fm_stock *stock, fm_error *err);
/* Where the tool tip's programmed point first goes deeper than min_depth
 * into stock (its distance, positive inside, trilinear, clamped to the
 * band) along motion m (fm_motion_pose_at: every kind, rotary axes
 * included), sampled at least every half voxel: 1 with *u (0..1) the first
 * such sample and *depth the deepest sample, else 0. With no tool in the
 * spindle the spindle's nose goes there (FM_CHECK_NO_TOOL; the job runner's
 * warning for `frepmill simulate`). */
int fm_check_tip_in_stock(const fm_motion *m, const fm_stock *stock, double min_depth, double *u,
                          double *depth);

/* The motions fed so far are now cut from the stock grid. */
void fm_check_stock_cut(fm_check *check);
/* Close the findings still open (call after the last motion). */
void fm_check_finish(fm_check *check);

size_t fm_check_count(const fm_check *check);
const fm_check_finding *fm_check_get(const fm_check *check, size_t i);
size_t fm_check_count_severity(const fm_check *check, fm_check_severity severity);

const char *fm_check_kind_name(fm_check_kind kind);
const char *fm_check_severity_name(fm_check_severity severity);
const char *fm_check_part_name(fm_check_part part);

/* Work done, for benchmarks. */
typedef struct fm_check_stats {
    long motions;
    long relations;       /* part-versus-grid relations evaluated */
    long skipped;         /* relations no region of the grid could answer */
    long regions;         /* leaves and tiles looked at */
    long voxels;          /* voxel centres the part was evaluated at */
    long ordered;         /* of those, evaluated against the flutes' sweep up to a time */
    long depth_searches;  /* depths beyond the band, searched in the grid */
    long uncertain;       /* points a search left undecided (see FM_CHECK_UNCERTAIN) */
} fm_check_stats;
void fm_check_get_stats(const fm_check *check, fm_check_stats *stats);

#endif
