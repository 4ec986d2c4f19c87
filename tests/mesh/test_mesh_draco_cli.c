/* test_mesh_draco_cli.c: our Draco files open in Debian's draco_decoder (a
 * separate program, not our bridge): it decodes a .drc we wrote to OBJ, and
 * the OBJ (parsed here) has our triangle count and every vertex within the
 * quantization bound of one of ours. Skips without the tool (test_skip). */
#include "fixtures.h"
#include "test.h"

#include <stdlib.h>
#include <unistd.h>

#define DECODER "/usr/bin/draco_decoder"

int main(void)
{
    if (access(DECODER, X_OK) != 0)
        return test_skip("mesh_draco_cli: " DECODER " is not installed (Debian package draco)");
    const double c[3] = {3, 4, -5};
    fm_mesh *m = fixture_sphere(c, 12, 16, 32);
    char drc[96], obj[96], cmd[400];
    snprintf(drc, sizeof drc, "/tmp/fm_test_draco_%d.drc", (int)getpid());
    snprintf(obj, sizeof obj, "/tmp/fm_test_draco_%d.obj", (int)getpid());
    fm_mesh_draco_options o;
    fm_mesh_draco_default(&o);
    o.position_bits = 14;
    fm_error err;
    fm_error_clear(&err);
    CHECK(fm_mesh_write_draco(m, &o, drc, &err) == FM_OK);
    snprintf(cmd, sizeof cmd, DECODER " -i %s -o %s > /dev/null 2>&1", drc, obj);
    CHECK(system(cmd) == 0);

    float lo[3], hi[3];
    fm_mesh_bounds(m, lo, hi);
    double bound = fm_mesh_draco_error_bound(lo, hi, o.position_bits);
    FILE *f = fopen(obj, "r");
    CHECK(f != NULL);
    size_t nv = 0, nf = 0;
    double worst = 0;
    char line[512];
    while (f && fgets(line, sizeof line, f)) {
        float p[3];
        if (line[0] == 'v' && line[1] == ' ' && sscanf(line + 2, "%f %f %f", &p[0], &p[1], &p[2]) == 3) {
            double best = INFINITY;
            for (size_t i = 0; i < m->vertex_count; i++) {
                double d = 0;
                for (int k = 0; k < 3; k++)
                    d += pow((double)m->positions[3 * i + k] - p[k], 2);
                best = fmin(best, d);
            }
            worst = fmax(worst, sqrt(best));
            nv++;
        } else if (line[0] == 'f' && line[1] == ' ') {
            nf++;
        }
    }
    if (f)
        fclose(f);
    CHECK(nv >= m->vertex_count);
    CHECK(nf == m->triangle_count);
    CHECK(worst <= bound);
    printf("draco_decoder: %zu vertices, %zu faces, max error %.3g mm (bound %.3g)\n", nv, nf,
           worst, bound);
    remove(drc);
    remove(obj);
    fm_mesh_free(m);
    return test_summary("mesh_draco_cli");
}
