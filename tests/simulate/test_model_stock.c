/* test_model_stock.c: a HyperFun stock builds in memory proportional to its
 * area, not its volume (issue 19). Spheres of radius 5 and 10 mm (hfSphere,
 * R^2 - r^2: not a distance, so the builder's normalization is exercised)
 * at 0.05 mm voxels: the model's interval over boxes widened by the band
 * must find the interior, so that the grid holds only the leaves along the
 * surface. Doubling the radius multiplies the area by 4 and the volume by
 * 8: the grid's bytes must grow by about 4. Each stock's volume must also
 * be the sphere's, 4/3 pi R^3, and it must build within a memory budget
 * of twice fm_stock_estimate_bytes of the sphere's projected area 6 pi R^2
 * (the formula of docs/stock.md, for a band of leaves along a surface):
 * the budget is checked against the leaves the interval pass finds before
 * any is made, so a builder that does not find the interior is refused. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "job.h"
#include "test.h"

#define VOXEL 0.05

static size_t sphere_bytes(double radius, const char *dir)
{
    char path[512];
    snprintf(path, sizeof path, "%s/sphere%g.hf", dir, radius);
    FILE *f = fopen(path, "w");
    CHECK(f != NULL);
    if (!f) return 0;
    fprintf(f, "sphere(x[3], a[1])\n{\n  array c[3];\n  c = [1, 2, 3];\n  sphere = hfSphere(x, c, %g);\n}\n",
            radius);
    fclose(f);
    const size_t estimate = fm_stock_estimate_bytes(6 * FM_PI * radius * radius, VOXEL, 3);
    fm_stock_options opt;
    fm_stock_options_default(&opt);
    opt.voxel_mm = VOXEL;
    /* the build is refused when the leaves it would make exceed the budget
     * (counted before they are made): twice the area's estimate fits a
     * band along the surface, not the whole ball (about 65,000 leaves for
     * R 10, far more bytes) */
    opt.memory_budget = 2 * estimate;
    fm_error err;
    fm_stock *s = fm_job_make_stock(path, &opt, &err);
    remove(path);
    if (!s) {
        char buf[700];
        fprintf(stderr, "stock: %s\n", fm_error_format(&err, buf, sizeof buf));
        CHECK(s != NULL);
        return 0;
    }
    const double exact = 4.0 / 3.0 * FM_PI * radius * radius * radius;
    const double volume = fm_stock_volume(s);
    const size_t bytes = fm_stock_memory_bytes(s);
    printf("sphere R %g at %g mm: volume %.2f mm3 (exact %.2f), grid %.2f MB, area estimate %.2f MB\n",
           radius, VOXEL, volume, exact, bytes / 1048576.0, estimate / 1048576.0);
    CHECK(fabs(volume - exact) <= 0.002 * exact);
    CHECK(bytes <= 2 * estimate);
    fm_stock_free(s);
    return bytes;
}

int main(void)
{
    char dir[] = "/tmp/fm-model-stock-XXXXXX";
    if (!mkdtemp(dir)) {
        perror("mkdtemp");
        return 1;
    }
    size_t small = sphere_bytes(5, dir), large = sphere_bytes(10, dir);
    rmdir(dir);
    double ratio = small ? (double)large / (double)small : 0;
    printf("bytes ratio R 10 / R 5: %.2f (area ratio 4, volume ratio 8)\n", ratio);
    /* the leaves along the surface make the grid: 4 within 25%; a grid
     * holding the interior too would be near 8 */
    CHECK(ratio >= 3 && ratio <= 5);
    return test_summary("model stock memory");
}
