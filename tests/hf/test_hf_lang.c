/* test_hf_lang.c: semantics of the language: operator precedence as
 * HyperFun's, R-functions with alpha, built-in math, per-point if (select)
 * versus constant if, loops, object calls, parameters, the frepmill
 * extension, the expression front end, and the examples/ models. Expected
 * values are computed here by hand. */
#include "frep/frep_internal.h"
#include "hf/hf.h"
#include "test.h"

static fm_graph *G;

static fm_node compile_src(const char *src, fm_hf_model *m)
{
    fm_error err;
    fm_status st = fm_hf_compile_string(G, src, strlen(src), "lang", NULL, NULL, m, &err);
    if (st != FM_OK) {
        char buf[800];
        fprintf(stderr, "%s\n  in: %s\n", fm_error_format(&err, buf, sizeof buf), src);
    }
    CHECK(st == FM_OK);
    return st == FM_OK ? m->root : FM_NONE;
}

/* value of `o = <expr>;` at p */
static double value_at(const char *expr, double x, double y, double z, double t)
{
    char src[2048];
    snprintf(src, sizeof src, "o(x[4], a[2]) { %s }", expr);
    fm_hf_model m;
    fm_node r = compile_src(src, &m);
    double p[4] = {x, y, z, t};
    return r ? fm_graph_eval_reference(G, r, p) : NAN;
}

static double value(const char *expr) { return value_at(expr, 0, 0, 0, 0); }

static void precedence(void)
{
    CHECK_NEAR(value("o = -2^2;"), 4, 0);        /* unary binds tighter than ^ */
    CHECK_NEAR(value("o = 2^3^2;"), 64, 0);      /* ^ is left-associative */
    CHECK_NEAR(value("o = 1 + 2 * 3 ^ 2;"), 19, 0);
    CHECK_NEAR(value("o = 10 - 4 - 3;"), 3, 0);
    CHECK_NEAR(value("o = 8 / 4 / 2;"), 1, 0);
    CHECK_NEAR(value("o = 2 * (3 + 4);"), 14, 0);
    /* | shares the level of + and -: 1 + 2 | 3 is (1 + 2) | 3 */
    CHECK_NEAR(value("o = 1 + 2 | 3;"), 3 + 3 + sqrt(18.0), 1e-12);
    CHECK_NEAR(value("o = 3 | 1 + 2;"), 3 + 1 + sqrt(10.0) + 2, 1e-12);
    CHECK_NEAR(value("o = 2 * 3 & 1;"), 6 + 1 - sqrt(37.0), 1e-12);
    CHECK_NEAR(value("o = ~3 + 1;"), -2, 0);
    CHECK_NEAR(value("o = --3 comment\n + 1;"), 1, 0); /* -- starts a comment: o = +1 */
}

static void r_functions(void)
{
    /* alpha 0 (HyperFun's default) */
    CHECK_NEAR(value("o = 3 | -1;"), 2 + sqrt(10.0), 1e-12);
    CHECK_NEAR(value("o = 3 & -1;"), 2 - sqrt(10.0), 1e-12);
    CHECK_NEAR(value("o = 3 \\ 1;"), 3 - 1 - sqrt(10.0), 1e-12);
    CHECK_NEAR(value("o = 3 @ 2;"), 5 - sqrt(13.0), 1e-12);
    /* alpha 0.5: (f1 + f2 +- sqrt(f1^2 + f2^2 - 2 alpha f1 f2)) / (1 + alpha) */
    CHECK_NEAR(value("r_alpha = 0.5; o = 3 | -1;"), (2 + sqrt(9 + 1 + 3.0)) / 1.5, 1e-12);
    CHECK_NEAR(value("r_alpha = 0.5; o = 3 & 2;"), (5 - sqrt(9 + 4 - 6.0)) / 1.5, 1e-12);
    /* alpha 1: max and min exactly */
    CHECK_NEAR(value("r_alpha = 1; o = 3 | -1;"), 3, 0);
    CHECK_NEAR(value("r_alpha = 1; o = 3 & -1;"), -1, 0);
    CHECK_NEAR(value("r_alpha = 1; o = 3 \\ 1;"), -1, 0);
    /* alpha changes in program order */
    CHECK_NEAR(value("u = 3 | 4; r_alpha = 1; o = u + (3 | 4);"), 7 + 5 + 4, 1e-12);
    /* and on points: the union of two spheres, at a point of the first */
    CHECK_NEAR(value_at("r_alpha = 1; o = (1 - x[1]^2) | (1 - (x[1] - 3)^2);", 3, 0, 0, 0), 1, 0);
}

static void builtins(void)
{
    CHECK_NEAR(value("o = sqrt(16) + exp(0) + log(1);"), 5, 1e-15);
    CHECK_NEAR(value("o = logd(1000);"), 3, 1e-14);
    CHECK_NEAR(value("o = sin(0.5) + cos(0.5) + tan(0.5);"), sin(0.5) + cos(0.5) + tan(0.5), 1e-15);
    CHECK_NEAR(value("o = asin(0.5) + acos(0.5) + atan(2);"), asin(0.5) + acos(0.5) + atan(2.0), 1e-15);
    CHECK_NEAR(value("o = atan2(1, -1);"), atan2(1.0, -1.0), 1e-15);
    CHECK_NEAR(value("o = abs(-2) + sinh(1) + cosh(1) + tanh(1);"), 2 + sinh(1.0) + cosh(1.0) + tanh(1.0), 1e-14);
    CHECK_NEAR(value("o = sign(-3) + 10 * sign(2) + 100 * sign(0);"), -1 + 10, 0);
    CHECK_NEAR(value("o = mod(7, 3) + 10 * mod(7.4, 2.6);"), 1 + 10 * 1, 0); /* fmod(round) */
    CHECK_NEAR(value("o = max(1, 4) + min(1, 4);"), 5, 0);
    CHECK_NEAR(value("o = ceil(1.2) + floor(1.8) + int(-1.7) + frac(-1.75);"), 2 + 1 - 1 - 0.75, 1e-15);
    /* comparisons give 1 or 0; = and /= use HyperFun's EPS = 1e-6 */
    CHECK_NEAR(value("o = (1 < 2) + (2 <= 2) + (3 > 2) + (2 >= 3) + (1 = 1.0000001) + (1 /= 1.1);"), 5, 0);
    CHECK_NEAR(value("o = (1 = 1.001) + 2 * (0 < 1 <= 1) + 4 * (0 < 2 <= 1);"), 2, 0);
    CHECK_NEAR(value("o = (1 < 2 and 2 < 1) + 2 * (1 < 2 or 2 < 1) + 4 * (not 0) + 8 * (not 1 < 2);"), 6, 0);
}

static void control(void)
{
    /* a point-dependent if is a select evaluated per point */
    const char *src = "o = 0; if x[1] > 0 then o = x[1]; else o = -2 * x[1]; endif;";
    CHECK_NEAR(value_at(src, 3, 0, 0, 0), 3, 0);
    CHECK_NEAR(value_at(src, -3, 0, 0, 0), 6, 0);
    fm_hf_model m;
    char buf[256];
    snprintf(buf, sizeof buf, "o(x[3]) { %s }", src);
    fm_node r = compile_src(buf, &m);
    int has_select = 0;
    for (size_t i = 1; i <= fm_graph_node_count(G); i++)
        if (fm_node_op(G, (fm_node)i) == FM_OP_SELECT && fm_node_depends_on(G, r, FM_X)) has_select = 1;
    CHECK(has_select);
    /* constant if follows one branch: no select, and the other branch may
     * even call something unknown without an error */
    CHECK_NEAR(value("if 1 > 2 then o = nothing(1); else o = 5; endif;"), 5, 0);
    /* while with a constant condition unrolls; nested loops */
    CHECK_NEAR(value("s = 0; i = 1; while i <= 4 loop j = 1; while j <= i loop s = s + j; j = j + 1; endloop; i = i + 1; endloop; o = s;"),
               1 + 3 + 6 + 10, 0);
    /* arrays: declaration, item and list assignment, copy */
    CHECK_NEAR(value("array v[3], w[3]; v = [1, 2, 3]; v[2] = 20; w = v; w[1] = 0; o = v[1] + v[2] + w[1] + w[3];"),
               1 + 20 + 0 + 3, 0);
    /* indexes round to the nearest integer as in HyperFun */
    CHECK_NEAR(value("array v[3]; v = [1, 2, 3]; o = v[2.4] + v[2.6];"), 5, 0);
    /* a variable assigned on both branches of a point-dependent if */
    CHECK_NEAR(value_at("if x[2] < 1 then r = 1; else r = 2; endif; o = r * 10;", 0, 5, 0, 0), 20, 0);
    /* case-insensitive names and keywords */
    CHECK_NEAR(value("ABC = 2; IF abc = 2 THEN o = AbC + 1; ENDIF;"), 3, 0);
}

static void objects_and_params(void)
{
    const char *src =
        "ball(x[3], a[1]) { array c[3]; c = [0, 0, 0]; ball = hfSphere(x, c, a[1]); }\n"
        "twice(x[4], a[2]) { array b[1], y[3]; b[1] = 2 * a[1];\n"
        "  y[1] = x[1]; y[2] = x[2]; y[3] = x[3];\n"
        "  r = hfShift3D(y, 1, 0, 0);\n"
        "  twice = ball(y, b) + a[2] * x[4] + x[1];\n"
        "}\n";
    fm_hf_model m;
    fm_node r = compile_src(src, &m);
    CHECK(m.dimension == 4 && m.param_count == 2);
    CHECK(!strcmp(m.param_names[0], "a1") && !strcmp(m.param_names[1], "a2"));
    CHECK(!strcmp(m.name, "twice"));
    CHECK(fm_graph_set_param(G, "a1", 1.5) == FM_OK);
    CHECK(fm_graph_set_param(G, "a2", 10) == FM_OK);
    double p[4] = {2, 1, 0.5, 0.25};
    /* ball at y = (x1 - 1, x2, x3) with radius 3: 9 - (1 + 1 + 0.25); the
     * callee's shift of y does not change the caller's x */
    CHECK_NEAR(fm_graph_eval_reference(G, r, p), 9 - 2.25 + 2.5 + 2, 1e-12);
    /* a named model */
    fm_error err;
    fm_hf_model mb;
    CHECK(fm_hf_compile_string(G, src, strlen(src), "lang", "BALL", NULL, &mb, &err) == FM_OK);
    CHECK(mb.dimension == 3 && !strcmp(mb.name, "ball"));
}

static void extension(void)
{
    /* fmMetamorph (eq. 15): f1 (1 - s) + f2 s, s = clamp((t - t0)/(t1 - t0), 0, 1) */
    const char *mm = "o = fmMetamorph(x[1], x[2], 1, 3);";
    CHECK_NEAR(value_at(mm, 4, 8, 0, 0), 4, 1e-12);
    CHECK_NEAR(value_at(mm, 4, 8, 0, 2), 6, 1e-12);
    CHECK_NEAR(value_at(mm, 4, 8, 0, 9), 8, 1e-12);
    /* fmTimeSegment (eq. 14) = min(t - t0, t1 - t) */
    CHECK_NEAR(value_at("o = fmTimeSegment(1, 3);", 0, 0, 0, 1.5), 0.5, 1e-12);
    CHECK_NEAR(value_at("o = fmTimeSegment(1, 3);", 0, 0, 0, 5), -2, 1e-12);
    CHECK_NEAR(value_at("o = fmOffset(x[1], 2);", 1, 0, 0, 0), 3, 0);
    /* fmAffineT: the unit sphere moved by X' = A X + c with A a rotation
     * by t about z and c = (t, 0, 0); at t = pi/2 the point c + A (0.5, 0, 0)
     * = (pi/2, 0.5, 0) is inside with value 1 - 0.25. */
    const char *af =
        "array y[3], c[3]; c = [0, 0, 0]; y[1] = x[1]; y[2] = x[2]; y[3] = x[3]; t = x[4];"
        "r = fmAffineT(y, cos(t), -sin(t), 0, t,  sin(t), cos(t), 0, 0,  0, 0, 1, 0);"
        "o = hfSphere(y, c, 1);";
    double h = FM_PI / 2;
    CHECK_NEAR(value_at(af, h, 0.5, 0, h), 0.75, 1e-12);
    CHECK_NEAR(value_at(af, 0.3, 0.2, 0.1, 0), 1 - 0.09 - 0.04 - 0.01, 1e-12);
    /* fmProject, fmNormalize and the offsets build their special nodes */
    fm_hf_model m;
    fm_node r = compile_src("o(x[4]) { o = fmProject(1 - (x[1] - x[4])^2 - x[2]^2 - x[3]^2, 0, 2); }", &m);
    CHECK(r && fm_node_op(G, r) == FM_OP_PROJECT && !fm_node_depends_on(G, r, FM_T));
    r = compile_src("o(x[3]) { o = fmNormalize(1 - x[1]^2) + fmOffsetNormal(x[1], 1) + fmOffsetRadius(x[2], 1); }", &m);
    CHECK(r != FM_NONE);
    /* evaluated through a compiled tape: the projection of the unit ball
     * moving from x = 0 to x = 2 is a capsule; at (1, 0.5, 0) its value is
     * 1 - 0.25 (the ball centred at x = 1 is the best). */
    r = compile_src("o(x[4]) { o = fmProject(1 - (x[1] - x[4])^2 - x[2]^2 - x[3]^2, 0, 2); }", &m);
    fm_error err;
    fm_tape *tape = fm_tape_compile(G, r, &err);
    fm_evaluator *ev = tape ? fm_evaluator_new(tape, &err) : NULL;
    CHECK(ev != NULL);
    if (ev) {
        double p[4] = {1, 0.5, 0, 7};
        CHECK_NEAR(fm_eval_point(ev, p), 0.75, 1e-6);
        double q[4] = {3, 0, 0, 0}; /* beyond the end: ball at x = 2 gives 0 */
        CHECK_NEAR(fm_eval_point(ev, q), 0, 1e-6);
    }
    fm_evaluator_free(ev);
    fm_tape_free(tape);
}

static void expression_api(void)
{
    const char *names[2] = {"t", "Phase"};
    fm_node vars[2] = {fm_var(G, FM_T), fm_param(G, "phase", 0.25)};
    fm_error err;
    fm_node e = fm_hf_parse_expression(G, "10 + 20*sin(t)", names, vars, 2, "traj", &err);
    CHECK(e != FM_NONE);
    double p[4] = {0, 0, 0, 0.7};
    CHECK_NEAR(fm_graph_eval_reference(G, e, p), 10 + 20 * sin(0.7), 1e-12);
    e = fm_hf_parse_expression(G, "PHASE * 4 + (t > 1) * 100 + hfBlendUni(t, 1, 0.5, 1, 1)", names, vars, 2,
                               "traj", &err);
    CHECK(e != FM_NONE);
    double f1 = 0.7, f2 = 1;
    CHECK_NEAR(fm_graph_eval_reference(G, e, p),
               1 + f1 + f2 + sqrt(f1 * f1 + f2 * f2) + 0.5 / (1 + f1 * f1 + f2 * f2), 1e-12);
    /* array lists as arguments work in expressions too */
    const char *xyz[3] = {"x", "y", "z"};
    fm_node xv[3] = {fm_var(G, FM_X), fm_var(G, FM_Y), fm_var(G, FM_Z)};
    e = fm_hf_parse_expression(G, "hfSphere([x, y, z], [1, 0, 0], 2)", xyz, xv, 3, "e", &err);
    double q[4] = {1, 1, 1, 0};
    CHECK(e != FM_NONE);
    CHECK_NEAR(fm_graph_eval_reference(G, e, q), 4 - 2, 1e-12);
}

static double eval_file(const char *path, double x, double y, double z)
{
    fm_hf_model m;
    fm_error err;
    fm_status st = fm_hf_compile_file(G, path, NULL, &m, &err);
    CHECK(st == FM_OK);
    if (st != FM_OK) return NAN;
    double p[4] = {x, y, z, 0};
    return fm_graph_eval_reference(G, m.root, p);
}

static void examples(void)
{
    /* form cutter: flat tip, concave corner radius 3 about (r 6, z 0), flutes r 6 to z 20, shank r 5 */
    CHECK_NEAR(eval_file("../examples/form_cutter.hf", 0, 0, 1), 1, 1e-12);
    CHECK_NEAR(eval_file("../examples/form_cutter.hf", 0, 0, 10), 6, 1e-12);
    CHECK_NEAR(eval_file("../examples/form_cutter.hf", 6, 0, 3), 0, 1e-12);
    double s = sqrt(0.5);
    CHECK_NEAR(eval_file("../examples/form_cutter.hf", (6 - 3 * s) * s, (6 - 3 * s) * s, 3 * s), 0, 1e-12);
    CHECK_NEAR(eval_file("../examples/form_cutter.hf", 0, 7, 40), -2, 1e-12);
    CHECK(eval_file("../examples/form_cutter.hf", 5.5, 0, 0.5) < 0); /* inside the rounding torus */
    /* clamp */
    CHECK_NEAR(eval_file("../examples/clamp.hf", -12, 30, 45), 5, 1e-12);   /* bolt axis above the nut */
    CHECK_NEAR(eval_file("../examples/clamp.hf", 0, 30, 35), 5, 1e-12);     /* strap middle */
    CHECK(eval_file("../examples/clamp.hf", 50, 30, 15) < 0);               /* the stock's place */
    CHECK(eval_file("../examples/clamp.hf", 0, 0, -1) < 0);
    /* cast stock: centre 15 from top and bottom; walls lean in by tan 3 deg */
    CHECK_NEAR(eval_file("../examples/cast_stock.hf", 50, 30, 15), 15, 1e-12);
    double t3 = tan(3 * FM_PI / 180);
    CHECK_NEAR(eval_file("../examples/cast_stock.hf", 100 - 15 * t3, 30, 15), 0, 1e-12);
    CHECK_NEAR(eval_file("../examples/cast_stock.hf", 50, 60 - 10 * t3, 10), 0, 1e-12);
    CHECK(eval_file("../examples/cast_stock.hf", 0.5, 0.5, 0.5) < 0); /* filleted corner */
}

int main(void)
{
    G = fm_graph_new(0);
    precedence();
    r_functions();
    builtins();
    control();
    objects_and_params();
    extension();
    expression_api();
    examples();
    fm_graph_free(G);
    return test_summary("hf_lang");
}
