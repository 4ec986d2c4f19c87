/* stock_spec.c: the one parser of stock specs and the stocks they make
 * (stock_spec.h); the sources themselves are lib/stock's. */
#include "stock_spec.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stddef.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job.h"

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
        return 2 * FM_PI * r * r + 8 * r * h;
    }
    return -1;
}

fm_stock *fm_stock_spec_make(const fm_stock_spec *spec, const fm_stock_options *opt,
                             fm_error *err)
{
    switch (spec->shape) {
    case FM_STOCK_SHAPE_BOX: return fm_stock_new_box(spec->lo, spec->hi, opt, err);
    case FM_STOCK_SHAPE_CYLINDER:
        return fm_stock_new_cylinder(spec->axis[0], spec->axis[1], spec->lo[2], spec->hi[2],
                                     spec->radius, opt, err);
    case FM_STOCK_SHAPE_HYPERFUN: return fm_stock_new_from_hf(spec->path, opt, err);
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
