/* fixtures.c: clamps, vises and tables the tool must not touch, given as
 * HyperFun models (evaluated exactly, with interval bounds) or closed STL
 * meshes (rasterized to a level set and read like the stock). */
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
    fm_evaluator_free(fx->ev);
    fm_tape_free(fx->tape);
    fm_graph_free(fx->graph);
    fm_stock_free(fx->grid);
    memset(fx, 0, sizeof *fx);
}

size_t fm_check_fixture_count(const fm_check *c) { return c->fixture_count; }

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

fm_status fm_check_add_fixture_hf(fm_check *c, const char *path, const char *model_name,
                                  fm_error *err)
{
    check_fixture *fx = new_fixture(c, path, err);
    if (!fx) return err ? err->code : FM_ERR_INPUT;
    fm_status st = FM_OK;
    fx->graph = fm_graph_new(0);
    if (!fx->graph) {
        st = fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        goto fail;
    }
    fm_hf_model model;
    st = fm_hf_compile_file(fx->graph, path, model_name, &model, err);
    if (st != FM_OK) goto fail;
    if (model.dimension > 3) {
        st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                         "the fixture model '%s' is %dD; a fixture is a 3D object (x[3])",
                         model.name, model.dimension);
        goto fail;
    }
    fx->tape = fm_tape_compile(fx->graph, model.root, err);
    if (!fx->tape) {
        st = err ? err->code : FM_ERR_INPUT;
        goto fail;
    }
    fx->ev = fm_evaluator_new(fx->tape, err);
    if (!fx->ev) {
        st = err ? err->code : FM_ERR_INPUT;
        goto fail;
    }
    fm_inside_bounds s;
    fm_interval start[3];
    for (int a = 0; a < 3; a++)
        start[a] = (fm_interval){-CHECK_FIXTURE_SEARCH_MM, CHECK_FIXTURE_SEARCH_MM};
    if (fm_find_inside_bounds(fx->ev, start, CHECK_FIXTURE_MIN_BOX_MM, CHECK_FIXTURE_MAX_BOXES,
                              &s) != FM_OK) {
        st = fm_error_at(err, FM_ERR_LIMIT, path, 0, 0,
                         "the fixture model's boundary is too complex to bound");
        goto fail;
    }
    if (!s.found) {
        st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "the fixture model '%s' is empty within +-%.0f mm",
                         model.name, CHECK_FIXTURE_SEARCH_MM);
        goto fail;
    }
    /* A fixture reaching the search cube's faces is unbounded (a table as
     * a half-space): keep those sides open. */
    for (int a = 0; a < 3; a++) {
        fx->lo[a] = s.lo[a] <= -CHECK_FIXTURE_SEARCH_MM ? -INFINITY : s.lo[a];
        fx->hi[a] = s.hi[a] >= CHECK_FIXTURE_SEARCH_MM ? INFINITY : s.hi[a];
    }
    c->fixture_count++;
    return FM_OK;
fail:
    check_fixture_free(fx);
    return st;
}

fm_status fm_check_add_fixture_stl(fm_check *c, const char *path, double voxel_mm, fm_error *err)
{
    check_fixture *fx = new_fixture(c, path, err);
    if (!fx) return err ? err->code : FM_ERR_INPUT;
    fm_stock_options so;
    fm_stock_options_default(&so);
    if (voxel_mm > 0) so.voxel_mm = voxel_mm;
    fx->grid = fm_stock_new_from_stl(path, &so, err);
    if (!fx->grid) return err ? err->code : FM_ERR_INPUT;
    check_grid g;
    if (!check_grid_init(&g, fx->grid)) {
        check_fixture_free(fx);
        return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "the fixture mesh is empty");
    }
    memcpy(fx->lo, g.lo, sizeof fx->lo);
    memcpy(fx->hi, g.hi, sizeof fx->hi);
    c->fixture_count++;
    return FM_OK;
}
