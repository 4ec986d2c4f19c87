/* relations.c: point membership (Pasko eq. 16 with a tolerance band), the
 * maximum of a function over a box by interval branch-and-bound, and the
 * intersection and inclusion relations built on it (Pasko eq. 18, Shapiro
 * sec. 6.5): max over the box of min(f1, f2), resp. min(f1, -f2). */
#include "frep/tape_internal.h"

#include <stdlib.h>
#include <string.h>

fm_membership fm_classify_point(fm_evaluator *ev, const double p[4], double tol)
{
    double v = fm_eval_point(ev, p);
    if (v > tol) return FM_INSIDE;
    if (v >= -tol) return FM_ON_BOUNDARY;
    return FM_OUTSIDE; /* also NaN: not a point of the object */
}

/* The objective: f, min(f, g) or min(f, -g) of one or two tapes. */
typedef struct objective {
    fm_evaluator *f, *g;
    double g_sign;
} objective;

static double obj_point(objective *o, const double p[4])
{
    double v = fm_eval_point(o->f, p);
    if (!o->g) return v;
    double w = o->g_sign * fm_eval_point(o->g, p);
    return v < w ? v : w;
}

static double obj_upper(objective *o, const fm_interval box[4])
{
    fm_interval a = fm_eval_interval(o->f, box);
    double hi = isnan(a.hi) ? -INFINITY : a.hi; /* NaN-only: no value to maximize */
    if (o->g) {
        fm_interval b = fm_eval_interval(o->g, box);
        double bh = o->g_sign > 0 ? b.hi : -b.lo;
        if (isnan(bh)) bh = -INFINITY;
        if (bh < hi) hi = bh;
    }
    return hi;
}

typedef struct box_item {
    fm_interval b[4];
    double ub;
} box_item;

typedef struct bb_heap {
    box_item *items;
    size_t n, cap;
} bb_heap;

static int heap_push(bb_heap *h, const box_item *x)
{
    if (h->n == h->cap) {
        size_t cap = h->cap ? h->cap * 2 : 64;
        box_item *it = realloc(h->items, cap * sizeof *it);
        if (!it) return 0;
        h->items = it;
        h->cap = cap;
    }
    size_t i = h->n++;
    while (i > 0) {
        size_t parent = (i - 1) / 2;
        if (h->items[parent].ub >= x->ub) break;
        h->items[i] = h->items[parent];
        i = parent;
    }
    h->items[i] = *x;
    return 1;
}

static box_item heap_pop(bb_heap *h)
{
    box_item top = h->items[0], last = h->items[--h->n];
    size_t i = 0;
    for (;;) {
        size_t l = 2 * i + 1, r = l + 1, m = i;
        double mv = last.ub;
        if (l < h->n && h->items[l].ub > mv) {
            m = l;
            mv = h->items[l].ub;
        }
        if (r < h->n && h->items[r].ub > mv) m = r;
        if (m == i) break;
        h->items[i] = h->items[m];
        i = m;
    }
    if (h->n > 0) h->items[i] = last;
    return top;
}

static void center(const fm_interval b[4], double p[4])
{
    for (int i = 0; i < 4; i++) p[i] = 0.5 * (b[i].lo + b[i].hi);
}

/* Compass search from the best point, inside the box: the interval bounds
 * prune well only once a good value is known, and near a flat or kinked
 * maximum bisection midpoints approach it slowly. */
static void local_refine(objective *o, const fm_interval box[4], size_t budget, fm_max_result *out)
{
    double step = 0;
    for (int i = 0; i < 4; i++)
        if (box[i].hi - box[i].lo > step) step = box[i].hi - box[i].lo;
    step *= 0.125;
    double floor_step = 1e-13 * (1.0 + step);
    while (step > floor_step && out->evaluations < budget) {
        int moved = 0;
        for (int i = 0; i < 4 && out->evaluations < budget; i++) {
            if (!(box[i].hi > box[i].lo)) continue;
            for (int sgn = -1; sgn <= 1; sgn += 2) {
                double q[4];
                memcpy(q, out->at, sizeof q);
                q[i] += sgn * step;
                if (q[i] < box[i].lo || q[i] > box[i].hi) continue;
                double v = obj_point(o, q);
                out->evaluations++;
                if (v > out->value) {
                    out->value = v;
                    memcpy(out->at, q, sizeof q);
                    moved = 1;
                    break;
                }
            }
        }
        if (!moved) step *= 0.5;
    }
}

/* Branch and bound. stop_at_or_above / stop_below end the search as soon
 * as the answer to a yes/no question is known. */
static fm_status maximize(objective *o, const fm_interval box[4], double tol, size_t budget,
                          double stop_at_or_above, double stop_below, fm_max_result *out,
                          fm_error *err)
{
    bb_heap h = {0};
    double p[4];
    center(box, p);
    out->value = obj_point(o, p);
    if (isnan(out->value)) out->value = -INFINITY;
    memcpy(out->at, p, sizeof p);
    out->evaluations = 1;
    double pruned = -INFINITY; /* the largest upper bound of a discarded box */
    box_item root;
    memcpy(root.b, box, sizeof root.b);
    root.ub = obj_upper(o, box);
    if (!heap_push(&h, &root)) goto oom;
    size_t refine_at = 256;
    while (h.n > 0) {
        if (out->evaluations >= refine_at) {
            local_refine(o, box, out->evaluations + budget / 8 + 1 < budget ? out->evaluations + budget / 8 + 1 : budget, out);
            refine_at = out->evaluations * 4;
        }
        double top = h.items[0].ub;
        if (top - out->value <= tol || out->value >= stop_at_or_above ||
            (top < stop_below && pruned < stop_below) || out->evaluations >= budget)
            break;
        box_item it = heap_pop(&h);
        int axis = -1;
        double widest = 0;
        for (int i = 0; i < 4; i++)
            if (it.b[i].hi - it.b[i].lo > widest) widest = it.b[i].hi - it.b[i].lo, axis = i;
        double mid = axis >= 0 ? 0.5 * (it.b[axis].lo + it.b[axis].hi) : 0;
        if (axis < 0 || !(mid > it.b[axis].lo && mid < it.b[axis].hi)) {
            /* A point (or too small to split): its bound stays as is. */
            if (it.ub > pruned) pruned = it.ub;
            continue;
        }
        for (int k = 0; k < 2; k++) {
            box_item c = it;
            if (k == 0) c.b[axis].hi = mid;
            else c.b[axis].lo = mid;
            center(c.b, p);
            double v = obj_point(o, p);
            out->evaluations++;
            if (v > out->value) {
                out->value = v;
                memcpy(out->at, p, sizeof p);
            }
            c.ub = obj_upper(o, c.b);
            if (c.ub - out->value <= tol) {
                if (c.ub > pruned) pruned = c.ub;
            } else if (!heap_push(&h, &c)) {
                goto oom;
            }
        }
    }
    if (!(out->value >= stop_at_or_above) && h.n > 0 && h.items[0].ub - out->value > tol)
        local_refine(o, box, budget, out);
    out->upper = pruned;
    if (h.n > 0 && h.items[0].ub > out->upper) out->upper = h.items[0].ub;
    if (out->value > out->upper) out->upper = out->value;
    free(h.items);
    return FM_OK;
oom:
    free(h.items);
    return fm_error_set(err, FM_ERR_LIMIT, "out of memory in the maximum search");
}

fm_status fm_maximize(const fm_tape *tape, const fm_interval box[4], double tol,
                      size_t max_evaluations, fm_max_result *out, fm_error *err)
{
    if (!tape || !box || !out) return fm_error_set(err, FM_ERR_INPUT, "fm_maximize: missing argument");
    for (int i = 0; i < 4; i++)
        if (!(box[i].lo <= box[i].hi))
            return fm_error_set(err, FM_ERR_INPUT, "fm_maximize: box axis %d has lo > hi or NaN", i);
    objective o = {fm_evaluator_new(tape, err), NULL, 1.0};
    if (!o.f) return err ? err->code : FM_ERR_LIMIT;
    fm_status st = maximize(&o, box, tol, max_evaluations ? max_evaluations : 1, INFINITY,
                            -INFINITY, out, err);
    fm_evaluator_free(o.f);
    return st;
}

/* Evaluations allowed to the yes/no relations. */
#define RELATION_BUDGET 200000

static int relation(const fm_graph *g, fm_node f1, fm_node f2, double sign,
                    const fm_interval box[4], double tol, fm_error *err, fm_max_result *res)
{
    fm_tape *t1 = fm_tape_compile(g, f1, err), *t2 = t1 ? fm_tape_compile(g, f2, err) : NULL;
    objective o = {NULL, NULL, sign};
    int answer = -2;
    if (!t1 || !t2) goto done;
    o.f = fm_evaluator_new(t1, err);
    o.g = o.f ? fm_evaluator_new(t2, err) : NULL;
    if (!o.g) goto done;
    /* Intersection: stop once a common point is found (max >= -tol) or
     * the upper bound is negative. Inclusion: once a point of the inner
     * object strictly outside the outer one is found, or the bound is
     * <= tol. */
    double stop_hi = sign > 0 ? -tol : tol, stop_lo = sign > 0 ? -tol : tol;
    if (maximize(&o, box, tol, RELATION_BUDGET, stop_hi, stop_lo, res, err) != FM_OK) goto done;
    answer = 0;
done:
    fm_evaluator_free(o.f);
    fm_evaluator_free(o.g);
    fm_tape_free(t1);
    fm_tape_free(t2);
    return answer;
}

int fm_intersects(const fm_graph *g, fm_node f1, fm_node f2, const fm_interval box[4], double tol,
                  fm_error *err)
{
    fm_max_result r;
    if (relation(g, f1, f2, 1.0, box, tol, err, &r) != 0) return -1;
    if (r.value >= -tol) return 1; /* a point in both (touching within tol counts) */
    if (r.upper < -tol) return 0;
    return -1;
}

int fm_includes(const fm_graph *g, fm_node inner, fm_node outer, const fm_interval box[4],
                double tol, fm_error *err)
{
    fm_max_result r;
    if (relation(g, inner, outer, -1.0, box, tol, err, &r) != 0) return -1;
    if (r.value > tol) return 0; /* a point inside inner, outside outer */
    if (r.upper <= tol) return 1;
    return -1;
}

/* ------------------------------------------------------ inside bounds -- */

static int inside_bounds_step(fm_evaluator *ev, const fm_interval box[3], double min_size,
                              size_t max_boxes, fm_inside_bounds *s)
{
    if (++s->boxes > max_boxes) return 0;
    fm_interval b4[4] = {box[0], box[1], box[2], {0, 0}};
    fm_interval v = fm_eval_interval(ev, b4);
    if (v.hi < 0) return 1; /* all outside (NaN goes on, as undecided) */
    if (v.lo >= 0 || box[0].hi - box[0].lo <= min_size) {
        for (int a = 0; a < 3; a++) {
            if (!s->found || box[a].lo < s->lo[a]) s->lo[a] = box[a].lo;
            if (!s->found || box[a].hi > s->hi[a]) s->hi[a] = box[a].hi;
        }
        s->found = 1;
        return 1;
    }
    for (int k = 0; k < 8; k++) {
        fm_interval sub[3];
        for (int a = 0; a < 3; a++) {
            double mid = 0.5 * (box[a].lo + box[a].hi);
            sub[a] = (k >> a) & 1 ? (fm_interval){mid, box[a].hi} : (fm_interval){box[a].lo, mid};
        }
        if (!inside_bounds_step(ev, sub, min_size, max_boxes, s)) return 0;
    }
    return 1;
}

fm_status fm_find_inside_bounds(fm_evaluator *ev, const fm_interval box[3], double min_size,
                                size_t max_boxes, fm_inside_bounds *out)
{
    memset(out, 0, sizeof *out);
    return inside_bounds_step(ev, box, min_size, max_boxes, out) ? FM_OK : FM_ERR_LIMIT;
}
