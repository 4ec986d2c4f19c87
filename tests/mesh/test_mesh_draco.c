/* test_mesh_draco.c: Draco round trips through the Draco library itself (our
 * bridge's decoder): triangle count, volume, every decoded vertex within the
 * quantization bound of an original one and back, colours exact, normals
 * within the octahedral quantization; and refusal of bytes that are not
 * Draco. */
#include "fixtures.h"
#include "test.h"

#include <stdlib.h>

/* Brute-force nearest vertex: the meshes here are small. */
static size_t nearest(const fm_mesh *m, const float *p, double *dist)
{
    size_t best = 0;
    double bd = INFINITY;
    for (size_t i = 0; i < m->vertex_count; i++) {
        double d = 0;
        for (int k = 0; k < 3; k++) {
            double e = (double)m->positions[3 * i + k] - p[k];
            d += e * e;
        }
        if (d < bd) {
            bd = d;
            best = i;
        }
    }
    *dist = sqrt(bd);
    return best;
}

static void round_trip(const fm_mesh *m, int bits, int speed, int normals, int colors)
{
    fm_mesh_draco_options o;
    fm_mesh_draco_default(&o);
    o.position_bits = bits;
    o.speed = speed;
    o.with_normals = normals;
    o.with_colors = colors;
    uint8_t *buf = NULL;
    size_t size = 0;
    fm_error err;
    fm_error_clear(&err);
    CHECK(fm_mesh_encode_draco(m, &o, &buf, &size, &err) == FM_OK);
    fm_mesh *d = fm_mesh_decode_draco(buf, size, NULL, &err);
    CHECK(d != NULL);
    if (!d) {
        fprintf(stderr, "decode: %s\n", err.message);
        free(buf);
        return;
    }
    float lo[3], hi[3];
    fm_mesh_bounds(m, lo, hi);
    double bound = fm_mesh_draco_error_bound(lo, hi, bits);
    /* The bound is half a step per axis: compute the step here too. */
    double range = fmax(hi[0] - lo[0], fmax(hi[1] - lo[1], hi[2] - lo[2]));
    CHECK(bound >= sqrt(3.0) * 0.5 * range / (ldexp(1.0, bits) - 1));
    CHECK(d->triangle_count == m->triangle_count);
    CHECK((d->normals != NULL) == (normals && m->normals));
    CHECK((d->colors != NULL) == (colors && m->colors));
    double worst = 0;
    for (size_t i = 0; i < d->vertex_count; i++) {
        double dist;
        size_t j = nearest(m, d->positions + 3 * i, &dist);
        worst = fmax(worst, dist);
        if (d->colors)
            for (int k = 0; k < 3; k++)
                CHECK(d->colors[3 * i + k] == m->colors[3 * j + k]);
        if (d->normals) {
            double c = 0;
            for (int k = 0; k < 3; k++)
                c += (double)d->normals[3 * i + k] * m->normals[3 * j + k];
            CHECK(c > cos(3.0 * FM_DEG)); /* 8-bit octahedral: about 1 degree */
        }
    }
    for (size_t i = 0; i < m->vertex_count; i++) {
        double dist;
        nearest(d, m->positions + 3 * i, &dist);
        worst = fmax(worst, dist);
    }
    CHECK(worst <= bound);
    if (!(worst <= bound))
        fprintf(stderr, "bits %d: error %g over bound %g\n", bits, worst, bound);
    /* Orientation survives: the volume keeps its sign and size. */
    CHECK_NEAR(fm_mesh_volume(d), fm_mesh_volume(m), fabs(fm_mesh_volume(m)) * 1e-2);
    fm_mesh_topology t;
    fm_mesh_topology_check(d, &t, NULL);
    CHECK(t.boundary_edges == 0 && t.misoriented_edges == 0 && t.nonmanifold_edges == 0);
    free(buf);
    fm_mesh_free(d);
}

static size_t encoded_size(const fm_mesh *m, int bits)
{
    fm_mesh_draco_options o;
    fm_mesh_draco_default(&o);
    o.position_bits = bits;
    o.with_normals = o.with_colors = 0;
    uint8_t *buf = NULL;
    size_t size = 0;
    fm_mesh_encode_draco(m, &o, &buf, &size, NULL);
    free(buf);
    return size;
}

int main(void)
{
    const double c[3] = {10, -20, 5};
    fm_mesh *sphere = fixture_sphere(c, 25, 24, 48);
    for (int bits = 8; bits <= 20; bits += 4)
        for (int speed = 0; speed <= 10; speed += 5)
            round_trip(sphere, bits, speed, 1, 1);
    round_trip(sphere, 14, 7, 0, 1);
    round_trip(sphere, 14, 7, 1, 0);
    const float lo[3] = {0, 0, 0}, hi[3] = {100, 50, 20};
    fm_mesh *box = fixture_box(lo, hi);
    round_trip(box, 11, 5, 1, 1);

    /* More bits, more bytes. */
    CHECK(encoded_size(sphere, 8) < encoded_size(sphere, 16));

    fm_error err;
    fm_error_clear(&err);
    fm_mesh_draco_options o;
    fm_mesh_draco_default(&o);
    o.speed = 11;
    uint8_t *buf = NULL;
    size_t size = 0;
    CHECK(fm_mesh_encode_draco(sphere, &o, &buf, &size, &err) == FM_ERR_INPUT);
    o.speed = 5;
    o.position_bits = 0;
    CHECK(fm_mesh_encode_draco(sphere, &o, &buf, &size, &err) == FM_ERR_INPUT);

    /* Not Draco: refused, not crashed; and a truncated stream likewise. */
    uint8_t junk[64];
    for (size_t i = 0; i < sizeof junk; i++)
        junk[i] = (uint8_t)(i * 37 + 11);
    CHECK(fm_mesh_decode_draco(junk, sizeof junk, NULL, &err) == NULL);
    CHECK(err.code == FM_ERR_INPUT);
    CHECK(fm_mesh_encode_draco(sphere, NULL, &buf, &size, &err) == FM_OK);
    CHECK(fm_mesh_decode_draco(buf, size / 2, NULL, &err) == NULL);
    /* A budget smaller than the mesh is refused. */
    fm_mesh_budget small = {100, 100};
    CHECK(fm_mesh_decode_draco(buf, size, &small, &err) == NULL && err.code == FM_ERR_LIMIT);
    free(buf);

    fm_mesh_free(box);
    fm_mesh_free(sphere);
    return test_summary("mesh_draco");
}
