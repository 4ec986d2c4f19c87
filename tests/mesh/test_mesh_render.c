/* test_mesh_render.c: the software renderer against geometry computed here
 * from the view documented in mesh.h: background corners, each visible face's
 * centre pixel shaded with its own Lambert value, the silhouette's extent
 * equal to the projected bounding box within a pixel, per-vertex colours and
 * normals, the toolpath overlay, and the PNG file read back with stb_image. */
#include "fixtures.h"
#include "test.h"

#include <stdlib.h>
#include <unistd.h>

#define STB_IMAGE_IMPLEMENTATION
#include <stb_image.h>

typedef struct view {
    double scale, cx, cy;
    int w, h;
} view;

static const double R[3] = {0.70710678118654752, 0.70710678118654752, 0};
static const double U[3] = {-0.40824829046386302, 0.40824829046386302, 0.81649658092772603};

static double dot(const double *a, const double *b) { return a[0] * b[0] + a[1] * b[1] + a[2] * b[2]; }

/* Fit the projections of pts (n points) as mesh.h says. */
static view fit(const double *pts, size_t n, int w, int h, int margin)
{
    double lo[2] = {INFINITY, INFINITY}, hi[2] = {-INFINITY, -INFINITY};
    for (size_t i = 0; i < n; i++) {
        double s[2] = {dot(pts + 3 * i, R), dot(pts + 3 * i, U)};
        for (int k = 0; k < 2; k++) {
            lo[k] = fmin(lo[k], s[k]);
            hi[k] = fmax(hi[k], s[k]);
        }
    }
    view v;
    v.scale = fmin((w - 2.0 * margin) / (hi[0] - lo[0]), (h - 2.0 * margin) / (hi[1] - lo[1]));
    v.cx = 0.5 * (lo[0] + hi[0]);
    v.cy = 0.5 * (lo[1] + hi[1]);
    v.w = w;
    v.h = h;
    return v;
}

static void to_pixel(const view *v, const double p[3], double *x, double *y)
{
    *x = 0.5 * v->w + (dot(p, R) - v->cx) * v->scale;
    *y = 0.5 * v->h - (dot(p, U) - v->cy) * v->scale;
}

static const uint8_t *pixel(const uint8_t *rgb, int w, double x, double y)
{
    return rgb + 3 * ((size_t)floor(y) * w + (size_t)floor(x));
}

static double lambert(const fm_render_options *o, const double n[3])
{
    double l = sqrt(dot(o->light, o->light));
    double c = dot(n, o->light) / l;
    return o->ambient + (1 - o->ambient) * (c > 0 ? c : 0);
}

static int is_bg(const uint8_t *p, const uint8_t bg[3])
{
    return p[0] == bg[0] && p[1] == bg[1] && p[2] == bg[2];
}

static void test_box(int antialias)
{
    const float lo[3] = {0, 0, 0}, hi[3] = {4, 3, 2};
    fm_mesh *m = fixture_box(lo, hi);
    fm_render_options o;
    fm_render_default(&o);
    o.width = 240;
    o.height = 180;
    o.margin = 12;
    o.antialias = antialias;
    uint8_t *rgb = malloc((size_t)o.width * o.height * 3);
    CHECK(fm_render_rgb(m, &o, rgb, NULL) == FM_OK);

    double corners[24];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++)
            corners[3 * i + k] = (i >> k) & 1 ? hi[k] : lo[k];
    view v = fit(corners, 8, o.width, o.height, o.margin);

    CHECK(is_bg(pixel(rgb, o.width, 0, 0), o.background));
    CHECK(is_bg(pixel(rgb, o.width, o.width - 1, 0), o.background));
    CHECK(is_bg(pixel(rgb, o.width, 0, o.height - 1), o.background));
    CHECK(is_bg(pixel(rgb, o.width, o.width - 1, o.height - 1), o.background));

    /* Visible faces from (1, -1, 1): +z, -y, +x. */
    const double tol = antialias > 1 ? 2 : 1;
    struct { double c[3], n[3]; } faces[3] = {
        {{2, 1.5, 2}, {0, 0, 1}}, {{2, 0, 1}, {0, -1, 0}}, {{4, 1.5, 1}, {1, 0, 0}}};
    double shades[3];
    for (int f = 0; f < 3; f++) {
        double x, y;
        to_pixel(&v, faces[f].c, &x, &y);
        const uint8_t *p = pixel(rgb, o.width, x, y);
        shades[f] = lambert(&o, faces[f].n);
        for (int k = 0; k < 3; k++)
            CHECK_NEAR(p[k], o.base_color[k] * shades[f], tol);
    }
    /* The three faces are told apart by their shades. */
    CHECK(fabs(shades[0] - shades[1]) > 0.05 && fabs(shades[1] - shades[2]) > 0.05);

    /* Silhouette extent against the projected corners. */
    int x0 = o.width, x1 = -1, y0 = o.height, y1 = -1;
    for (int y = 0; y < o.height; y++)
        for (int x = 0; x < o.width; x++)
            if (!is_bg(rgb + 3 * ((size_t)y * o.width + x), o.background)) {
                if (x < x0) x0 = x;
                if (x > x1) x1 = x;
                if (y < y0) y0 = y;
                if (y > y1) y1 = y;
            }
    double ex0 = INFINITY, ex1 = -INFINITY, ey0 = INFINITY, ey1 = -INFINITY;
    for (int i = 0; i < 8; i++) {
        double x, y;
        to_pixel(&v, corners + 3 * i, &x, &y);
        ex0 = fmin(ex0, x), ex1 = fmax(ex1, x), ey0 = fmin(ey0, y), ey1 = fmax(ey1, y);
    }
    CHECK_NEAR(x0, ex0, 1.0);
    CHECK_NEAR(x1 + 1, ex1, 1.0);
    CHECK_NEAR(y0, ey0, 1.0);
    CHECK_NEAR(y1 + 1, ey1, 1.0);
    /* The fit touches the margin on the binding axis. */
    CHECK(fabs(ex0 - o.margin) < 1e-6 || fabs(ey0 - o.margin) < 1e-6);

    /* Colours per vertex replace the base colour. */
    fm_mesh *cm = fm_mesh_new(8, 12, FM_MESH_COLORS, NULL, NULL);
    fm_mesh_append(cm, m, NULL);
    for (size_t i = 0; i < cm->vertex_count; i++) {
        cm->colors[3 * i] = 250;
        cm->colors[3 * i + 1] = 10;
        cm->colors[3 * i + 2] = 0;
    }
    CHECK(fm_render_rgb(cm, &o, rgb, NULL) == FM_OK);
    {
        double x, y;
        to_pixel(&v, faces[0].c, &x, &y);
        const uint8_t *p = pixel(rgb, o.width, x, y);
        CHECK_NEAR(p[0], 250 * shades[0], tol);
        CHECK_NEAR(p[1], 10 * shades[0], tol);
        CHECK(p[2] == 0);
    }

    /* PNG file read back by stb_image equals the buffer. */
    char path[96];
    snprintf(path, sizeof path, "/tmp/fm_test_render_%d.png", (int)getpid());
    CHECK(fm_render_png(cm, &o, path, NULL) == FM_OK);
    int w = 0, h = 0, ch = 0;
    uint8_t *back = stbi_load(path, &w, &h, &ch, 3);
    CHECK(back && w == o.width && h == o.height);
    if (back)
        CHECK(memcmp(back, rgb, (size_t)w * h * 3) == 0);
    stbi_image_free(back);
    remove(path);

    fm_mesh_free(cm);
    free(rgb);
    fm_mesh_free(m);
}

static void test_sphere_normals(void)
{
    const double c[3] = {0, 0, 0};
    fm_mesh *m = fixture_sphere(c, 10, 48, 96);
    fm_render_options o;
    fm_render_default(&o);
    o.width = o.height = 200;
    o.antialias = 1;
    fm_mesh *plain = fm_mesh_new(0, 0, FM_MESH_NORMALS, NULL, NULL);
    fm_mesh_append(plain, m, NULL); /* normals kept, colours dropped */
    uint8_t *rgb = malloc(200 * 200 * 3);
    CHECK(fm_render_rgb(plain, &o, rgb, NULL) == FM_OK);
    /* The point nearest the eye has the normal towards the eye. */
    double d[3] = {1 / sqrt(3.0), -1 / sqrt(3.0), 1 / sqrt(3.0)};
    const uint8_t *p = rgb + 3 * (100 * 200 + 100);
    for (int k = 0; k < 3; k++)
        CHECK_NEAR(p[k], o.base_color[k] * lambert(&o, d), 3);
    /* Where the light hits head-on, the shade is full: find the brightest
     * pixel and compare with base colour times 1. */
    int best = 0;
    for (int i = 0; i < 200 * 200; i++)
        if (rgb[3 * i + 2] > best && !(rgb[3 * i] == 255 && rgb[3 * i + 1] == 255))
            best = rgb[3 * i + 2];
    CHECK_NEAR(best, o.base_color[2], 3);
    free(rgb);
    fm_mesh_free(plain);
    fm_mesh_free(m);
}

static void test_overlay(void)
{
    const float lo[3] = {0, 0, 0}, hi[3] = {4, 4, 1};
    fm_mesh *m = fixture_box(lo, hi);
    double feed[6] = {-1, 2, 3, 5, 2, 3};
    double rapid[6] = {2, -1, 4, 2, 5, 4};
    fm_render_polyline paths[2] = {{feed, 2, 0}, {rapid, 2, 1}};
    fm_render_options o;
    fm_render_default(&o);
    o.width = 300;
    o.height = 300;
    o.antialias = 1;
    o.paths = paths;
    o.path_count = 2;
    uint8_t *rgb = malloc(300 * 300 * 3);
    CHECK(fm_render_rgb(m, &o, rgb, NULL) == FM_OK);
    double pts[8 * 3 + 12];
    int n = 0;
    for (int i = 0; i < 8; i++, n++)
        for (int k = 0; k < 3; k++)
            pts[3 * n + k] = (i >> k) & 1 ? hi[k] : lo[k];
    for (int i = 0; i < 2; i++, n++)
        for (int k = 0; k < 3; k++)
            pts[3 * n + k] = feed[3 * i + k];
    for (int i = 0; i < 2; i++, n++)
        for (int k = 0; k < 3; k++)
            pts[3 * n + k] = rapid[3 * i + k];
    view v = fit(pts, (size_t)n, 300, 300, o.margin);
    /* Feeds: solid, every sample along the line has the feed colour. */
    int feed_hits = 0, samples = 0;
    for (int i = 1; i < 20; i++) {
        double q[3], x, y;
        for (int k = 0; k < 3; k++)
            q[k] = feed[k] + (feed[3 + k] - feed[k]) * i / 20.0;
        to_pixel(&v, q, &x, &y);
        const uint8_t *p = pixel(rgb, 300, x, y);
        samples++;
        feed_hits += p[0] == o.feed_color[0] && p[1] == o.feed_color[1] && p[2] == o.feed_color[2];
    }
    CHECK(feed_hits == samples);
    /* Rapids: dashed, so some samples have the colour and some do not. */
    int on = 0, off = 0;
    for (int i = 1; i < 200; i++) {
        double q[3], x, y;
        for (int k = 0; k < 3; k++)
            q[k] = rapid[k] + (rapid[3 + k] - rapid[k]) * i / 200.0;
        to_pixel(&v, q, &x, &y);
        const uint8_t *p = pixel(rgb, 300, x, y);
        if (p[0] == o.rapid_color[0] && p[1] == o.rapid_color[1] && p[2] == o.rapid_color[2])
            on++;
        else
            off++;
    }
    CHECK(on > 40 && off > 40);

    fm_error err;
    fm_error_clear(&err);
    o.antialias = 9;
    CHECK(fm_render_rgb(m, &o, rgb, &err) == FM_ERR_INPUT);
    o.antialias = 1;
    o.width = 0;
    CHECK(fm_render_png(m, &o, "/tmp/never.png", &err) == FM_ERR_INPUT);
    free(rgb);
    fm_mesh_free(m);
}

int main(void)
{
    test_box(1);
    test_box(2);
    test_sphere_normals();
    test_overlay();
    return test_summary("mesh_render");
}
