/* fuzz_hf.c: libFuzzer target for the HyperFun parser and compiler. Each
 * input is compiled as a whole program and parsed as a single expression,
 * under small budgets so that every input finishes quickly; small results
 * are evaluated at a point with the reference evaluator. The command that
 * runs it is in docs/hf.md ("Fuzzing"). */
#include <stddef.h>
#include <stdint.h>
#include <string.h>

#include "frep/frep_internal.h"
#include "hf/hf.h"

static int has_special_ops(const fm_graph *g)
{
    size_t n = fm_graph_node_count(g);
    for (size_t i = 1; i <= n; i++)
        if (fm_node_op(g, (fm_node)i) >= FM_OP_PROJECT) return 1;
    return 0;
}

int LLVMFuzzerTestOneInput(const uint8_t *data, size_t size)
{
    fm_hf_options opt = {0};
    opt.max_steps = 200000;
    opt.max_iterations = 20000;
    opt.max_array = 4096;
    opt.max_depth = 200;
    fm_graph *g = fm_graph_new(100000);
    if (!g) return 0;
    fm_hf_model m;
    fm_error err;
    const double p[4] = {0.25, -0.5, 0.75, 0.5};
    if (fm_hf_compile_string(g, (const char *)data, size, "fuzz", NULL, &opt, &m, &err) == FM_OK &&
        fm_graph_node_count(g) < 5000 && !has_special_ops(g))
        (void)fm_graph_eval_reference(g, m.root, p);
    fm_graph_free(g);

    /* The expression front end takes NUL-terminated text. */
    char text[4096];
    size_t n = size < sizeof text - 1 ? size : sizeof text - 1;
    memcpy(text, data, n);
    text[n] = '\0';
    g = fm_graph_new(100000);
    if (!g) return 0;
    const char *names[4] = {"x", "y", "z", "t"};
    fm_node vars[4];
    for (int i = 0; i < 4; i++) vars[i] = fm_var(g, i);
    fm_node e = fm_hf_parse_expression(g, text, names, vars, 4, "expr", &err);
    if (e && fm_graph_node_count(g) < 5000 && !has_special_ops(g))
        (void)fm_graph_eval_reference(g, e, p);
    fm_graph_free(g);
    return 0;
}
