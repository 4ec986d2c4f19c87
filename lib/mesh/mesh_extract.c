/* mesh_extract.c: the C side of extraction: option defaults, the colour
 * ramps for depth, tool and deviation colouring (and the deviation's key
 * for pictures), and meshing an F-rep field through
 * lib/stock's narrow-band rasterizer (the same one the stock is made with). */
#include "mesh/mesh.h"

#include "frep/frep.h"
#include "stock/stock.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

void fm_mesh_extract_default(fm_mesh_extract_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->adaptivity = 0.0;
    opt->normals = 1;
    opt->coloring = FM_MESH_COLOR_NONE;
    opt->depth_range = 10.0;
    opt->budget.max_vertices = FM_MESH_DEFAULT_MAX_VERTICES;
    opt->budget.max_triangles = FM_MESH_DEFAULT_MAX_TRIANGLES;
}

void fm_mesh_depth_color(double depth, double range, uint8_t rgb[3])
{
    /* Untouched top grey; then blue, cyan, green, yellow, red as the cut
     * goes deeper, so that equal colours mean equal depths at a glance. */
    static const double stops[6][3] = {{200, 200, 200}, {40, 80, 220},  {40, 190, 210},
                                       {60, 190, 60},   {230, 210, 40}, {220, 50, 40}};
    double f = range > 0 ? depth / range : 0;
    if (!(f > 0))
        f = 0;
    if (f > 1)
        f = 1;
    /* The first stop is only the surface itself (depth within 1% of range). */
    double s;
    if (f < 0.01)
        s = f / 0.01;
    else
        s = 1 + (f - 0.01) / 0.99 * 4;
    int i = (int)floor(s);
    if (i >= 5)
        i = 4;
    double t = s - i;
    for (int k = 0; k < 3; k++)
        rgb[k] = (uint8_t)lround(stops[i][k] + t * (stops[i + 1][k] - stops[i][k]));
}

void fm_mesh_tool_color(int tool, uint8_t rgb[3])
{
    /* Twelve distinct hues (tool 0, "no tool" in many controls, still cuts
     * in a simulation and gets one); negative: never cut, the stock's grey. */
    static const uint8_t palette[12][3] = {
        {230, 25, 75},  {60, 180, 75},  {0, 130, 200},  {245, 130, 48},
        {145, 30, 180}, {70, 240, 240}, {240, 50, 230}, {210, 245, 60},
        {250, 190, 190}, {0, 128, 128}, {170, 110, 40}, {128, 0, 0}};
    if (tool < 0) {
        rgb[0] = rgb[1] = rgb[2] = 200;
        return;
    }
    memcpy(rgb, palette[(tool + 11) % 12], 3);
}

static void mix(const uint8_t a[3], const uint8_t b[3], double t, uint8_t rgb[3])
{
    for (int k = 0; k < 3; k++) rgb[k] = (uint8_t)lround(a[k] + t * (b[k] - a[k]));
}

static const uint8_t DEV_GREEN[3] = {40, 170, 60};
static const uint8_t DEV_EXCESS_LIGHT[3] = {140, 190, 255}, DEV_EXCESS_DARK[3] = {20, 40, 170};
static const uint8_t DEV_GOUGE_LIGHT[3] = {255, 150, 130}, DEV_GOUGE_DARK[3] = {170, 0, 0};

void fm_mesh_deviation_color(double deviation, double tolerance, double range, uint8_t rgb[3])
{
    const double a = fabs(deviation);
    if (!(a > tolerance)) { /* NaN counts as on the design */
        memcpy(rgb, DEV_GREEN, 3);
        return;
    }
    double t = range > tolerance ? (a - tolerance) / (range - tolerance) : 1;
    if (t > 1) t = 1;
    if (deviation > 0)
        mix(DEV_EXCESS_LIGHT, DEV_EXCESS_DARK, t, rgb);
    else
        mix(DEV_GOUGE_LIGHT, DEV_GOUGE_DARK, t, rgb);
}

void fm_mesh_deviation_legend(double tolerance, double range, fm_render_legend *legend)
{
    memset(legend, 0, sizeof *legend);
    snprintf(legend->title, sizeof legend->title, "mm");
    if (!(range > tolerance)) range = 2 * tolerance;
    /* enough decimals to print the tolerance as it is (up to 4) */
    int digits = 2;
    while (digits < 4 && fabs(tolerance * pow(10, digits) - round(tolerance * pow(10, digits))) > 1e-6)
        digits++;
    const double values[7] = {range, 0.5 * (range + tolerance), tolerance, 0,
                              -tolerance, -0.5 * (range + tolerance), -range};
    for (int i = 0; i < 7; i++) {
        /* the colour just beyond each value: the tolerance's swatches show
         * the lightest shade, not green */
        fm_mesh_deviation_color(values[i] * (1 + 1e-9), tolerance, range, legend->colors[i]);
        if (values[i] == 0)
            snprintf(legend->labels[i], sizeof legend->labels[i], "0");
        else
            snprintf(legend->labels[i], sizeof legend->labels[i], "%+.*f", digits, values[i]);
    }
    legend->count = 7;
}

fm_mesh *fm_mesh_from_field(const struct fm_field *field, double voxel_mm,
                            const fm_mesh_extract_options *opt, fm_error *err)
{
    if (!(voxel_mm > 0))
        return fm_error_set(err, FM_ERR_INPUT, "voxel size must be positive"), NULL;
    fm_stock_options so;
    fm_stock_options_default(&so);
    so.voxel_mm = voxel_mm;
    fm_stock *stock = fm_stock_new_from_field(field, &so, err);
    if (!stock)
        return NULL;
    fm_mesh *m = fm_mesh_from_stock(stock, opt, err);
    fm_stock_free(stock);
    return m;
}
