/* check.h: collision and safety relations between the moving tool, the
 * stock, fixtures and the machine (issue 8). The caller feeds every motion,
 * in program order, with the stock as it is when that motion starts (the
 * job runner's before_motion hook); the check records findings: rapids into
 * the stock, shank and holder contact, fixture contact, plunges with a tool
 * that cannot cut at its centre, cutting with the spindle stopped, travel
 * limits, and a start position inside the stock.
 *
 * Two solids interfere where the maximum of their R-conjunction (min) is not
 * negative (Pasko 1995 sec. 2.3.3, Shapiro 2007 sec. 6.5). Both fields are
 * distances, so that maximum is the penetration depth. It is computed by a
 * Lipschitz branch-and-bound against an upper bound of the stock's distance
 * (the coarse grid inflated by its interpolation error, tightened by the
 * exact swept volumes of the motions that cut it); docs/check.md argues why
 * no contact deeper than the tolerance is missed. No JSON and no printing
 * here: daemon/runner/findings_json.c writes the findings. */
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
    FM_CHECK_KIND_COUNT
} fm_check_kind;

typedef enum fm_check_severity { FM_CHECK_WARNING = 0, FM_CHECK_ERROR } fm_check_severity;

typedef enum fm_check_part {
    FM_CHECK_PART_FLUTES = 0,
    FM_CHECK_PART_SHANK,
    FM_CHECK_PART_HOLDER,
    FM_CHECK_PART_COUNT
} fm_check_part;

/* A machine: travel limits of the programmed point in machine coordinates,
 * and where the tool tip is before the first motion. */
typedef struct fm_check_machine {
    int has_limit[3];        /* 0: that axis is not limited */
    double limit_lo[3], limit_hi[3];
    double start[3];         /* default: the machine origin */
    double rapid_rate;       /* mm/min; 0: not given (for the caller's job spec) */
    /* Fanuc G28/G30's 1st-4th reference points (mm; not given: the origin),
     * for the caller's job spec; the check itself does not use them. */
    double reference_points[4][3];
    int reference_point_count;
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
    /* How many of the latest cutting motions near a place tighten the
     * stock's distance bound there (0: 64). */
    size_t history_terms;
} fm_check_options;

void fm_check_options_default(fm_check_options *opt);

typedef struct fm_check_finding {
    fm_check_kind kind;
    fm_check_severity severity;
    fm_check_part part;
    int fixture;            /* FM_CHECK_FIXTURE_CONTACT: index of the fixture; else -1 */
    int line;               /* source line where it first happens (0: before the first motion) */
    long block;             /* N number there, -1 if none */
    double time_s;          /* program time of the first contact */
    double position[3];     /* tool tip then */
    double penetration_mm;  /* deepest over the finding (0 for a near miss) */
    double contact[3];      /* first contact point */
    int last_line;          /* source line of the last motion grouped into it */
    long motions;           /* motions grouped into it */
} fm_check_finding;

typedef struct fm_check fm_check;

/* opt may be NULL (defaults). NULL on error (bad options, out of memory). */
fm_check *fm_check_new(const fm_check_options *opt, fm_error *err);
void fm_check_free(fm_check *check);

/* The stock as first created, as an exact field (positive inside, first
 * order, at least the true signed distance): tightens the bound where
 * nothing has cut yet. Optional. */
void fm_check_set_initial_box(fm_check *check, const double lo[3], const double hi[3]);

/* Fixtures: a HyperFun model (distance-like, positive inside; the last or
 * the named object) or a closed STL mesh rasterized at voxel_mm. */
fm_status fm_check_add_fixture_hf(fm_check *check, const char *path, const char *model_name,
                                  fm_error *err);
fm_status fm_check_add_fixture_stl(fm_check *check, const char *path, double voxel_mm,
                                   fm_error *err);
size_t fm_check_fixture_count(const fm_check *check);

/* Check one motion against the stock as it is before the motion cuts
 * (tool NULL: nothing in the spindle). The caller then cuts the motion's
 * flute sweep from the stock, as the job runner does. */
fm_status fm_check_motion(fm_check *check, const fm_motion *motion, const fm_tool *tool,
                          const fm_stock *stock, fm_error *err);
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
    long relations;       /* part-versus-target relations evaluated */
    long skipped;         /* relations skipped by their bounds alone */
    long boxes;           /* branch-and-bound boxes */
} fm_check_stats;
void fm_check_get_stats(const fm_check *check, fm_check_stats *stats);

#endif
