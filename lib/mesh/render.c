/* render.c: a software renderer for preview pictures, no display or GPU:
 * isometric orthographic view with Z up, z-buffer, Lambert plus ambient
 * shading, per-vertex colours, an optional toolpath overlay (feeds solid,
 * rapids dashed), supersampling anti-aliasing, an optional colour key with
 * a tiny built-in font, and a PNG writer (stb). */
#include "mesh/mesh.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#define STB_IMAGE_WRITE_IMPLEMENTATION
#define STB_IMAGE_WRITE_STATIC
#include <stb_image_write.h>

/* The view basis documented in mesh.h. */
static const double VIEW_RIGHT[3] = {0.70710678118654752, 0.70710678118654752, 0.0};
static const double VIEW_UP[3] = {-0.40824829046386302, 0.40824829046386302,
                                  0.81649658092772603};
static const double VIEW_TOWARD_EYE[3] = {0.57735026918962576, -0.57735026918962576,
                                          0.57735026918962576};

void fm_render_default(fm_render_options *opt)
{
    memset(opt, 0, sizeof *opt);
    opt->width = 800;
    opt->height = 600;
    opt->margin = 16;
    opt->antialias = 2;
    opt->background[0] = opt->background[1] = opt->background[2] = 255;
    opt->base_color[0] = 176;
    opt->base_color[1] = 190;
    opt->base_color[2] = 210;
    opt->light[0] = 0.3;
    opt->light[1] = -0.5;
    opt->light[2] = 1.0;
    opt->ambient = 0.25;
    opt->feed_color[2] = 220;
    opt->feed_color[1] = 60;
    opt->rapid_color[0] = 220;
    opt->dash_pixels = 6.0;
}

static double dot3(const double a[3], const double b[3])
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}

typedef struct canvas {
    int w, h, ss;       /* supersampled size and factor */
    double scale;       /* supersampled pixels per mm */
    double cx, cy;      /* projected centre of the scene, mm */
    float *depth;       /* larger is nearer the eye */
    float *color;       /* 3 per sample, 0..255 */
    double light[3];    /* unit */
    double ambient;
    /* The view basis in the mesh's frame: the fixed basis turned back by
     * the scene's rotation (x_view = R x, so v . R x = (R^T v) . x). */
    double right[3], up[3], eye[3];
} canvas;

/* Screen position (supersampled pixels, y down) and depth of a point. */
static void project(const canvas *c, const double p[3], double s[3])
{
    s[0] = 0.5 * c->w + (dot3(p, c->right) - c->cx) * c->scale;
    s[1] = 0.5 * c->h - (dot3(p, c->up) - c->cy) * c->scale;
    s[2] = dot3(p, c->eye);
}

/* out = R^T v (R row-major; NULL is the identity). */
static void turn_back(const double *R, const double v[3], double out[3])
{
    for (int a = 0; a < 3; a++)
        out[a] = R ? R[a] * v[0] + R[3 + a] * v[1] + R[6 + a] * v[2] : v[a];
}

static double shade_of(const canvas *c, double n[3])
{
    double len = sqrt(dot3(n, n));
    if (len <= 0)
        return c->ambient;
    /* Two-sided: an open chunk mesh seen from behind is lit like its front. */
    if (dot3(n, c->eye) < 0)
        len = -len;
    double l = dot3(n, c->light) / len;
    return c->ambient + (1.0 - c->ambient) * (l > 0 ? l : 0);
}

static void draw_triangle(canvas *c, const fm_mesh *m, size_t t, const uint8_t base[3])
{
    double s[3][3], pos[3][3];
    uint32_t vi[3];
    for (int k = 0; k < 3; k++) {
        vi[k] = m->triangles[3 * t + k];
        for (int a = 0; a < 3; a++)
            pos[k][a] = m->positions[3 * (size_t)vi[k] + a];
        project(c, pos[k], s[k]);
    }
    double area = (s[1][0] - s[0][0]) * (s[2][1] - s[0][1]) -
                  (s[2][0] - s[0][0]) * (s[1][1] - s[0][1]);
    if (area == 0 || !isfinite(area))
        return;
    double fn[3];
    {
        double u[3], v[3];
        for (int a = 0; a < 3; a++) {
            u[a] = pos[1][a] - pos[0][a];
            v[a] = pos[2][a] - pos[0][a];
        }
        fn[0] = u[1] * v[2] - u[2] * v[1];
        fn[1] = u[2] * v[0] - u[0] * v[2];
        fn[2] = u[0] * v[1] - u[1] * v[0];
    }
    double flat = shade_of(c, fn);
    int x0 = (int)floor(fmin(s[0][0], fmin(s[1][0], s[2][0])));
    int x1 = (int)ceil(fmax(s[0][0], fmax(s[1][0], s[2][0])));
    int y0 = (int)floor(fmin(s[0][1], fmin(s[1][1], s[2][1])));
    int y1 = (int)ceil(fmax(s[0][1], fmax(s[1][1], s[2][1])));
    if (x0 < 0)
        x0 = 0;
    if (y0 < 0)
        y0 = 0;
    if (x1 > c->w - 1)
        x1 = c->w - 1;
    if (y1 > c->h - 1)
        y1 = c->h - 1;
    for (int y = y0; y <= y1; y++) {
        double py = y + 0.5;
        for (int x = x0; x <= x1; x++) {
            double px = x + 0.5;
            /* Barycentric weights; a sample on an edge belongs to both
             * neighbours, which the z test resolves identically. */
            double w0 = ((s[1][0] - px) * (s[2][1] - py) - (s[2][0] - px) * (s[1][1] - py)) / area;
            double w1 = ((s[2][0] - px) * (s[0][1] - py) - (s[0][0] - px) * (s[2][1] - py)) / area;
            double w2 = 1.0 - w0 - w1;
            if (w0 < 0 || w1 < 0 || w2 < 0)
                continue;
            double z = w0 * s[0][2] + w1 * s[1][2] + w2 * s[2][2];
            size_t i = (size_t)y * c->w + x;
            if (z <= c->depth[i])
                continue;
            c->depth[i] = (float)z;
            double sh = flat;
            if (m->normals) {
                double n[3];
                for (int a = 0; a < 3; a++)
                    n[a] = w0 * m->normals[3 * (size_t)vi[0] + a] +
                           w1 * m->normals[3 * (size_t)vi[1] + a] +
                           w2 * m->normals[3 * (size_t)vi[2] + a];
                sh = shade_of(c, n);
            }
            for (int a = 0; a < 3; a++) {
                double col = base[a];
                if (m->colors)
                    col = w0 * m->colors[3 * (size_t)vi[0] + a] +
                          w1 * m->colors[3 * (size_t)vi[1] + a] +
                          w2 * m->colors[3 * (size_t)vi[2] + a];
                c->color[3 * i + a] = (float)(col * sh);
            }
        }
    }
}

/* A polyline as a band about one final pixel wide, depth-tested with a bias
 * of two pixels so that a path lying on the surface it cut stays visible. */
static void draw_polyline(canvas *c, const fm_render_polyline *pl, const uint8_t rgb[3],
                          double dash)
{
    double run = 0; /* length drawn so far, final pixels, for the dash phase */
    double bias = 2.0 * c->ss / c->scale;
    double half = 0.5 * c->ss;
    for (size_t k = 0; k + 1 < pl->count; k++) {
        double a[3], b[3];
        project(c, pl->points + 3 * k, a);
        project(c, pl->points + 3 * k + 3, b);
        double dx = b[0] - a[0], dy = b[1] - a[1];
        double len = sqrt(dx * dx + dy * dy);
        int steps = (int)ceil(len * 2) + 1;
        for (int i = 0; i <= steps; i++) {
            double f = (double)i / steps;
            double along = run + f * len / c->ss;
            if (pl->rapid && fmod(along, 2 * dash) >= dash)
                continue;
            double x = a[0] + f * dx, y = a[1] + f * dy, z = a[2] + f * (b[2] - a[2]) + bias;
            for (int yy = (int)floor(y - half); yy < (int)ceil(y + half); yy++)
                for (int xx = (int)floor(x - half); xx < (int)ceil(x + half); xx++) {
                    if (xx < 0 || yy < 0 || xx >= c->w || yy >= c->h)
                        continue;
                    size_t p = (size_t)yy * c->w + xx;
                    if (z < c->depth[p])
                        continue;
                    for (int ch = 0; ch < 3; ch++)
                        c->color[3 * p + ch] = rgb[ch];
                }
        }
        run += len / c->ss;
    }
}

static void draw_legend(uint8_t *rgb, int w, int h, const fm_render_legend *l);

fm_status fm_render_rgb(const fm_mesh *mesh, const fm_render_options *opt_in, uint8_t *rgb,
                        fm_error *err)
{
    fm_render_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        fm_render_default(&opt);
    if (opt.width < 1 || opt.height < 1 || opt.width > 16384 || opt.height > 16384)
        return fm_error_set(err, FM_ERR_INPUT, "picture size %dx%d is not in 1..16384",
                            opt.width, opt.height);
    if (opt.antialias < 1 || opt.antialias > 4)
        return fm_error_set(err, FM_ERR_INPUT, "anti-aliasing factor %d is not in 1..4",
                            opt.antialias);
    if (opt.margin < 0 || 2 * opt.margin >= opt.width || 2 * opt.margin >= opt.height)
        return fm_error_set(err, FM_ERR_INPUT, "margin %d leaves no picture", opt.margin);

    canvas c;
    turn_back(opt.rotation, VIEW_RIGHT, c.right);
    turn_back(opt.rotation, VIEW_UP, c.up);
    turn_back(opt.rotation, VIEW_TOWARD_EYE, c.eye);

    /* Projected bounds of everything drawn. */
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (size_t i = 0; mesh && i < mesh->vertex_count; i++) {
        double p[3] = {mesh->positions[3 * i], mesh->positions[3 * i + 1],
                       mesh->positions[3 * i + 2]};
        double sx = dot3(p, c.right), sy = dot3(p, c.up);
        lo[0] = fmin(lo[0], sx), hi[0] = fmax(hi[0], sx);
        lo[1] = fmin(lo[1], sy), hi[1] = fmax(hi[1], sy);
    }
    for (size_t k = 0; k < opt.path_count; k++)
        for (size_t i = 0; i < opt.paths[k].count; i++) {
            const double *p = opt.paths[k].points + 3 * i;
            double sx = dot3(p, c.right), sy = dot3(p, c.up);
            lo[0] = fmin(lo[0], sx), hi[0] = fmax(hi[0], sx);
            lo[1] = fmin(lo[1], sy), hi[1] = fmax(hi[1], sy);
        }

    c.ss = opt.antialias;
    c.w = opt.width * c.ss;
    c.h = opt.height * c.ss;
    c.ambient = fmin(1.0, fmax(0.0, opt.ambient));
    double ll = sqrt(dot3(opt.light, opt.light));
    if (!(ll > 0))
        return fm_error_set(err, FM_ERR_INPUT, "light direction is zero");
    /* the light stays with the viewer, so it turns back with the view */
    double light[3];
    for (int a = 0; a < 3; a++)
        light[a] = opt.light[a] / ll;
    turn_back(opt.rotation, light, c.light);
    if (lo[0] <= hi[0]) {
        double ex = hi[0] - lo[0], ey = hi[1] - lo[1];
        double sx = ex > 0 ? (opt.width - 2.0 * opt.margin) / ex : INFINITY;
        double sy = ey > 0 ? (opt.height - 2.0 * opt.margin) / ey : INFINITY;
        c.scale = fmin(sx, sy);
        if (!isfinite(c.scale))
            c.scale = 1.0;
        c.scale *= c.ss;
        c.cx = 0.5 * (lo[0] + hi[0]);
        c.cy = 0.5 * (lo[1] + hi[1]);
    } else {
        c.scale = c.ss;
        c.cx = c.cy = 0;
    }

    size_t n = (size_t)c.w * c.h;
    c.depth = malloc(n * sizeof *c.depth);
    c.color = malloc(3 * n * sizeof *c.color);
    if (!c.depth || !c.color) {
        free(c.depth);
        free(c.color);
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory for a %dx%d picture", opt.width,
                            opt.height);
    }
    for (size_t i = 0; i < n; i++) {
        c.depth[i] = -INFINITY;
        for (int a = 0; a < 3; a++)
            c.color[3 * i + a] = opt.background[a];
    }
    for (size_t t = 0; mesh && t < mesh->triangle_count; t++)
        draw_triangle(&c, mesh, t, opt.base_color);
    for (size_t k = 0; k < opt.path_count; k++)
        draw_polyline(&c, &opt.paths[k], opt.paths[k].rapid ? opt.rapid_color : opt.feed_color,
                      opt.dash_pixels > 0 ? opt.dash_pixels : 6.0);

    /* Box filter down to the final size. */
    double inv = 1.0 / (c.ss * c.ss);
    for (int y = 0; y < opt.height; y++)
        for (int x = 0; x < opt.width; x++)
            for (int a = 0; a < 3; a++) {
                double sum = 0;
                for (int j = 0; j < c.ss; j++)
                    for (int i = 0; i < c.ss; i++)
                        sum += c.color[3 * ((size_t)(y * c.ss + j) * c.w + x * c.ss + i) + a];
                double v = floor(sum * inv + 0.5);
                rgb[3 * ((size_t)y * opt.width + x) + a] =
                    (uint8_t)(v < 0 ? 0 : v > 255 ? 255 : v);
            }
    free(c.depth);
    free(c.color);
    if (opt.legend) draw_legend(rgb, opt.width, opt.height, opt.legend);
    return FM_OK;
}

/* ------------------------------------------------------------ legend -- */

/* 5 x 7 glyphs, one row per byte, bit 4 the leftmost pixel. */
static const struct glyph {
    char c;
    uint8_t rows[7];
} GLYPHS[] = {
    {'0', {0x0e, 0x11, 0x13, 0x15, 0x19, 0x11, 0x0e}},
    {'1', {0x04, 0x0c, 0x04, 0x04, 0x04, 0x04, 0x0e}},
    {'2', {0x0e, 0x11, 0x01, 0x02, 0x04, 0x08, 0x1f}},
    {'3', {0x1f, 0x02, 0x04, 0x02, 0x01, 0x11, 0x0e}},
    {'4', {0x02, 0x06, 0x0a, 0x12, 0x1f, 0x02, 0x02}},
    {'5', {0x1f, 0x10, 0x1e, 0x01, 0x01, 0x11, 0x0e}},
    {'6', {0x06, 0x08, 0x10, 0x1e, 0x11, 0x11, 0x0e}},
    {'7', {0x1f, 0x01, 0x02, 0x04, 0x08, 0x08, 0x08}},
    {'8', {0x0e, 0x11, 0x11, 0x0e, 0x11, 0x11, 0x0e}},
    {'9', {0x0e, 0x11, 0x11, 0x0f, 0x01, 0x02, 0x0c}},
    {'.', {0x00, 0x00, 0x00, 0x00, 0x00, 0x0c, 0x0c}},
    {'+', {0x00, 0x04, 0x04, 0x1f, 0x04, 0x04, 0x00}},
    {'-', {0x00, 0x00, 0x00, 0x1f, 0x00, 0x00, 0x00}},
    {'m', {0x00, 0x00, 0x1a, 0x15, 0x15, 0x11, 0x11}},
};

#define LEGEND_PX 2 /* screen pixels per font pixel */

static size_t bounded_length(const char *s, size_t max)
{
    size_t n = 0;
    while (n < max && s[n]) n++;
    return n;
}

static void fill_rect(uint8_t *rgb, int w, int h, int x0, int y0, int x1, int y1,
                      const uint8_t c[3])
{
    for (int y = y0 < 0 ? 0 : y0; y < y1 && y < h; y++)
        for (int x = x0 < 0 ? 0 : x0; x < x1 && x < w; x++)
            memcpy(rgb + 3 * ((size_t)y * w + x), c, 3);
}

static void draw_text(uint8_t *rgb, int w, int h, int x, int y, const char *text,
                      const uint8_t c[3])
{
    for (; *text; text++, x += 6 * LEGEND_PX) {
        const struct glyph *g = NULL;
        for (size_t i = 0; i < sizeof GLYPHS / sizeof GLYPHS[0]; i++)
            if (GLYPHS[i].c == *text) g = &GLYPHS[i];
        if (!g) continue;
        for (int r = 0; r < 7; r++)
            for (int b = 0; b < 5; b++)
                if (g->rows[r] >> (4 - b) & 1)
                    fill_rect(rgb, w, h, x + b * LEGEND_PX, y + r * LEGEND_PX,
                              x + (b + 1) * LEGEND_PX, y + (r + 1) * LEGEND_PX, c);
    }
}

/* The key in the top-left corner, on a white panel with a grey border. */
static void draw_legend(uint8_t *rgb, int w, int h, const fm_render_legend *l)
{
    static const uint8_t white[3] = {255, 255, 255}, grey[3] = {150, 150, 150},
                         ink[3] = {30, 30, 30};
    const size_t n = l->count < FM_RENDER_LEGEND_MAX ? l->count : FM_RENDER_LEGEND_MAX;
    size_t chars = bounded_length(l->title, sizeof l->title);
    for (size_t i = 0; i < n; i++) {
        const size_t c = bounded_length(l->labels[i], sizeof l->labels[i]);
        if (c + 4 > chars) chars = c + 4;
    }
    const int line = 9 * LEGEND_PX, x0 = 6, y0 = 6;
    const int pw = (int)chars * 6 * LEGEND_PX + 12, ph = (int)(n + 1) * line + 12;
    fill_rect(rgb, w, h, x0, y0, x0 + pw, y0 + ph, grey);
    fill_rect(rgb, w, h, x0 + 1, y0 + 1, x0 + pw - 1, y0 + ph - 1, white);
    char title[sizeof l->title + 1];
    memcpy(title, l->title, sizeof l->title);
    title[sizeof l->title] = '\0';
    draw_text(rgb, w, h, x0 + 6, y0 + 6, title, ink);
    for (size_t i = 0; i < n; i++) {
        const int y = y0 + 6 + (int)(i + 1) * line;
        fill_rect(rgb, w, h, x0 + 6, y, x0 + 6 + 3 * 6 * LEGEND_PX - 4, y + line - 2, l->colors[i]);
        char label[sizeof l->labels[i] + 1];
        memcpy(label, l->labels[i], sizeof l->labels[i]);
        label[sizeof l->labels[i]] = '\0';
        draw_text(rgb, w, h, x0 + 6 + 4 * 6 * LEGEND_PX, y + LEGEND_PX / 2, label, ink);
    }
}

typedef struct png_sink {
    uint8_t *data;
    size_t size;
    int failed;
} png_sink;

static void png_collect(void *ctx, void *data, int size)
{
    png_sink *s = ctx;
    if (s->failed || size <= 0)
        return;
    uint8_t *q = realloc(s->data, s->size + (size_t)size);
    if (!q) {
        s->failed = 1;
        return;
    }
    memcpy(q + s->size, data, (size_t)size);
    s->data = q;
    s->size += (size_t)size;
}

fm_status fm_render_png(const fm_mesh *mesh, const fm_render_options *opt_in, const char *path,
                        fm_error *err)
{
    fm_render_options opt;
    if (opt_in)
        opt = *opt_in;
    else
        fm_render_default(&opt);
    if (opt.width < 1 || opt.height < 1 || opt.width > 16384 || opt.height > 16384)
        return fm_error_set(err, FM_ERR_INPUT, "picture size %dx%d is not in 1..16384",
                            opt.width, opt.height);
    uint8_t *rgb = malloc((size_t)opt.width * opt.height * 3);
    if (!rgb)
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory for a picture");
    fm_status st = fm_render_rgb(mesh, &opt, rgb, err);
    if (st == FM_OK) {
        png_sink sink = {0};
        if (!stbi_write_png_to_func(png_collect, &sink, opt.width, opt.height, 3, rgb,
                                    opt.width * 3) ||
            sink.failed)
            st = fm_error_set(err, FM_ERR_LIMIT, "PNG encoding failed (out of memory)");
        else
            st = fm_file_write_durable(path, NULL, sink.data, sink.size, err);
        free(sink.data);
    }
    free(rgb);
    return st;
}
