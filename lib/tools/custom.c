/* custom.c: the hook for custom cutters given as an frep tape (HyperFun
 * models compiled by lib/hf): evaluates the model's section y = 0, x = r
 * through a per-thread fm_evaluator. */
#include "tools/tools.h"

static void *tape_worker_new(void *ctx)
{
    return fm_evaluator_new((const fm_tape *)ctx, NULL);
}

static void tape_worker_free(void *ctx, void *worker)
{
    (void)ctx;
    fm_evaluator_free((fm_evaluator *)worker);
}

static double tape_eval(void *ctx, void *worker, double r, double z)
{
    (void)ctx;
    double p[4] = {r, 0, z, 0};
    return fm_eval_point((fm_evaluator *)worker, p);
}

static fm_interval tape_interval(void *ctx, void *worker, fm_interval r, fm_interval z)
{
    (void)ctx;
    fm_interval box[4] = {r, {0, 0}, z, {0, 0}};
    return fm_eval_interval((fm_evaluator *)worker, box);
}

fm_status fm_tool_custom_from_tape(const fm_tape *tape, double bound_radius, double bound_length,
                                   fm_tool_custom *custom, fm_error *err)
{
    if (!tape) return fm_error_set(err, FM_ERR_INPUT, "custom cutter: no compiled model");
    if (!(bound_radius > 0) || !(bound_length > 0))
        return fm_error_set(err, FM_ERR_INPUT,
                            "custom cutter: bounding radius (%g) and length (%g) must be positive",
                            bound_radius, bound_length);
    custom->ctx = (void *)tape;
    custom->worker_new = tape_worker_new;
    custom->worker_free = tape_worker_free;
    custom->eval = tape_eval;
    custom->interval = tape_interval;
    custom->bound_radius = bound_radius;
    custom->bound_length = bound_length;
    return FM_OK;
}
