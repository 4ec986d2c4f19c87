/* cmd_eval.c: `frepmill eval`, evaluate a HyperFun model at a point (and
 * optionally its gradient and its interval enclosure over a box). The model
 * is compiled by lib/hf and evaluated through a compiled tape, the same
 * path the pipeline uses. Errors print as file:line:column: message. */
#include "commands.h"

#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "frep/frep.h"
#include "hf/hf.h"

static void eval_usage(FILE *out)
{
    fprintf(out,
            "usage: frepmill eval MODEL.hf X Y Z [T] [--grad]\n"
            "                     [--interval X0 X1 Y0 Y1 Z0 Z1 [T0 T1]]\n"
            "                     [--model NAME] [--param NAME=VALUE]...\n\n"
            "Prints f at the point (positive inside, negative outside). --grad adds\n"
            "df/dx df/dy df/dz df/dt; --interval adds an enclosure of f over the box.\n"
            "--model picks an object of the file (default: the last one); --param\n"
            "sets a model parameter such as a1 (default 0). The language is\n"
            "described in docs/hf.md.\n");
}

static int parse_number(const char *s, double *v)
{
    char *end;
    if (!s || !*s) return 0;
    *v = strtod(s, &end);
    return *end == '\0';
}

static int fail(const char *fmt, const char *arg)
{
    fprintf(stderr, "frepmill eval: ");
    fprintf(stderr, fmt, arg);
    fprintf(stderr, "\n");
    return 2;
}

int fm_cmd_eval(int argc, char **argv)
{
    const char *path = NULL, *model_name = NULL;
    double point[4] = {0, 0, 0, 0};
    int n_coords = 0, want_grad = 0, want_interval = 0, n_box = 0;
    double box[8] = {0};
    const char *params[64];
    int n_params = 0;
    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            eval_usage(stdout);
            return 0;
        } else if (!strcmp(a, "--grad")) {
            want_grad = 1;
        } else if (!strcmp(a, "--interval")) {
            want_interval = 1;
            while (n_box < 8 && i + 1 < argc && parse_number(argv[i + 1], &box[n_box])) {
                n_box++;
                i++;
            }
            if (n_box != 6 && n_box != 8)
                return fail("--interval needs 6 numbers (X0 X1 Y0 Y1 Z0 Z1) or 8 (and T0 T1)%s", "");
        } else if (!strcmp(a, "--model")) {
            if (++i >= argc) return fail("--model needs a name%s", "");
            model_name = argv[i];
        } else if (!strcmp(a, "--param")) {
            if (++i >= argc || !strchr(argv[i], '=')) return fail("--param needs NAME=VALUE%s", "");
            if (n_params == 64) return fail("too many --param options%s", "");
            params[n_params++] = argv[i];
        } else if (a[0] == '-' && a[1] == '-') {
            eval_usage(stderr);
            return fail("unknown option '%s'", a);
        } else if (!path) {
            path = a;
        } else if (n_coords < 4 && parse_number(a, &point[n_coords])) {
            n_coords++;
        } else {
            eval_usage(stderr);
            return fail("unexpected argument '%s' (expected a number)", a);
        }
    }
    if (!path || n_coords < 3) {
        eval_usage(stderr);
        return 2;
    }

    fm_graph *g = fm_graph_new(0);
    if (!g) return fail("out of memory%s", "");
    fm_hf_model model;
    fm_error err;
    char buf[1024];
    fm_status st = fm_hf_compile_file(g, path, model_name, &model, &err);
    if (st != FM_OK) {
        fprintf(stderr, "%s\n", fm_error_format(&err, buf, sizeof buf));
        fm_graph_free(g);
        return (int)st;
    }
    for (int i = 0; i < n_params; i++) {
        char name[128];
        const char *eq = strchr(params[i], '=');
        size_t len = (size_t)(eq - params[i]);
        double v;
        if (len == 0 || len >= sizeof name || !parse_number(eq + 1, &v)) {
            fm_graph_free(g);
            return fail("bad --param '%s' (expected NAME=VALUE)", params[i]);
        }
        memcpy(name, params[i], len);
        name[len] = '\0';
        for (char *c = name; *c; c++)
            if (*c >= 'A' && *c <= 'Z') *c = (char)(*c - 'A' + 'a');
        if (fm_graph_set_param(g, name, v) != FM_OK) {
            fprintf(stderr, "frepmill eval: the model has no parameter '%s'", name);
            if (model.param_count) fprintf(stderr, " (it has %s..%s)", model.param_names[0],
                                           model.param_names[model.param_count - 1]);
            fprintf(stderr, "\n");
            fm_graph_free(g);
            return 2;
        }
    }
    fm_tape *tape = fm_tape_compile(g, model.root, &err);
    fm_evaluator *ev = tape ? fm_evaluator_new(tape, &err) : NULL;
    if (!ev) {
        fprintf(stderr, "%s: %s\n", path, fm_error_format(&err, buf, sizeof buf));
        fm_tape_free(tape);
        fm_graph_free(g);
        return err.code ? (int)err.code : 5;
    }
    double value;
    if (want_grad) {
        double grad[4];
        value = fm_eval_grad(ev, point, grad);
        printf("%.17g\n", value);
        printf("grad %.17g %.17g %.17g %.17g\n", grad[0], grad[1], grad[2], grad[3]);
    } else {
        value = fm_eval_point(ev, point);
        printf("%.17g\n", value);
    }
    if (want_interval) {
        fm_interval b[4];
        for (int k = 0; k < 3; k++) {
            b[k].lo = box[2 * k];
            b[k].hi = box[2 * k + 1];
        }
        b[3].lo = n_box == 8 ? box[6] : point[3];
        b[3].hi = n_box == 8 ? box[7] : point[3];
        fm_interval r = fm_eval_interval(ev, b);
        printf("interval %.17g %.17g\n", r.lo, r.hi);
    }
    fm_evaluator_free(ev);
    fm_tape_free(tape);
    fm_graph_free(g);
    return 0;
}
