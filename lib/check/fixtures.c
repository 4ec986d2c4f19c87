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
        /* a fixture out of the tool's reach has no grid; a component
         * moving against the workpiece is not where its grid says */
        if (!c->fixtures[i].grid || c->fixtures[i].frame_up) continue;
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

static fm_status add_stl(fm_check *c, const char *path, const char *what, double voxel_mm,
                         fm_error *err)
{
    check_fixture *fx = new_fixture(c, path, err);
    if (!fx) return err ? err->code : FM_ERR_INPUT;
    fm_stock_options so;
    grid_options(c, voxel_mm, &so);
    fx->grid = fm_stock_new_from_stl_named(path, what, &so, err);
    if (!fx->grid) return err ? err->code : FM_ERR_INPUT;
    c->fixture_count++;
    return FM_OK;
}

/* Where the tool can go, seen from the link frame_up table axes nearer
 * the base: the region's bounding ball turned about the inner table axes'
 * lines by any angle, innermost first (x_link = R_{j+1} ... R_n
 * x_workpiece, each line at home), lies in the ball about the centre's
 * foot on the line grown by the centre's distance from it. */
static void frame_region(const fm_check *c, int frame_up, double lo[3], double hi[3])
{
    const fm_machine *mc = &c->opt.machine.chain;
    double ctr[3], rad = 0;
    for (int a = 0; a < 3; a++) {
        ctr[a] = 0.5 * (c->region_lo[a] + c->region_hi[a]);
        rad += 0.25 * (c->region_hi[a] - c->region_lo[a]) * (c->region_hi[a] - c->region_lo[a]);
    }
    rad = sqrt(rad);
    for (int i = mc->rotary_count - 1, t = 0; i >= 0 && t < frame_up; i--) {
        const fm_rotary_axis *ax = &mc->rotary[i];
        if (ax->carries != FM_ROTARY_TABLE) continue;
        t++;
        double along = 0, d = 0, foot[3];
        for (int a = 0; a < 3; a++) along += (ctr[a] - ax->through[a]) * ax->around[a];
        for (int a = 0; a < 3; a++) {
            foot[a] = ax->through[a] + along * ax->around[a];
            d += (ctr[a] - foot[a]) * (ctr[a] - foot[a]);
        }
        rad += sqrt(d);
        memcpy(ctr, foot, sizeof ctr);
    }
    for (int a = 0; a < 3; a++) {
        lo[a] = ctr[a] - rad * (1 + 1e-12) - 1e-9;
        hi[a] = ctr[a] + rad * (1 + 1e-12) + 1e-9;
    }
}

fm_status fm_check_add_component(fm_check *c, int i, double voxel_mm, fm_error *err)
{
    const fm_check_machine *mc = &c->opt.machine;
    if (i < 0 || i >= mc->component_count || i >= FM_CHECK_MAX_COMPONENTS)
        return fm_error_set(err, FM_ERR_INPUT, "the machine has no component %d", i);
    const char *path = mc->component_path[i];
    int up = mc->component_frame_up[i], ntable = fm_machine_table_axes(&mc->chain);
    if (up < 0 || up > ntable)
        return fm_error_set(err, FM_ERR_INPUT,
                            "component %s: its link lies %d table axes below the workpiece's, of %d", path, up,
                            ntable);
    size_t len = strlen(path);
    int hf = len > 3 && !strcmp(path + len - 3, ".hf");
    /* A HyperFun component that is not bounded (a table as a half-space)
     * is kept within where the tool can go, seen from its own link. */
    int had_region = c->have_region;
    double keep_lo[3], keep_hi[3];
    memcpy(keep_lo, c->region_lo, sizeof keep_lo);
    memcpy(keep_hi, c->region_hi, sizeof keep_hi);
    if (up > 0 && had_region) {
        double lo[3], hi[3];
        frame_region(c, up, lo, hi);
        fm_check_set_region(c, lo, hi);
    }
    size_t before = c->fixture_count;
    fm_status st = hf ? fm_check_add_fixture_hf(c, path, NULL, voxel_mm, err)
                      : add_stl(c, path, "machine component", voxel_mm, err);
    c->have_region = had_region;
    memcpy(c->region_lo, keep_lo, sizeof keep_lo);
    memcpy(c->region_hi, keep_hi, sizeof keep_hi);
    if (st != FM_OK) return st;
    if (c->fixture_count > before) {
        c->fixtures[before].machine = 1;
        c->fixtures[before].frame_up = up;
    }
    return FM_OK;
}

fm_status fm_check_add_fixture_stl(fm_check *c, const char *path, double voxel_mm, fm_error *err)
{
    return add_stl(c, path, "fixture", voxel_mm, err);
}
