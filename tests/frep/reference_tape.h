/* reference_tape.h: the helper test_ops.c and test_prims.c share: every
 * value a test reads through it comes from the reference evaluator and is
 * also computed by the compiled tape, which must agree. Include after
 * test.h; a test program includes it once. */
#ifndef FM_REFERENCE_TAPE_H
#define FM_REFERENCE_TAPE_H

#include "frep/frep_internal.h"
#include "test.h"

/* Every value the tests read is also computed by the compiled tape
 * (fm_tape_compile + fm_eval_point) and must equal the reference
 * evaluator's. One tape is cached: tests evaluate one node many times. */
static struct {
    const fm_graph *g;
    fm_node node;
    fm_tape *tape;
    fm_evaluator *ev;
} tape_cache;

static void tape_cache_clear(void)
{
    fm_evaluator_free(tape_cache.ev);
    fm_tape_free(tape_cache.tape);
    memset(&tape_cache, 0, sizeof tape_cache);
}

static void free_graph(fm_graph *g)
{
    tape_cache_clear();
    fm_graph_free(g);
}

static double reference_and_tape(const fm_graph *g, fm_node n, const double p[4])
{
    double ref = fm_graph_eval_reference(g, n, p);
    if (tape_cache.g != g || tape_cache.node != n) {
        tape_cache_clear();
        fm_error err;
        fm_error_clear(&err);
        tape_cache.g = g;
        tape_cache.node = n;
        tape_cache.tape = fm_tape_compile(g, n, &err);
        tape_cache.ev = tape_cache.tape ? fm_evaluator_new(tape_cache.tape, &err) : NULL;
        CHECK(tape_cache.ev != NULL);
    }
    if (tape_cache.ev) {
        double v = fm_eval_point(tape_cache.ev, p);
        if (isnan(ref)) CHECK(isnan(v));
        else CHECK_NEAR(v, ref, 1e-12 * (1.0 + fabs(ref)));
    }
    return ref;
}

#endif
