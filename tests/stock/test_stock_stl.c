/* test_stock_stl.c: stock from STL files: binary and ASCII meshes of a box
 * and an octahedron against their closed-form volumes; malformed files
 * (size not matching the triangle count, NaN, garbage, no triangles) and
 * an over-budget mesh are refused with errors that say why, including
 * meshes whose band is far larger than their area says (a sliver found by
 * fuzz_stl, a zero-area triangle, tiny triangles far apart) and
 * coordinates beyond the grid's index range; open surfaces (as stock and
 * as design) are refused where their first open edge is, and closed ones
 * pass however their triangles are wound, with a T-junction too. */
#include "stock/stock.h"
#include "test.h"

#include <stdint.h>
#include <stdlib.h>
#include <unistd.h>

static char dir[256];

typedef struct tri {
    float v[9];
} tri;

static int box_tris(const double lo[3], const double hi[3], tri *out)
{
    /* corners c[i] with bit 0 = x, 1 = y, 2 = z; faces wound outward */
    float c[8][3];
    for (int i = 0; i < 8; i++)
        for (int k = 0; k < 3; k++) c[i][k] = (float)((i >> k & 1) ? hi[k] : lo[k]);
    static const int q[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    int n = 0;
    for (int f = 0; f < 6; f++) {
        const int t[2][3] = {{q[f][0], q[f][1], q[f][2]}, {q[f][0], q[f][2], q[f][3]}};
        for (int j = 0; j < 2; j++, n++)
            for (int v = 0; v < 3; v++) memcpy(out[n].v + 3 * v, c[t[j][v]], sizeof c[0]);
    }
    return n;
}

/* Octahedron |x| + |y| + |z| <= a around c: volume 4/3 a^3. */
static int octa_tris(const double c[3], double a, tri *out)
{
    int n = 0;
    for (int sx = -1; sx <= 1; sx += 2)
        for (int sy = -1; sy <= 1; sy += 2)
            for (int sz = -1; sz <= 1; sz += 2) {
                float p[3][3] = {{(float)(c[0] + sx * a), (float)c[1], (float)c[2]},
                                 {(float)c[0], (float)(c[1] + sy * a), (float)c[2]},
                                 {(float)c[0], (float)c[1], (float)(c[2] + sz * a)}};
                /* outward when sx*sy*sz > 0 in this order; else swap two */
                if (sx * sy * sz < 0) {
                    float t[3];
                    memcpy(t, p[1], sizeof t);
                    memcpy(p[1], p[2], sizeof t);
                    memcpy(p[2], t, sizeof t);
                }
                memcpy(out[n++].v, p, sizeof out[0].v);
            }
    return n;
}

static void put_le32(unsigned char *p, uint32_t v)
{
    for (int i = 0; i < 4; i++) p[i] = (unsigned char)(v >> (8 * i));
}

static void write_binary(const char *path, const tri *t, int n, long size_delta)
{
    FILE *f = fopen(path, "wb");
    unsigned char head[84] = "solid but actually binary";
    put_le32(head + 80, (uint32_t)n);
    fwrite(head, 1, 84, f);
    for (int i = 0; i < n; i++) {
        unsigned char rec[50] = {0};
        for (int k = 0; k < 9; k++) {
            uint32_t u;
            memcpy(&u, &t[i].v[k], 4);
            put_le32(rec + 12 + 4 * k, u);
        }
        fwrite(rec, 1, 50, f);
    }
    if (size_delta > 0)
        for (long i = 0; i < size_delta; i++) fputc(0, f);
    fclose(f);
    if (size_delta < 0) {
        if (truncate(path, 84 + 50L * n + size_delta) != 0) perror("truncate");
    }
}

static void write_ascii(const char *path, const tri *t, int n)
{
    FILE *f = fopen(path, "w");
    fprintf(f, "solid test part\n");
    for (int i = 0; i < n; i++) {
        fprintf(f, "  facet normal 0 0 0\n    outer loop\n");
        for (int v = 0; v < 3; v++)
            fprintf(f, "      vertex %.9g %.9g %.9g\n", t[i].v[3 * v], t[i].v[3 * v + 1],
                    t[i].v[3 * v + 2]);
        fprintf(f, "    endloop\n  endfacet\n");
    }
    fprintf(f, "endsolid test part\n");
    fclose(f);
}

static void write_text(const char *path, const char *text)
{
    FILE *f = fopen(path, "w");
    fputs(text, f);
    fclose(f);
}

static void check_volume(const char *path, double want, double tol)
{
    fm_error err;
    fm_stock_options o;
    fm_stock_options_default(&o);
    o.voxel_mm = 0.1;
    fm_stock *s = fm_stock_new_from_stl(path, &o, &err);
    CHECK(s != NULL);
    if (!s) {
        fprintf(stderr, "%s: %s\n", path, err.message);
        return;
    }
    const double v = fm_stock_volume(s);
    CHECK_NEAR(v, want, tol * want);
    printf("%s: volume %.4f, exact %.4f (%+.4f%%)\n", strrchr(path, '/') + 1, v, want,
           100 * (v - want) / want);
    fm_stock_free(s);
}

static void refused(const char *path, fm_status code, const char *needle, int line)
{
    fm_error err;
    fm_error_clear(&err);
    fm_stock *s = fm_stock_new_from_stl(path, NULL, &err);
    CHECK(s == NULL);
    CHECK(err.code == code);
    CHECK_STR_CONTAINS(err.message, needle);
    if (line) CHECK(err.line == line);
    fm_stock_free(s);
}

/* Refused within a small budget at coarse voxels (as fuzz_stl runs). */
static void refused_small(const char *path, double voxel, size_t budget_mb, fm_status code,
                          const char *needle)
{
    fm_stock_options o;
    fm_stock_options_default(&o);
    o.voxel_mm = voxel;
    o.memory_budget = budget_mb << 20;
    fm_error err;
    fm_error_clear(&err);
    fm_stock *s = fm_stock_new_from_stl(path, &o, &err);
    CHECK(s == NULL);
    if (s)
        fprintf(stderr, "%s: accepted, grid of %.1f MB\n", path,
                (double)fm_stock_memory_bytes(s) / 1048576.0);
    CHECK(err.code == code);
    CHECK_STR_CONTAINS(err.message, needle);
    printf("refusal: %s\n", err.message);
    fm_stock_free(s);
}

/* Meshes whose band is a tube or scattered blobs pass the projected-area
 * estimate; before the leaf count they made grids of 199 MB in a 64 MB
 * budget (the sliver), 47 MB in 16 MB (the line) and 103 MB in 64 MB (the
 * scattered triangles), and the far triangle ran meshToLevelSet for 8 CPU
 * minutes into an empty grid. */
static void test_thin_and_scattered(void)
{
    char p[512];
    /* fuzz_stl's find: a 1 mm wide sliver 98 m long in a closed cube */
    const double lo[3] = {1, 1, 1}, hi[3] = {6, 6, 6};
    tri t[216];
    int n = box_tris(lo, hi, t);
    const float sliver[9] = {6, 1, 1, 6, 0, 1, 98304, 6, 6};
    memcpy(t[10].v, sliver, sizeof sliver);
    snprintf(p, sizeof p, "%s/sliver.stl", dir);
    write_binary(p, t, n, 0);
    refused_small(p, 0.5, 64, FM_ERR_LIMIT, "leaves of 8^3 voxels");
    /* one zero-area triangle along a 10 m line */
    const float line[9] = {0, 0, 0, 5000, 0, 0, 10000, 0, 0};
    memcpy(t[0].v, line, sizeof line);
    snprintf(p, sizeof p, "%s/line.stl", dir);
    write_binary(p, t, 1, 0);
    refused_small(p, 0.5, 16, FM_ERR_LIMIT, "projected surface 0 mm^2");
    /* 216 triangles of 0.5 mm^2, 2.1 m apart: each in internal nodes of its own */
    n = 0;
    for (int i = 0; i < 6; i++)
        for (int j = 0; j < 6; j++)
            for (int k = 0; k < 6; k++, n++) {
                const float x = 2100.0f * i, y = 2100.0f * j, z = 2100.0f * k;
                const float v[9] = {x, y, z, x + 1, y, z, x, y + 1, z};
                memcpy(t[n].v, v, sizeof v);
            }
    snprintf(p, sizeof p, "%s/scattered.stl", dir);
    write_binary(p, t, n, 0);
    refused_small(p, 0.5, 64, FM_ERR_LIMIT, "reaches 1728 leaves");
    /* a small triangle 9 km out at 1 um voxels: index 9e9 is beyond
     * OpenVDB's int32 coordinates */
    const float far[9] = {9e6f, 0, 0, 9e6f + 1, 0, 0, 9e6f, 1, 0};
    memcpy(t[0].v, far, sizeof far);
    snprintf(p, sizeof p, "%s/far.stl", dir);
    write_binary(p, t, 1, 0);
    refused_small(p, 0.001, 64, FM_ERR_INPUT, "beyond the grid's index range");
}

/* OpenVDB's meshToLevelSet signs by flood-filling the outside: through a
 * hole the fill reaches the inside, and an open box was taken as the thin
 * shell of its band (at 0.5 mm, 3,920 of the 150,000 mm^3 its triangles
 * enclose), a single triangle as 0.4 mm^3 of stock: silently, with every
 * later figure wrong. Open surfaces are refused where the first open edge
 * is; closed ones pass however their triangles are wound, thin or not. */
static void test_open_surfaces(void)
{
    char p[512], want[128];
    const double lo[3] = {1.25, -3.5, 0.3}, hi[3] = {13.75, 6.2, 8.85};
    tri t[16], open[12];
    int n = box_tris(lo, hi, t);
    /* without its top face (triangles 2 and 3): the four edges of the top
     * rim are open; the first triangle that has one is the y = lo face's
     * second (corners 0, 5, 4: edge 5-4), the fourth left, on line 2 + 7 * 3
     * of write_ascii's file. About the box's centre the triangles enclose
     * the box but the top face's pyramid, V - A (H / 2) / 3. */
    int m = 0;
    for (int i = 0; i < n; i++)
        if (i != 2 && i != 3) open[m++] = t[i];
    snprintf(p, sizeof p, "%s/open_box.stl", dir);
    write_ascii(p, open, m);
    const double a = (hi[0] - lo[0]) * (hi[1] - lo[1]), ht = hi[2] - lo[2];
    refused(p, FM_ERR_INPUT, "is not a closed surface: 4 of its edges bound one triangle only", 23);
    snprintf(want, sizeof want, "triangles enclose %.1f mm^3", a * ht - a * ht / 6);
    refused(p, FM_ERR_INPUT, want, 23);
    refused(p, FM_ERR_INPUT, "in triangle 4;", 23);
    /* the same as a design */
    fm_stock_options o;
    fm_stock_options_default(&o);
    o.voxel_mm = 0.25;
    fm_error err;
    fm_stock *box = fm_stock_new_box(lo, hi, &o, &err);
    CHECK(box != NULL);
    fm_design *d = box ? fm_design_from_stl(box, p, NULL, &err) : NULL;
    CHECK(d == NULL);
    if (!d) CHECK_STR_CONTAINS(err.message, "the STL design");
    printf("refusal: %s\n", err.message);
    fm_design_free(d);
    fm_stock_free(box);
    /* one triangle, binary: three open edges, no line to name */
    snprintf(p, sizeof p, "%s/one_triangle.stl", dir);
    write_binary(p, t, 1, 0);
    refused(p, FM_ERR_INPUT, "3 of its edges bound one triangle only", 0);
    /* closed but with a T-junction: the top face split at the middle of its
     * edge along y = lo, which the y = lo face does not share (three edges
     * without a twin), holds its volume and passes */
    {
        tri tj[16];
        int k = 0;
        for (int i = 0; i < n; i++)
            if (i != 2 && i != 3) tj[k++] = t[i];
        const float x0 = (float)lo[0], x1 = (float)hi[0], y0 = (float)lo[1], y1 = (float)hi[1],
                    z1 = (float)hi[2], xm = (float)((lo[0] + hi[0]) / 2);
        const float top[3][9] = {{x0, y0, z1, xm, y0, z1, x0, y1, z1},
                                 {xm, y0, z1, x1, y0, z1, x1, y1, z1},
                                 {xm, y0, z1, x1, y1, z1, x0, y1, z1}};
        for (int i = 0; i < 3; i++) memcpy(tj[k++].v, top[i], sizeof top[i]);
        snprintf(p, sizeof p, "%s/t_junction.stl", dir);
        write_binary(p, tj, k, 0);
        check_volume(p, (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]), 0.001);
    }
    /* closed, every other triangle wound inward: the triangles' volume is
     * off (their edges are checked), the grid's is not; it passes, whole */
    for (int i = 1; i < n; i += 2) {
        float v[3];
        memcpy(v, t[i].v + 3, sizeof v);
        memcpy(t[i].v + 3, t[i].v + 6, sizeof v);
        memcpy(t[i].v + 6, v, sizeof v);
    }
    snprintf(p, sizeof p, "%s/flipped.stl", dir);
    write_binary(p, t, n, 0);
    check_volume(p, (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]), 0.001);
    /* closed, but a 0.02 mm cube at 0.1 mm voxels: no voxel centre lies
     * inside it, so the grid holds nothing of it */
    const double tlo[3] = {0.01, 0.01, 0.01}, thi[3] = {0.03, 0.03, 0.03};
    n = box_tris(tlo, thi, t);
    snprintf(p, sizeof p, "%s/speck.stl", dir);
    write_binary(p, t, n, 0);
    refused(p, FM_ERR_INPUT, "encloses no volume at 0.1 mm voxels", 0);
    /* closed and thin: a 0.3 mm plate, three voxels at 0.1 mm */
    const double plo[3] = {0.05, 0.05, 0.05}, phi[3] = {10.05, 10.05, 0.35};
    n = box_tris(plo, phi, t);
    snprintf(p, sizeof p, "%s/plate.stl", dir);
    write_binary(p, t, n, 0);
    check_volume(p, 10 * 10 * 0.3, 0.001);
}

int main(void)
{
    snprintf(dir, sizeof dir, "/tmp/fm-stock-stl-XXXXXX");
    if (!mkdtemp(dir)) return 1;
    char p[512];
    tri t[16];
    const double lo[3] = {1.25, -3.5, 0.3}, hi[3] = {13.75, 6.2, 8.85};
    int n = box_tris(lo, hi, t);
    const double box_vol = (hi[0] - lo[0]) * (hi[1] - lo[1]) * (hi[2] - lo[2]);
    snprintf(p, sizeof p, "%s/box_bin.stl", dir);
    write_binary(p, t, n, 0);
    check_volume(p, box_vol, 0.001);
    snprintf(p, sizeof p, "%s/box_ascii.stl", dir);
    write_ascii(p, t, n);
    check_volume(p, box_vol, 0.001);
    const double c[3] = {2, 3, 4};
    n = octa_tris(c, 6, t);
    snprintf(p, sizeof p, "%s/octa.stl", dir);
    write_binary(p, t, n, 0);
    check_volume(p, 4.0 / 3.0 * 216, 0.001);

    /* malformed */
    snprintf(p, sizeof p, "%s/short.stl", dir);
    write_binary(p, t, n, -10);
    /* the header starts with "solid", but the count decides */
    refused(p, FM_ERR_INPUT, "triangle count (8) does not match its size (474 bytes)", 0);
    snprintf(p, sizeof p, "%s/long.stl", dir);
    write_binary(p, t, n, 7);
    refused(p, FM_ERR_INPUT, "triangle count (8) does not match its size (491 bytes)", 0);
    snprintf(p, sizeof p, "%s/nan.stl", dir);
    t[3].v[4] = NAN;
    write_binary(p, t, n, 0);
    refused(p, FM_ERR_INPUT, "triangle 4", 0);
    snprintf(p, sizeof p, "%s/empty.stl", dir);
    write_binary(p, t, 0, 0);
    refused(p, FM_ERR_INPUT, "no triangles", 0);
    snprintf(p, sizeof p, "%s/bad.stl", dir);
    write_text(p, "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 "
                  "zero\n");
    refused(p, FM_ERR_INPUT, "\"zero\" is not a finite coordinate", 5);
    write_text(p, "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n   vertex 1 0 "
                  "0\n   vertex 0 1 0\n   vertex 1 1 0\n  endloop\n endfacet\nendsolid\n");
    refused(p, FM_ERR_INPUT, "endloop", 7);
    write_text(p, "solid x\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 nan\n");
    refused(p, FM_ERR_INPUT, "not a finite coordinate", 4);
    write_text(p, "hello world, this is no STL at all\n");
    refused(p, FM_ERR_INPUT, "does not start with \"solid\"", 0);
    write_text(p, "solid x\n facet normal 0 0 1\n");
    refused(p, FM_ERR_INPUT, "outer loop", 0);
    snprintf(p, sizeof p, "%s/missing.stl", dir);
    refused(p, FM_ERR_IO, "cannot open", 0);

    /* over budget: a 400 mm cube at 0.1 mm */
    const double blo[3] = {0, 0, 0}, bhi[3] = {400, 400, 400};
    n = box_tris(blo, bhi, t);
    snprintf(p, sizeof p, "%s/big.stl", dir);
    write_binary(p, t, n, 0);
    fm_stock_options o;
    fm_stock_options_default(&o);
    o.memory_budget = (size_t)1 << 30;
    fm_error err;
    CHECK(fm_stock_new_from_stl(p, &o, &err) == NULL);
    CHECK(err.code == FM_ERR_LIMIT);
    CHECK_STR_CONTAINS(err.message, "would need about");
    printf("refusal: %s\n", err.message);

    test_thin_and_scattered();
    test_open_surfaces();

    char cmd[600];
    snprintf(cmd, sizeof cmd, "rm -rf %s", dir);
    if (system(cmd) != 0) return 1;
    return test_summary("stock_stl");
}
