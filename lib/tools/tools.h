/* tools.h: cutters, shanks and holders. A tool table entry (fm_tool_spec)
 * says what the user declared; lib/tools turns it into F-rep solids of
 * revolution about +Z with the tip at the origin (DESIGN.md sec. 2).
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
    char comment[128];
} fm_tool_spec;

typedef struct fm_tool_table {
    size_t count;
    fm_tool_spec *tools; /* owned; free with fm_tool_table_free */
} fm_tool_table;

void fm_tool_table_free(fm_tool_table *table);
/* The entry for tool number n, or NULL. */
const fm_tool_spec *fm_tool_table_find(const fm_tool_table *table, int number);

#endif
