/* job_check.c: the collision check beside the cut: its options, region,
 * fixtures and machine components, and the grid it reads (the job's own,
 * or a twin at the check's voxel). */
#include <math.h>
#include <string.h>

#include "job_internal.h"
#include "stock_spec.h"

/* "box:X0,Y0,Z0,X1,Y1,Z1": the check gets the exact initial stock. */
static int box_of_spec(const char *spec, double lo[3], double hi[3])
{
    fm_stock_spec shape;
    if (!spec || fm_stock_spec_parse(spec, &shape, NULL) != FM_OK ||
        shape.shape != FM_STOCK_SHAPE_BOX)
        return 0;
    memcpy(lo, shape.lo, sizeof shape.lo);
    memcpy(hi, shape.hi, sizeof shape.hi);
    return 1;
}

/* The check, its grid and fixtures, for a job whose stock is made. */
fm_status job_check_setup(job_cutter *c, const job_survey *sv, fm_error *err)
{
    const fm_job_check *jc = c->spec->check;
    double voxel = jc->voxel_mm > 0 ? jc->voxel_mm : FM_JOB_CHECK_VOXEL;
    int band = fm_check_band_voxels(&jc->options, voxel);
    if (band > 32)
        return fm_error_set(err, FM_ERR_INPUT,
                            "the check's clearances need a band of %d voxels of %g mm (at most "
                            "32): use a larger check voxel or smaller clearances",
                            band, voxel);
    /* where the interpreter starts, the check starts (the one start) */
    fm_check_options options = jc->options;
    if (c->spec->has_start)
        memcpy(options.machine.start, c->spec->start, sizeof options.machine.start);
    c->check = fm_check_new(&options, err);
    if (!c->check) return err ? err->code : FM_ERR_INPUT;
    double lo[3], hi[3];
    if (box_of_spec(c->spec->stock_spec, lo, hi)) fm_check_set_initial_box(c->check, lo, hi);
    if (sv->any_tip) {
        /* where any part of any tool can go: the tip's box grown by the
         * largest tool */
        double up = 0, out = 0;
        for (size_t i = 0; i < c->tools->count; i++) {
            const fm_tool *t = &c->tools->built[i].tool;
            const fm_tool_part *parts[3] = {&t->flutes, t->has_shank ? &t->shank : NULL,
                                            t->has_holder ? &t->holder : NULL};
            for (int k = 0; k < 3; k++)
                if (parts[k]) {
                    up = fmax(up, fmax(fabs(parts[k]->z_lo), fabs(parts[k]->z_hi)));
                    out = fmax(out, parts[k]->r_max);
                }
        }
        double reach = sqrt(up * up + out * out);
        for (int a = 0; a < 3; a++) {
            lo[a] = sv->tip_lo[a] - reach;
            hi[a] = sv->tip_hi[a] + reach;
        }
        fm_check_set_region(c->check, lo, hi);
    }
    for (int i = 0; i < jc->fixture_count; i++) {
        const char *f = jc->fixtures[i];
        fm_status st = fm_path_has_extension(f, ".hf")
                           ? fm_check_add_fixture_hf(c->check, f, NULL, voxel, err)
                       : fm_path_has_extension(f, ".stl")
                           ? fm_check_add_fixture_stl(c->check, f, voxel, err)
                           : fm_error_set(err, FM_ERR_INPUT,
                                          "fixture %s: give a .hf model or an .stl mesh", f);
        if (st != FM_OK) return st;
    }
    /* the machine's components: fixtures whose contacts are
     * machine_contact, on their link */
    for (int i = 0; i < jc->options.machine.component_count; i++) {
        fm_status st = fm_check_add_component(c->check, i, voxel, err);
        if (st != FM_OK) return st;
    }
    fm_stock_options own = c->spec->stock, defaults;
    fm_stock_options_default(&defaults);
    if (own.voxel_mm <= 0) own.voxel_mm = defaults.voxel_mm;
    if (own.band_voxels <= 0) own.band_voxels = defaults.band_voxels;
    if (!c->spec->resume_stock && fabs(own.voxel_mm - voxel) <= 1e-12 * voxel &&
        own.band_voxels == band) {
        c->check_grid = c->stock;
        return FM_OK;
    }
    own.voxel_mm = voxel;
    own.band_voxels = band;
    c->check_grid = fm_job_make_stock(c->spec->stock_spec, &own, err);
    if (!c->check_grid) return err ? err->code : FM_ERR_INPUT;
    c->check_twin = 1;
    return FM_OK;
}

void job_check_free(job_cutter *c)
{
    if (c->check_twin) fm_stock_free(c->check_grid);
    c->check_grid = NULL;
    c->check_twin = 0;
    fm_check_free(c->check);
    c->check = NULL;
}
