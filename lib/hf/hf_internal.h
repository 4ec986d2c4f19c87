/* hf_internal.h: what the parser, the symbolic executor and the library of
 * lib/hf share: tokens, the syntax tree (an index-linked arena), the name
 * table, and the execution context the library functions build nodes in.
 * Not part of the public API. */
#ifndef FM_HF_INTERNAL_H
#define FM_HF_INTERNAL_H

#include <stdint.h>

#include "hf/hf.h"

/* Token kinds. Keywords are recognised case-insensitively. */
typedef enum hf_tok {
    HF_TK_EOF, HF_TK_NUMBER, HF_TK_NAME,
    HF_TK_LPAREN, HF_TK_RPAREN, HF_TK_LBRACKET, HF_TK_RBRACKET, HF_TK_LBRACE, HF_TK_RBRACE,
    HF_TK_COMMA, HF_TK_SEMI, HF_TK_EQ, HF_TK_LT, HF_TK_GT, HF_TK_LE, HF_TK_GE, HF_TK_NE,
    HF_TK_PLUS, HF_TK_MINUS, HF_TK_STAR, HF_TK_SLASH, HF_TK_CARET, HF_TK_BAR, HF_TK_AMP,
    HF_TK_BACKSLASH, HF_TK_AT, HF_TK_TILDE,
    HF_TK_IF, HF_TK_THEN, HF_TK_ELSE, HF_TK_ENDIF, HF_TK_WHILE, HF_TK_LOOP, HF_TK_ENDLOOP,
    HF_TK_AND, HF_TK_OR, HF_TK_NOT, HF_TK_ARRAY,
    HF_TK_COUNT
} hf_tok;

/* Syntax tree node kinds. */
typedef enum hf_kind {
    HF_E_NUM, HF_E_NAME, HF_E_INDEX, HF_E_CALL, HF_E_UNARY, HF_E_BINARY, HF_E_ARRAY,
    HF_S_ASSIGN, HF_S_ASSIGN_ELEM, HF_S_IF, HF_S_WHILE, HF_S_ARRAY_DECL
} hf_kind;

/* One node. Children and lists are indexes into the arena (0: none);
 * lists (arguments, statements, array literal items) chain through next.
 *   E_NUM num | E_NAME name | E_INDEX name[a] | E_CALL name(a...)
 *   E_UNARY op a | E_BINARY a op b | E_ARRAY [a...]
 *   S_ASSIGN name = a | S_ASSIGN_ELEM name[a] = b
 *   S_IF if a then b... else c... | S_WHILE while a loop b...
 *   S_ARRAY_DECL array a... (each an E_INDEX name[size]) */
typedef struct hf_ast {
    uint8_t kind;
    uint8_t op; /* hf_tok of the operator */
    int line, col;
    uint32_t name;
    uint32_t a, b, c, next;
    double num;
} hf_ast;

typedef struct hf_object {
    uint32_t name;
    uint32_t x_name, a_name, s_name; /* 0 when absent (x is required) */
    int x_dim, a_dim, s_dim;
    uint32_t body;
    int line, col;
} hf_object;

/* The parsed program: arena, names (lower case) with their spelling as
 * first written, objects. */
typedef struct hf_program {
    hf_ast *nodes;
    size_t count, capacity;
    char **names;     /* names[0] unused */
    char **spellings;
    size_t name_count, name_capacity;
    hf_object *objects;
    size_t object_count, object_capacity;
    const char *source_name;
    const fm_hf_options *opt;
} hf_program;

/* Parse a whole program (objects) or, with expression_only, a single
 * expression whose root is stored in *root. */
fm_status fm_hf_parse(hf_program *p, const char *src, size_t len, int expression_only,
                      uint32_t *root, fm_error *err);
void fm_hf_program_free(hf_program *p);
/* Find or add a (lower-cased) name; 0 on out of memory. */
uint32_t fm_hf_intern(hf_program *p, const char *s, size_t len);

/* Edit distance (case-insensitive) for "did you mean" suggestions. */
size_t fm_hf_edit_distance(const char *a, const char *b);
/* Printable text of a token kind: "';'", "'endif'", "a number". */
const char *fm_hf_token_text(hf_tok t);

/* ------------------------------------------------------------ library -- */

/* A value as the executor passes it to a library function: a scalar node
 * or an array of nodes (for transforms, the array is changed in place). */
typedef struct hf_value {
    int is_array;
    fm_node scalar;
    fm_node *elems;
    size_t n;
} hf_value;

typedef struct hf_lib_ctx {
    fm_graph *g;
    double alpha;       /* the current R-function alpha */
    const char *fname;  /* spelling of the called function, for messages */
    char message[400];  /* filled when a function fails */
} hf_lib_ctx;

/* A library function. sig lists the argument kinds: 'r' a number, 'a' an
 * array (read), 'x' an array changed in place, 'p' a point array (>= 3
 * elements). fn returns FM_NONE and fills ctx->message on a bad argument. */
typedef struct hf_lib_fn {
    const char *name; /* HyperFun's spelling */
    const char *sig;
    fm_node (*fn)(hf_lib_ctx *ctx, hf_value *args);
} hf_lib_fn;

const hf_lib_fn *fm_hf_library_find(const char *lower_name);
const hf_lib_fn *fm_hf_library_at(size_t i); /* NULL past the end */

#endif
