/* hf.h: the HyperFun-compatible geometry language of frepmill. A program
 * (one or more objects `name(x[3], a[1]) { ... name = expr; }`) is parsed,
 * executed symbolically (Hasan sec. 4.1: loops with compile-time conditions
 * are unrolled, an `if` whose condition depends on the point becomes a
 * select node) and compiled to an fm_graph DAG of lib/frep. The expression
 * part of the language is usable on its own (trajectories, tool
 * definitions). The language, its library with formulas and the frepmill
 * extension are described in docs/hf.md. Nothing here prints. */
#ifndef FM_HF_H
#define FM_HF_H

#include <stddef.h>

#include "core/core.h"
#include "frep/frep.h"

/* Default limits (each can be lowered or raised in fm_hf_options). */
#define FM_HF_MAX_SOURCE (4u << 20)      /* bytes of source text */
#define FM_HF_MAX_TOKENS 1000000u        /* tokens in one source */
#define FM_HF_MAX_DEPTH 200u             /* nesting of parentheses, calls, statements */
#define FM_HF_MAX_ITERATIONS 1000000u    /* unrolled loop iterations, all loops together */
#define FM_HF_MAX_STEPS 20000000u        /* statements and expression nodes executed */
#define FM_HF_MAX_ARRAY 100000u          /* elements of one array */
#define FM_HF_MAX_CALL_DEPTH 64u         /* nested calls of one object by another */

/* Limits for one compilation; zero fields take the defaults above. */
typedef struct fm_hf_options {
    size_t max_source, max_tokens, max_depth, max_iterations, max_steps, max_array;
    size_t max_call_depth;
    /* The alpha of the R-functions | & \ @ at the start of every object
     * (HyperFun's ALPHA, default 0); a program changes it with the
     * statement `r_alpha = <constant>;`. Must be in [0, 1]. */
    double alpha;
} fm_hf_options;

#define FM_HF_MAX_PARAMS 64
#define FM_HF_NAME_MAX 64

/* A compiled model. Parameters: the elements of the model's parameter
 * array (the `a` of `name(x[3], a[2])`) are fm_param nodes named after the
 * array and the 1-based index as written: "a1", "a2" (lower case, because
 * names are case-insensitive). Their initial value is 0; set them with
 * fm_graph_set_param or fm_tape_set_param. */
typedef struct fm_hf_model {
    fm_node root;
    int dimension;                 /* size of the model's x array: 1..4 (4: x[4] is time) */
    char name[FM_HF_NAME_MAX];     /* the model object's name, lower case */
    size_t param_count;
    char param_names[FM_HF_MAX_PARAMS][FM_HF_NAME_MAX + 8]; /* array name + index */
} fm_hf_model;

/* Compile the object model_name (case-insensitive; NULL: the last object in
 * the source) into g. source_name is used in error positions. On error,
 * err carries file:line:column and a message that says what was expected
 * and what was found. options may be NULL (defaults). */
fm_status fm_hf_compile_string(fm_graph *g, const char *source, size_t length,
                               const char *source_name, const char *model_name,
                               const fm_hf_options *options, fm_hf_model *out, fm_error *err);
fm_status fm_hf_compile_file(fm_graph *g, const char *path, const char *model_name,
                             fm_hf_model *out, fm_error *err);

/* Parse one expression such as "10 + 20*sin(t)" over the given variable
 * names (case-insensitive), which stand for the given nodes. Built-in math,
 * the library functions that take no arrays (hfBlendUni, ...) and the
 * frepmill extension functions may be called. Returns FM_NONE and fills
 * err (positions are 1:column in text) on error. */
fm_node fm_hf_parse_expression(fm_graph *g, const char *text, const char *const *var_names,
                               const fm_node *var_nodes, size_t n_vars,
                               const char *source_name, fm_error *err);

#endif
