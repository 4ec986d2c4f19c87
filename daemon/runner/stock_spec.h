/* stock_spec.h: the one parser of stock specs, shared by the CLI (--stock),
 * the job document, the collision check (its exact initial box) and the
 * daemon's memory estimate before it acknowledges a job; and the stock a
 * spec makes. A spec is "box:X0,Y0,Z0,X1,Y1,Z1", "cylinder:X,Y,Z0,Z1,R"
 * (an upright cylinder, mm) or the path of a model file: HyperFun (.hf),
 * a closed STL mesh (.stl) or a frepmill snapshot (.vdb). */
#ifndef FM_STOCK_SPEC_H
#define FM_STOCK_SPEC_H

#include "core/core.h"
#include "stock/stock.h"

typedef enum fm_stock_shape {
    FM_STOCK_SHAPE_BOX = 1,
    FM_STOCK_SHAPE_CYLINDER,
    FM_STOCK_SHAPE_HYPERFUN,
    FM_STOCK_SHAPE_STL,
    FM_STOCK_SHAPE_SNAPSHOT
} fm_stock_shape;

typedef struct fm_stock_spec {
    fm_stock_shape shape;
    double lo[3], hi[3]; /* box: its corners; cylinder: its bounding box (mm) */
    double axis[2];      /* cylinder: the axis passes through (x, y) */
    double radius;       /* cylinder */
    const char *path;    /* model file: points into the parsed text */
} fm_stock_spec;

/* Parse text; FM_ERR_INPUT with a message naming the expected forms. */
fm_status fm_stock_spec_parse(const char *text, fm_stock_spec *out, fm_error *err);
/* The surface projected on the three axis planes (fm_stock_estimate_bytes'
 * input) of a box or cylinder; -1 for model files (known only once built). */
double fm_stock_spec_projected_area(const fm_stock_spec *spec);
/* Build the stock (lib/stock); NULL with err filled. */
fm_stock *fm_stock_spec_make(const fm_stock_spec *spec, const fm_stock_options *opt,
                             fm_error *err);

#endif
