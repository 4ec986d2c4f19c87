/* test_hf_errors.c: each kind of error of lib/hf has a message that says
 * what was expected and what was found, and the right file:line:column;
 * budgets end runaway programs with a clear error instead of a hang. */
#include "hf/hf.h"
#include "test.h"

#include <stdlib.h>

static fm_error compile(const char *src, const fm_hf_options *opt, size_t max_nodes)
{
    fm_graph *g = fm_graph_new(max_nodes);
    fm_hf_model m;
    fm_error err;
    fm_error_clear(&err);
    fm_status st = fm_hf_compile_string(g, src, strlen(src), "t.hf", NULL, opt, &m, &err);
    if (st == FM_OK) err.message[0] = '\0';
    fm_graph_free(g);
    return err;
}

#define EXPECT_ERROR(src, code_, line_, col_, text)                                   \
    do {                                                                              \
        fm_error e_ = compile(src, NULL, 0);                                          \
        CHECK(e_.code == (code_));                                                    \
        CHECK(e_.line == (line_));                                                    \
        CHECK(e_.column == (col_));                                                   \
        CHECK(!strcmp(e_.file, "t.hf"));                                              \
        CHECK_STR_CONTAINS(e_.message, text);                                         \
        if (e_.line != (line_) || e_.column != (col_))                                \
            fprintf(stderr, "  at %d:%d: %s\n", e_.line, e_.column, e_.message);       \
    } while (0)

static void syntax_errors(void)
{
    EXPECT_ERROR("bad(x[3], a[1])\n{\n  if x[1] < 0 then bad = 1 endif;\n}\n", FM_ERR_INPUT, 3, 28,
                 "expected ';' after assignment, found 'endif'");
    EXPECT_ERROR("o(x[3]) { o = (x[1] + 1; }", FM_ERR_INPUT, 1, 24, "expected ')' to close '(', found ';'");
    EXPECT_ERROR("o(x[3]) { o = x[1] $ 2; }", FM_ERR_INPUT, 1, 20, "unexpected character '$'");
    EXPECT_ERROR("o(x[3]) { o = ; }", FM_ERR_INPUT, 1, 15, "expected an expression, found ';'");
    EXPECT_ERROR("o(x[3]) { if x[1] then o = 1; }", FM_ERR_INPUT, 1, 31,
                 "expected 'else' or 'endif' to close 'if', found '}'");
    EXPECT_ERROR("o(x[3]) { while 1 o = 1; endloop; }", FM_ERR_INPUT, 1, 19,
                 "expected 'loop' after the condition of 'while', found 'o'");
    EXPECT_ERROR("o(x[3]) { 3 = o; }", FM_ERR_INPUT, 1, 11,
                 "expected a statement (a name, 'if', 'while' or 'array'), found '3'");
    EXPECT_ERROR("o(x[3]) { o = 1; ", FM_ERR_INPUT, 1, 18, "expected '}' to close the object body, found end of input");
    EXPECT_ERROR("o(x[5]) { o = 1; }", FM_ERR_INPUT, 1, 5, "coordinate array size must be an integer from 1 to 4, found 5");
    EXPECT_ERROR("o(x[3]) { o = 1; }\no(x[3]) { o = 2; }", FM_ERR_INPUT, 2, 1, "object 'o' is defined twice");
    EXPECT_ERROR("o(x[3]) { o = hfSphere(x, [0, 0, 0] 1); }", FM_ERR_INPUT, 1, 37,
                 "expected ',' or ')' after the arguments, found '1'");
    EXPECT_ERROR("", FM_ERR_INPUT, 1, 1, "expected an object");
}

static void name_errors(void)
{
    EXPECT_ERROR("s(x[3], a[1])\n{\n  array c[3];\n  c = [0, 0, 0];\n  s = hfSpere(x, c, 1);\n}\n",
                 FM_ERR_INPUT, 5, 7, "unknown function 'hfSpere'; did you mean 'hfSphere'?");
    EXPECT_ERROR("s(x[3]) { s = sqr(x[1]); }", FM_ERR_INPUT, 1, 15, "unknown function 'sqr'; did you mean 'sqrt'?");
    EXPECT_ERROR("s(x[3]) { radius = 2; s = radus - x[1]; }", FM_ERR_INPUT, 1, 27,
                 "unknown name 'radus' (no value is assigned to it before this use); did you mean 'radius'?");
    EXPECT_ERROR("s(x[3]) { s = x[1] + zzz; }", FM_ERR_INPUT, 1, 22, "unknown name 'zzz'");
    EXPECT_ERROR("s(x[3]) { s = x; }", FM_ERR_INPUT, 1, 15, "'x' is an array; use an item such as x[1]");
    EXPECT_ERROR("s(x[3]) { s = x[4]; }", FM_ERR_INPUT, 1, 17, "index 4 is out of range for array 'x' of 3 items");
    EXPECT_ERROR("s(x[3]) { array v[2]; v[1] = 1; s = v[2]; }", FM_ERR_INPUT, 1, 37, "v[2] is used before it is assigned");
    EXPECT_ERROR("s(x[3]) { s = x[x[1]]; }", FM_ERR_INPUT, 1, 17,
                 "an array index must be known at compile time, but it depends on the point coordinates (x)");
    EXPECT_ERROR("s(x[3]) { s = hfSphere(x, 1, 2); }", FM_ERR_INPUT, 1, 27,
                 "hfSphere: argument 2 must be an array");
    EXPECT_ERROR("s(x[3]) { array c[3]; c = [0,0,0]; s = hfSphere(x, c); }", FM_ERR_INPUT, 1, 40,
                 "hfSphere takes 3 arguments, found 2");
    EXPECT_ERROR("s(x[3]) { s = sin(1, 2); }", FM_ERR_INPUT, 1, 15, "sin takes 1 argument, found 2");
    EXPECT_ERROR("s(x[3]) { array c[2]; c = [0, 0]; s = hfSphere(x, c, 1); }", FM_ERR_INPUT, 1, 51,
                 "hfSphere: argument 2 must have at least 3 items, found 2");
    EXPECT_ERROR("s(x[3]) { array c[3]; c = [0,0,0]; s = hfEllipsoid(x, c, 1, 0, 1); }", FM_ERR_INPUT,
                 1, 40, "hfEllipsoid: the half-axes must not be zero");
    EXPECT_ERROR("s(x[3]) { array c[3]; c = [1, 2]; s = 1; }", FM_ERR_INPUT, 1, 27,
                 "array 'c' has 3 items, but the list has 2");
    EXPECT_ERROR("s(x[3]) { r_alpha = 2; s = 1; }", FM_ERR_INPUT, 1, 21, "r_alpha must be in [0, 1]");
    /* lib/frep's time-dependent affine map refuses a singular A (its message) */
    EXPECT_ERROR("s(x[3]) { r = fmAffineT(x, 1, 0, 0, 0,  2, 0, 0, 0,  0, 0, 1, 0); s = 1; }",
                 FM_ERR_INPUT, 1, 15, "the matrix is singular (determinant 0)");
    EXPECT_ERROR("s(x[3]) { r_alpha = x[1]; s = 1; }", FM_ERR_INPUT, 1, 21,
                 "r_alpha must be a constant known at compile time");
    EXPECT_ERROR("s(x[3]) { t = 1; }", FM_ERR_INPUT, 1, 1, "object 's' never assigns its result; end it with 's = ...;'");
    EXPECT_ERROR("s(x[3]) { x = 1; s = 1; }", FM_ERR_INPUT, 1, 11, "'x' is the coordinate array of 's'");
    /* A variable assigned on one branch of a point-dependent if. */
    EXPECT_ERROR("s(x[3])\n{\n  if x[1] > 0 then r = 1; endif;\n  s = r;\n}\n", FM_ERR_INPUT, 4, 7,
                 "'r' may have no value here: it is assigned in only one branch of the 'if' at line 3:3");
    EXPECT_ERROR("s(x[3]) { s = fmProject(x[1], x[2], 1); }", FM_ERR_INPUT, 1, 31,
                 "fmProject: t0 must be known at compile time");
}

static void loop_and_budget_errors(void)
{
    EXPECT_ERROR("w(x[3])\n{\n  i = 0;\n  while i < x[1] loop i = i + 1; endloop;\n  w = i;\n}\n",
                 FM_ERR_INPUT, 4, 3,
                 "the condition of this 'while' depends on the point coordinates (x); only loops "
                 "whose condition is known at compile time can be unrolled");
    EXPECT_ERROR("w(x[3], a[1]) { i = 0; while i < a[1] loop i = i + 1; endloop; w = i; }",
                 FM_ERR_INPUT, 1, 24, "depends on a parameter (a)");
    EXPECT_ERROR("w(x[3])\n{\n  i = 0;\n  while 1 loop i = 1; endloop;\n  w = i;\n}\n", FM_ERR_LIMIT,
                 4, 3, "has not ended after 1000000 iterations");
    /* a runaway loop that builds new nodes meets the node budget first */
    EXPECT_ERROR("w(x[3])\n{\n  i = 0;\n  while 1 loop i = i + 1; endloop;\n  w = i;\n}\n", FM_ERR_LIMIT,
                 4, 22, "the node budget");
    /* Recursion, direct and through another object. */
    EXPECT_ERROR("r(x[3], a[1]) { r = r(x, a) + 1; }", FM_ERR_INPUT, 1, 21,
                 "recursive call of object 'r'");
    EXPECT_ERROR("p(x[3], a[1]) { p = q(x, a); }\nq(x[3], a[1]) { q = p(x, a); }", FM_ERR_INPUT, 1, 21,
                 "recursive call of object 'q'");
    /* Node budget: a graph of 50 nodes cannot hold 30 different spheres. */
    {
        const char *src = "n(x[3]) { array c[3]; i = 0; n = -1; while i < 30 loop\n"
                          "c = [i, 0, 0]; n = n | hfSphere(x, c, 1); i = i + 1; endloop; }";
        fm_error e = compile(src, NULL, 50);
        CHECK(e.code == FM_ERR_LIMIT);
        CHECK_STR_CONTAINS(e.message, "more than 50 nodes (the node budget)");
        CHECK(e.line == 2 && e.column > 0);
    }
    /* Deep parentheses end with an error, not a stack overflow. */
    {
        size_t n = 100000;
        char *src = malloc(2 * n + 64);
        strcpy(src, "d(x[3]) { d = ");
        size_t k = strlen(src);
        for (size_t i = 0; i < n; i++) src[k++] = '(';
        src[k++] = '1';
        for (size_t i = 0; i < n; i++) src[k++] = ')';
        strcpy(src + k, "; }");
        fm_error e = compile(src, NULL, 0);
        CHECK(e.code == FM_ERR_LIMIT);
        CHECK_STR_CONTAINS(e.message, "nesting is deeper than 200 levels");
        CHECK(e.line == 1 && e.column > 100);
        /* and so do deeply nested if statements and unary minus chains */
        k = strlen("d(x[3]) { ");
        strcpy(src, "d(x[3]) { ");
        for (size_t i = 0; i < 5000; i++) {
            memcpy(src + k, "if 1 then ", 10);
            k += 10;
        }
        strcpy(src + k, "d = 1;");
        e = compile(src, NULL, 0);
        CHECK(e.code == FM_ERR_LIMIT);
        CHECK_STR_CONTAINS(e.message, "nesting is deeper");
        free(src);
    }
    /* A long flat chain is fine: 1 + 1 + ... (no recursion per term). */
    {
        size_t n = 50000;
        char *src = malloc(4 * n + 64);
        strcpy(src, "c(x[3]) { c = x[1]");
        size_t k = strlen(src);
        for (size_t i = 0; i < n; i++) {
            memcpy(src + k, " + 1", 4);
            k += 4;
        }
        strcpy(src + k, "; }");
        fm_error e = compile(src, NULL, 0);
        CHECK(e.message[0] == '\0');
        free(src);
    }
    /* Exponential work (each object calls the next twice) hits the step
     * budget, not the wall clock. */
    {
        char src[4096] = "";
        for (int i = 0; i < 40; i++) {
            char line[128];
            if (i == 0) snprintf(line, sizeof line, "o0(x[3]) { o0 = x[1]; }\n");
            else snprintf(line, sizeof line, "o%d(x[3]) { o%d = o%d(x) + o%d(x); }\n", i, i, i - 1, i - 1);
            strcat(src, line);
        }
        fm_hf_options opt = {0};
        opt.max_steps = 100000;
        fm_error e = compile(src, &opt, 0);
        CHECK(e.code == FM_ERR_LIMIT);
        CHECK_STR_CONTAINS(e.message, "more than 100000 steps");
    }
    /* Token and source budgets. */
    {
        fm_hf_options opt = {0};
        opt.max_tokens = 10;
        fm_error e = compile("o(x[3]) { o = 1 + 2 + 3 + 4; }", &opt, 0);
        CHECK(e.code == FM_ERR_LIMIT);
        CHECK_STR_CONTAINS(e.message, "more than 10 tokens");
        opt.max_tokens = 0;
        opt.max_source = 8;
        e = compile("o(x[3]) { o = 1; }", &opt, 0);
        CHECK(e.code == FM_ERR_LIMIT);
        CHECK_STR_CONTAINS(e.message, "the source budget");
        opt.max_source = 0;
        opt.max_array = 10;
        e = compile("o(x[3]) { array v[11]; o = 1; }", &opt, 0);
        CHECK(e.code == FM_ERR_LIMIT);
        CHECK_STR_CONTAINS(e.message, "the array budget");
    }
}

static void entry_errors(void)
{
    fm_graph *g = fm_graph_new(0);
    fm_hf_model m;
    fm_error err;
    const char *src = "ball(x[3]) { ball = 1; }\ncube(x[3]) { cube = 2; }";
    CHECK(fm_hf_compile_string(g, src, strlen(src), "t.hf", "bal", NULL, &m, &err) == FM_ERR_INPUT);
    CHECK_STR_CONTAINS(err.message, "no object named 'bal' in the source; did you mean 'ball'?");
    CHECK(fm_hf_compile_file(g, "hf/corpus/does-not-exist.hf", NULL, &m, &err) == FM_ERR_IO);
    CHECK_STR_CONTAINS(err.message, "cannot open");
    CHECK_STR_CONTAINS(err.file, "does-not-exist.hf");
    /* the expression front end */
    const char *names[1] = {"t"};
    fm_node t = fm_var(g, FM_T);
    CHECK(fm_hf_parse_expression(g, "10 + 20*sin(t) t", names, &t, 1, "traj", &err) == FM_NONE);
    CHECK(err.line == 1 && err.column == 16);
    CHECK_STR_CONTAINS(err.message, "expected end of the expression, found 't'");
    CHECK(fm_hf_parse_expression(g, "10 + 20*sin(tt)", names, &t, 1, "traj", &err) == FM_NONE);
    CHECK(err.column == 13);
    CHECK_STR_CONTAINS(err.message, "unknown name 'tt'");
    CHECK_STR_CONTAINS(err.message, "did you mean 't'?");
    CHECK(fm_hf_parse_expression(g, "10 + 20*expp(t)", names, &t, 1, "traj", &err) == FM_NONE);
    CHECK_STR_CONTAINS(err.message, "unknown function 'expp'; did you mean 'exp'?");
    CHECK(!strcmp(err.file, "traj"));
    fm_graph_free(g);
}

int main(void)
{
    syntax_errors();
    name_errors();
    loop_and_budget_errors();
    entry_errors();
    return test_summary("hf_errors");
}
