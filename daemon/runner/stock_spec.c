/* stock_spec.c: the one parser of stock specs and the stocks they make
 * (stock_spec.h). */
#include "stock_spec.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "hf/hf.h"
#include "job.h"

/* Stock models given as HyperFun are searched for within this cube (mm). */
#define STOCK_MODEL_SEARCH_MM 2000.0
#define STOCK_MODEL_MAX_BOXES 4000000u
#define STOCK_PI 3.14159265358979323846

/* Parse exactly n comma-separated finite numbers. */
static int parse_numbers(const char *s, double *out, int n)
{
    for (int i = 0; i < n; i++) {
        char *end;
        errno = 0;
        out[i] = strtod(s, &end);
        if (end == s || errno == ERANGE || !isfinite(out[i])) return 0;
        s = end;
        while (isspace((unsigned char)*s)) s++;
        if (i < n - 1) {
            if (*s != ',') return 0;
            s++;
        }
    }
    return *s == '\0';
}

fm_status fm_stock_spec_parse(const char *text, fm_stock_spec *out, fm_error *err)
{
    memset(out, 0, sizeof *out);
    double v[6];
    if (!text || !*text)
        return fm_error_set(err, FM_ERR_INPUT,
                            "no stock given (box:X0,Y0,Z0,X1,Y1,Z1, cylinder:X,Y,Z0,Z1,R, or a "
                            ".hf, .stl or .vdb file)");
    if (!strncmp(text, "box:", 4)) {
        if (!parse_numbers(text + 4, v, 6))
            return fm_error_set(err, FM_ERR_INPUT,
                                "stock '%.200s': expected box:X0,Y0,Z0,X1,Y1,Z1 (six numbers in mm)",
                                text);
        for (int a = 0; a < 3; a++) {
            if (!(v[a] < v[a + 3]))
                return fm_error_set(err, FM_ERR_INPUT,
                                    "stock '%.200s': the box's %c range is empty (%g >= %g); give "
                                    "the lower corner first",
                                    text, "XYZ"[a], v[a], v[a + 3]);
            out->lo[a] = v[a];
            out->hi[a] = v[a + 3];
        }
        out->shape = FM_STOCK_SHAPE_BOX;
        return FM_OK;
    }
    if (!strncmp(text, "cylinder:", 9)) {
        if (!parse_numbers(text + 9, v, 5))
            return fm_error_set(err, FM_ERR_INPUT,
                                "stock '%.200s': expected cylinder:X,Y,Z0,Z1,R (five numbers in mm)",
                                text);
        if (!(v[2] < v[3]) || !(v[4] > 0))
            return fm_error_set(err, FM_ERR_INPUT,
                                "stock '%.200s': the cylinder needs Z0 < Z1 and a radius above 0",
                                text);
        out->shape = FM_STOCK_SHAPE_CYLINDER;
        out->axis[0] = v[0];
        out->axis[1] = v[1];
        out->radius = v[4];
        out->lo[0] = v[0] - v[4];
        out->lo[1] = v[1] - v[4];
        out->lo[2] = v[2];
        out->hi[0] = v[0] + v[4];
        out->hi[1] = v[1] + v[4];
        out->hi[2] = v[3];
        return FM_OK;
    }
    out->path = text;
    if (fm_path_has_extension(text, ".hf")) out->shape = FM_STOCK_SHAPE_HYPERFUN;
    else if (fm_path_has_extension(text, ".stl")) out->shape = FM_STOCK_SHAPE_STL;
    else if (fm_path_has_extension(text, ".vdb")) out->shape = FM_STOCK_SHAPE_SNAPSHOT;
    else
        return fm_error_set(err, FM_ERR_INPUT,
                            "stock '%.200s' is not box:X0,Y0,Z0,X1,Y1,Z1, cylinder:X,Y,Z0,Z1,R, or "
                            "a .hf, .stl or .vdb file",
                            text);
    return FM_OK;
}

double fm_stock_spec_projected_area(const fm_stock_spec *s)
{
    if (s->shape == FM_STOCK_SHAPE_BOX) {
        double dx = s->hi[0] - s->lo[0], dy = s->hi[1] - s->lo[1], dz = s->hi[2] - s->lo[2];
        return 2 * (dx * dy + dy * dz + dx * dz);
    }
    if (s->shape == FM_STOCK_SHAPE_CYLINDER) {
        /* Caps project on z; the side projects to 8 r h on x and y. */
        double r = s->radius, h = s->hi[2] - s->lo[2];
        return 2 * STOCK_PI * r * r + 8 * r * h;
    }
    return -1;
}

static fm_stock *stock_from_model(const char *path, const fm_stock_options *opt, fm_error *err)
{
    fm_graph *g = fm_graph_new(0);
    if (!g) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        return NULL;
    }
    fm_stock *stock = NULL;
    fm_tape *tape = NULL, *raw_tape = NULL;
    fm_evaluator *ev = NULL;
    fm_field field;
    memset(&field, 0, sizeof field);
    fm_hf_model model;
    if (fm_hf_compile_file(g, path, NULL, &model, err) != FM_OK) goto done;
    if (model.dimension > 3) {
        fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                    "the stock model '%s' is %dD; a stock is a 3D object (x[3])", model.name,
                    model.dimension);
        goto done;
    }
    /* HyperFun functions are rarely distances (hfSphere is R^2 - r^2), and
     * the stock's narrow band needs first-order distances: normalize
     * (Shapiro eq. 4.9). */
    fm_node root = fm_normalize(g, model.root);
    if (!root) {
        *err = *fm_graph_error(g);
        goto done;
    }
    tape = fm_tape_compile(g, root, err);
    if (!tape) goto done;
    /* The bounds are searched on the model itself: it has the same sign as
     * its normalization, whose interval bounds are much looser. */
    raw_tape = fm_tape_compile(g, model.root, err);
    if (!raw_tape) goto done;
    ev = fm_evaluator_new(raw_tape, err);
    if (!ev) goto done;
    double voxel = opt && opt->voxel_mm > 0 ? opt->voxel_mm : 0.1;
    fm_inside_bounds s;
    fm_interval start[3];
    for (int a = 0; a < 3; a++) start[a] = (fm_interval){-STOCK_MODEL_SEARCH_MM, STOCK_MODEL_SEARCH_MM};
    double min_size = fmax(voxel, 2 * STOCK_MODEL_SEARCH_MM / 1024.0);
    if (fm_find_inside_bounds(ev, start, min_size, STOCK_MODEL_MAX_BOXES, &s) != FM_OK) {
        fm_error_at(err, FM_ERR_LIMIT, path, 0, 0,
                    "the stock model's boundary is too complex to bound (over %u boxes)",
                    STOCK_MODEL_MAX_BOXES);
        goto done;
    }
    if (!s.found) {
        fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                    "the stock model '%s' is empty within +-%.0f mm", model.name,
                    STOCK_MODEL_SEARCH_MM);
        goto done;
    }
    for (int a = 0; a < 3; a++) {
        if (s.lo[a] <= -STOCK_MODEL_SEARCH_MM || s.hi[a] >= STOCK_MODEL_SEARCH_MM) {
            fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                        "the stock model '%s' is not bounded within +-%.0f mm along %c; "
                        "intersect it with a block",
                        model.name, STOCK_MODEL_SEARCH_MM, "xyz"[a]);
            goto done;
        }
        s.lo[a] -= 4 * voxel;
        s.hi[a] += 4 * voxel;
    }
    if (fm_field_from_tape(&field, tape, s.lo, s.hi, 0.0, err) != FM_OK) goto done;
    stock = fm_stock_new_from_field(&field, opt, err);
    fm_field_release(&field);
done:
    fm_evaluator_free(ev);
    fm_tape_free(raw_tape);
    fm_tape_free(tape);
    fm_graph_free(g);
    return stock;
}

fm_stock *fm_stock_spec_make(const fm_stock_spec *spec, const fm_stock_options *opt,
                             fm_error *err)
{
    switch (spec->shape) {
    case FM_STOCK_SHAPE_BOX: return fm_stock_new_box(spec->lo, spec->hi, opt, err);
    case FM_STOCK_SHAPE_CYLINDER:
        return fm_stock_new_cylinder(spec->axis[0], spec->axis[1], spec->lo[2], spec->hi[2],
                                     spec->radius, opt, err);
    case FM_STOCK_SHAPE_HYPERFUN: return stock_from_model(spec->path, opt, err);
    case FM_STOCK_SHAPE_STL: return fm_stock_new_from_stl(spec->path, opt, err);
    case FM_STOCK_SHAPE_SNAPSHOT: return fm_stock_load_vdb(spec->path, opt, err);
    }
    fm_error_set(err, FM_ERR_INPUT, "no stock given");
    return NULL;
}

fm_stock *fm_job_make_stock(const char *text, const fm_stock_options *opt, fm_error *err)
{
    fm_stock_spec spec;
    if (fm_stock_spec_parse(text, &spec, err) != FM_OK) return NULL;
    return fm_stock_spec_make(&spec, opt, err);
}
