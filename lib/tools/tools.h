/* tools.h: cutters, shanks and holders. A tool table entry (fm_tool_spec)
 * says what the user declared; lib/tools turns it into F-rep solids of
 * revolution about +Z with the tip at the origin (ARCHITECTURE.md, "Conventions").
 * Parsing of JSON and LinuxCNC .tbl tables lives in toolpaths/tooltable,
 * which fills these plain structs. */
#ifndef FM_TOOLS_H
#define FM_TOOLS_H

#include "core/core.h"

typedef enum fm_tool_shape {
    FM_TOOL_FLAT = 0,  /* flat end mill */
    FM_TOOL_BALL,      /* ball end mill */
    FM_TOOL_BULL,      /* bull nose: corner_radius */
    FM_TOOL_VBIT,      /* V-bit / chamfer: angle (included), tip_diameter */
    FM_TOOL_DRILL,     /* twist drill: point_angle (included) */
    FM_TOOL_TAPERED,   /* tapered: taper_angle per side, tip_radius (0 = flat tip) */
    FM_TOOL_DOVETAIL,  /* dovetail: diameter at the bottom, angle, neck_diameter */
    FM_TOOL_LOLLIPOP,  /* lollipop / undercut: ball of diameter, neck_diameter */
    FM_TOOL_HYPERFUN   /* custom: a HyperFun model in hyperfun_file */
} fm_tool_shape;

#define FM_TOOL_MAX_HOLDER 8

/* One stacked holder segment, from the holder face upward. */
typedef struct fm_holder_segment {
    double diameter;     /* mm, at the bottom of the segment */
    double diameter_top; /* mm, at the top (a cone); equals diameter for a cylinder */
    double length;       /* mm */
} fm_holder_segment;

/* A library's feeds and speeds for a tool (Fusion 360's presets): kept for
 * reports, not used by the simulation. 0 where the library has no value. */
#define FM_TOOL_MAX_PRESETS 4
typedef struct fm_tool_preset {
    char name[48];
    double spindle_rpm;
    double cutting_speed;  /* m/min */
    double feed;           /* cutting feed, mm/min */
    double plunge_feed;    /* mm/min */
    double feed_per_tooth; /* mm */
} fm_tool_preset;

/* Every length in millimetres, every angle in degrees. A field a shape does
 * not use is 0. */
typedef struct fm_tool_spec {
    int number;            /* T number */
    fm_tool_shape shape;
    double diameter;       /* cutting diameter (largest, for dovetail and lollipop) */
    double flute_length;   /* cutting part, measured up from the tip */
    double length;         /* stick-out from the holder face to the tip */
    double shank_diameter; /* default: diameter */
    double corner_radius;  /* bull */
    double angle;          /* vbit: included angle; dovetail: angle of the flank to the axis... see docs/tools.md */
    double tip_diameter;   /* vbit: flat at the tip */
    double point_angle;    /* drill: included point angle (118 typical) */
    double taper_angle;    /* tapered: angle per side */
    double tip_radius;     /* tapered: ball tip radius, 0 for a flat tip */
    double neck_diameter;  /* dovetail and lollipop: diameter of the neck above the cutting part */
    int holder_count;
    fm_holder_segment holder[FM_TOOL_MAX_HOLDER];
    int center_cutting;    /* 1 if the tool can plunge (default 1) */
    double length_offset;  /* the value G43 H<number> applies (LinuxCNC table Z); 0 when the
                              program's Z zero was touched off with this tool */
    char hyperfun_file[256];
    double bound_radius;   /* hyperfun: declared bounding radius */
    char comment[128];     /* the description as the table or library names the tool */
    /* What a CAM library says besides the geometry, for reports (0 / empty
     * when the table does not say). */
    int flute_count;       /* Fusion NOF */
    int length_register;   /* Fusion post-process length-offset: the H register its posts write */
    int diameter_register; /* Fusion post-process diameter-offset: the D register its posts write */
    /* Cutter radius compensation (G41/G42 D): the radius D compensates by,
     * mm (0: half the diameter), and the wear added to it (mm, usually
     * negative), as a control's geometry and wear registers hold them. */
    double radius_offset;
    double radius_wear;
    int preset_count;
    fm_tool_preset presets[FM_TOOL_MAX_PRESETS];
} fm_tool_spec;

typedef struct fm_tool_table {
    size_t count;
    fm_tool_spec *tools; /* owned; free with fm_tool_table_free */
} fm_tool_table;

void fm_tool_table_free(fm_tool_table *table);
/* The entry for tool number n, or NULL. */
const fm_tool_spec *fm_tool_table_find(const fm_tool_table *table, int number);

/* ================================================= cutter geometry ==
 * Everything below turns a tool table entry into solids. Each part (flutes,
 * shank, holder) is a solid of revolution about +Z given by its boundary
 * profile in the (r, z) half-plane: a chain of segments and arcs from the
 * axis at the bottom (0, z_lo) to the axis at the top (0, z_hi), with z never
 * decreasing along the chain, so that the part is {z_lo <= z <= z_hi,
 * r <= R(z)}. Its signed distance at (x, y, z) is the exact 2D signed
 * distance to that region at (sqrt(x^2 + y^2), z), positive inside. Such a
 * distance is 1-Lipschitz and never increases with r (lib/sweep relies on
 * both; docs/tools.md proves the second). */

#include "frep/frep.h"

#define FM_PROFILE_MAX 48

typedef enum fm_profile_kind { FM_PROFILE_SEGMENT = 0, FM_PROFILE_ARC } fm_profile_kind;

/* One element of a profile, from a to b (points (r, z)). An arc has centre c
 * and radius, spans at most a quarter turn, and goes the short way round
 * (ccw is 1 when that is counter-clockwise in the (r, z) plane). */
typedef struct fm_profile_elem {
    fm_profile_kind kind;
    double a[2], b[2];
    double c[2], radius;
    int ccw;
} fm_profile_elem;

/* A custom cutter (HyperFun model or any other function) as the function
 * of (r, z) of the solid the spinning tool sweeps: its solid of revolution
 * (fm_tool_custom_from_tape builds that profile from a 3D model). It must
 * lie in r <= bound_radius, 0 <= z <= bound_length. eval need not be a
 * distance; interval must be a sound enclosure over the (r, z) box.
 * Callbacks run on several threads, each with its own worker (worker_new
 * may be NULL: no per-thread state). release, when set, frees ctx
 * (fm_tool_custom_release). */
typedef struct fm_tool_custom {
    void *ctx;
    void *(*worker_new)(void *ctx);
    void (*worker_free)(void *ctx, void *worker);
    double (*eval)(void *ctx, void *worker, double r, double z);
    fm_interval (*interval)(void *ctx, void *worker, fm_interval r, fm_interval z);
    double bound_radius, bound_length;
    void (*release)(void *ctx);
} fm_tool_custom;

typedef enum fm_tool_part_kind { FM_TOOL_PART_PROFILE = 0, FM_TOOL_PART_CUSTOM } fm_tool_part_kind;

typedef struct fm_tool_part {
    fm_tool_part_kind kind;
    size_t count;                        /* profile elements */
    fm_profile_elem elem[FM_PROFILE_MAX];
    double z_lo, z_hi, r_max;            /* bounding cylinder, tool frame */
    int convex;                          /* the solid is convex */
    double ball_radius;                  /* > 0: the profile is a ball tip under a cylinder of the
                                            same radius, at least 2 radii tall (capsule fast path) */
    double cylinder_radius;              /* > 0: the profile is a plain cylinder (flat end mill): its
                                            distance has a direct formula */
    fm_tool_custom custom;               /* FM_TOOL_PART_CUSTOM */
} fm_tool_part;

typedef struct fm_tool {
    fm_tool_spec spec;
    fm_tool_part flutes; /* cutting part: tip to flute_length */
    fm_tool_part shank;  /* flute_length to length; has_shank = 0 when they are equal */
    fm_tool_part holder; /* from the holder face (z = length) upward; has_holder = 0 without segments */
    int has_shank, has_holder;
} fm_tool;

/* Check a tool table entry: FM_ERR_INPUT with a message naming the tool and
 * the field when a dimension is impossible. */
fm_status fm_tool_validate(const fm_tool_spec *spec, fm_error *err);
/* Build the parts of a standard cutter (every shape but FM_TOOL_HYPERFUN;
 * for that one use fm_tool_build_custom). */
fm_status fm_tool_build(const fm_tool_spec *spec, fm_tool *tool, fm_error *err);
/* The round parts of the machine's head (a spindle nose, a housing: solids
 * of revolution about the spindle) as a part of this tool: the segments
 * stacked up from the top of its holder, where the spindle's face is (the
 * holder face at z = length when it has no holder). For the check. */
fm_status fm_tool_build_head(const fm_tool_spec *spec, const fm_holder_segment *segments, int count,
                             fm_tool_part *head, fm_error *err);
/* A custom cutting part with the shank and holder of spec (spec->shape is
 * FM_TOOL_HYPERFUN; flute_length and bound_radius bound the custom part). */
fm_status fm_tool_build_custom(const fm_tool_spec *spec, const fm_tool_custom *custom,
                               fm_tool *tool, fm_error *err);
/* A custom part over a compiled tape of f(x, y, z) (t = 0): the hook for
 * lib/hf models. The part is the solid of revolution of the model, clipped
 * to the bound: max over the angle t of f(r cos t, r sin t, z), tabulated
 * once here on a 512-cell grid over the longer side of the bound (a few MB
 * at most; docs/tools.md gives its error). The tape is not used afterwards.
 * Free the table with fm_tool_custom_release once no part uses it. */
fm_status fm_tool_custom_from_tape(const fm_tape *tape, double bound_radius, double bound_length,
                                   fm_tool_custom *custom, fm_error *err);
/* Free what custom->release frees (nothing when it is NULL); ctx becomes NULL. */
void fm_tool_custom_release(fm_tool_custom *custom);

/* A part from an explicit profile chain (validated: starts and ends on the
 * axis, continuous, z non-decreasing, r >= 0, arcs consistent). */
fm_status fm_tool_part_from_profile(const fm_profile_elem *elems, size_t n, fm_tool_part *part,
                                    fm_error *err);

/* Per-thread state for evaluating a part (NULL for profile parts, and NULL
 * is accepted by every evaluator for them). */
void *fm_tool_part_worker_new(const fm_tool_part *part);
void fm_tool_part_worker_free(const fm_tool_part *part, void *worker);

/* The exact 2D signed distance at (r, z), r >= 0, and its gradient
 * (d/dr, d/dz) (a supergradient where it has a kink); grad may be NULL. */
double fm_tool_profile_eval(const fm_tool_part *part, void *worker, double r, double z,
                            double grad[2]);
/* The same at n points (r[i], z[i]); fast for the plain cylinder and the
 * ball tip, identical to the point form. */
void fm_tool_profile_eval_batch(const fm_tool_part *part, void *worker, size_t n, const double *r,
                                const double *z, double *out);
/* A sound enclosure of the profile function over [r] x [z] (r >= 0). */
fm_interval fm_tool_profile_interval(const fm_tool_part *part, void *worker, fm_interval r,
                                     fm_interval z);
/* The part in 3D (tool frame). */
double fm_tool_part_eval(const fm_tool_part *part, void *worker, const double p[3]);
void fm_tool_part_eval_batch(const fm_tool_part *part, void *worker, size_t n, const double *x,
                             const double *y, const double *z, double *out);
fm_interval fm_tool_part_interval(const fm_tool_part *part, void *worker,
                                  const fm_interval box[3]);

/* The part as an frep DAG of the nodes r (>= 0) and z: the same exact
 * distance. FM_NONE for custom parts (they are functions already). */
fm_node fm_tool_part_build_rz(fm_graph *g, const fm_tool_part *part, fm_node r, fm_node z);
/* In 3D: r = sqrt(x^2 + y^2). */
fm_node fm_tool_part_build(fm_graph *g, const fm_tool_part *part);

#endif
