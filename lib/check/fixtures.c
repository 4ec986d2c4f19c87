/* fixtures.c: clamps, vises and tables the tool must not touch, as level
 * sets at the check's voxel whose band holds true distances in millimetres:
 * a HyperFun model through its zero set (whatever the model's scale: a
 * model whose gradient is 0.1 is measured in mm, not in tenths), a closed
 * STL mesh through OpenVDB's mesh-to-volume. The check relates the tool's
 * parts to them as it does to the stock (relate.c). */
#include "check/check_internal.h"

#include <math.h>
#include <stdlib.h>
#include <string.h>

#include "hf/hf.h"

/* HyperFun fixtures are searched for within this cube (mm), in boxes no
 * smaller than this. */
#define CHECK_FIXTURE_SEARCH_MM 2000.0
#define CHECK_FIXTURE_MIN_BOX_MM 8.0
#define CHECK_FIXTURE_MAX_BOXES 2000000u

void check_fixture_free(check_fixture *fx)
{
    fm_stock_free(fx->grid);
    memset(fx, 0, sizeof *fx);
}

size_t fm_check_fixture_count(const fm_check *c) { return c->fixture_count; }

double fm_check_fixture_distance(const fm_check *c, const double p[3])
{
    double best = -HUGE_VAL;
    for (size_t i = 0; i < c->fixture_count; i++) {
        /* a fixture out of the tool's reach has no grid */
        if (!c->fixtures[i].grid) continue;
        double v = fm_stock_sample(c->fixtures[i].grid, p);
        if (v > best) best = v;
    }
    return best;
}

void fm_check_set_region(fm_check *c, const double lo[3], const double hi[3])
{
    c->have_region = 1;
    for (int a = 0; a < 3; a++) {
        c->region_lo[a] = lo[a];
        c->region_hi[a] = hi[a];
    }
}

static check_fixture *new_fixture(fm_check *c, const char *path, fm_error *err)
{
    if (c->started) {
        fm_error_set(err, FM_ERR_INPUT, "fixtures must be added before the first motion");
        return NULL;
    }
    check_fixture *f = realloc(c->fixtures, (c->fixture_count + 1) * sizeof *f);
    if (!f) {
        fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        return NULL;
    }
    c->fixtures = f;
    check_fixture *fx = &f[c->fixture_count];
    memset(fx, 0, sizeof *fx);
    size_t n = strlen(path);
    if (n >= sizeof fx->name) n = sizeof fx->name - 1;
    memcpy(fx->name, path, n);
    return fx;
}

/* A fixture does not change: its grid gets the widest band lib/stock
 * allows, so that depths into it (up to 32 voxels) are read, not searched. */
static void grid_options(const fm_check *c, double voxel_mm, fm_stock_options *so)
{
    (void)c;
    fm_stock_options_default(so);
    if (voxel_mm > 0) so->voxel_mm = voxel_mm;
    so->band_voxels = 32;
}

fm_status fm_check_add_fixture_hf(fm_check *c, const char *path, const char *model_name,
                                  double voxel_mm, fm_error *err)
{
    check_fixture *fx = new_fixture(c, path, err);
    if (!fx) return err ? err->code : FM_ERR_INPUT;
    fm_status st = FM_OK;
    fm_tape *tape = NULL;
    fm_evaluator *ev = NULL;
    fm_field field;
    memset(&field, 0, sizeof field);
    fm_graph *graph = fm_graph_new(0);
    if (!graph) {
        st = fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        goto done;
    }
    fm_hf_model model;
    st = fm_hf_compile_file(graph, path, model_name, &model, err);
    if (st != FM_OK) goto done;
    if (model.dimension > 3) {
        st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                         "the fixture model '%s' is %dD; a fixture is a 3D object (x[3])",
                         model.name, model.dimension);
        goto done;
    }
    tape = fm_tape_compile(graph, model.root, err);
    if (!tape) {
        st = err ? err->code : FM_ERR_INPUT;
        goto done;
    }
    ev = fm_evaluator_new(tape, err);
    if (!ev) {
        st = err ? err->code : FM_ERR_INPUT;
        goto done;
    }
    fm_inside_bounds s;
    fm_interval start[3];
    for (int a = 0; a < 3; a++)
        start[a] = (fm_interval){-CHECK_FIXTURE_SEARCH_MM, CHECK_FIXTURE_SEARCH_MM};
    if (fm_find_inside_bounds(ev, start, CHECK_FIXTURE_MIN_BOX_MM, CHECK_FIXTURE_MAX_BOXES,
                              &s) != FM_OK) {
        st = fm_error_at(err, FM_ERR_LIMIT, path, 0, 0,
                         "the fixture model's boundary is too complex to bound");
        goto done;
    }
    if (!s.found) {
        st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                         "the fixture model '%s' is empty within +-%.0f mm", model.name,
                         CHECK_FIXTURE_SEARCH_MM);
        goto done;
    }
    /* A fixture reaching the search cube's faces is not bounded (a table as
     * a half-space): it is kept within the region the tool can reach, with
     * a margin, so that its artificial faces lie beyond every depth the
     * check measures up to that margin. */
    fm_stock_options so;
    grid_options(c, voxel_mm, &so);
    double lo[3], hi[3];
    for (int a = 0; a < 3; a++) {
        int open_lo = s.lo[a] <= -CHECK_FIXTURE_SEARCH_MM, open_hi = s.hi[a] >= CHECK_FIXTURE_SEARCH_MM;
        if ((open_lo || open_hi) && !c->have_region) {
            st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                             "the fixture model '%s' is not bounded along %c and no region for "
                             "the tool is known; intersect it with a block",
                             model.name, "xyz"[a]);
            goto done;
        }
        double margin = FM_CHECK_FIXTURE_MARGIN_MM;
        lo[a] = open_lo ? c->region_lo[a] - margin : s.lo[a];
        hi[a] = open_hi ? c->region_hi[a] + margin : s.hi[a];
        if (c->have_region) {
            lo[a] = fmax(lo[a], c->region_lo[a] - margin);
            hi[a] = fmin(hi[a], c->region_hi[a] + margin);
        }
        /* room for the band on both sides of the surface */
        lo[a] -= (so.band_voxels + 2) * so.voxel_mm;
        hi[a] += (so.band_voxels + 2) * so.voxel_mm;
        if (!(lo[a] < hi[a])) {
            /* out of the tool's reach: nothing to meet */
            st = FM_OK;
            c->fixture_count++;
            goto done;
        }
    }
    st = fm_field_from_tape(&field, tape, lo, hi, 0.0, err);
    if (st != FM_OK) goto done;
    fx->grid = fm_stock_new_from_zero_set(&field, &so, err);
    fm_field_release(&field);
    if (!fx->grid) {
        st = err ? err->code : FM_ERR_INPUT;
        if (err && !err->file[0]) {
            char msg[sizeof err->message];
            memcpy(msg, err->message, sizeof msg);
            fm_error_at(err, st, path, 0, 0, "the fixture model '%s': %s", model.name, msg);
        }
        goto done;
    }
    c->fixture_count++;
done:
    if (st != FM_OK) check_fixture_free(fx);
    fm_evaluator_free(ev);
    fm_tape_free(tape);
    fm_graph_free(graph);
    return st;
}

void fm_check_set_fixture_machine(fm_check *c, size_t fixture)
{
    if (fixture < c->fixture_count) c->fixtures[fixture].machine = 1;
}

fm_status fm_check_add_fixture_stl(fm_check *c, const char *path, double voxel_mm, fm_error *err)
{
    check_fixture *fx = new_fixture(c, path, err);
    if (!fx) return err ? err->code : FM_ERR_INPUT;
    fm_stock_options so;
    grid_options(c, voxel_mm, &so);
    fx->grid = fm_stock_new_from_stl(path, &so, err);
    if (!fx->grid) return err ? err->code : FM_ERR_INPUT;
    c->fixture_count++;
    return FM_OK;
}
