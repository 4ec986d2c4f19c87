/* cmd_mesh.c: `frepmill mesh`: mesh a HyperFun model directly, through the
 * same narrow-band rasterizer the stock uses, and write it as a mesh file
 * and/or a picture. */
#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "commands.h"
#include "frep/frep.h"
#include "hf/hf.h"
#include "mesh/mesh.h"

#define MESH_MAX_OUTPUTS 8

static void usage(FILE *out)
{
    fprintf(out,
            "usage: frepmill mesh MODEL.hf --bounds X0,Y0,Z0,X1,Y1,Z1 --voxel MM\n"
            "                     [--out FILE]... [--png FILE] [--png-size WxH]\n"
            "                     [--model NAME] [--param NAME=VALUE]... [--time T]\n"
            "\n"
            "Meshes the model (positive inside) within the bounds, which also close it.\n"
            "--out     .drc, .stl, .ply or .obj (may be given several times)\n"
            "--png     an isometric shaded picture, Z up\n"
            "--time    the time at which a 4D model (x[4]) is meshed (default 0)\n"
            "Exit status: 0 success, 2 bad input, 3 resource limit, 4 I/O error.\n");
}

static int parse_number(const char *s, double *out)
{
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    return end != s && *end == '\0' && errno != ERANGE && isfinite(*out);
}

static int parse_bounds(const char *s, double lo[3], double hi[3])
{
    double v[6];
    for (int i = 0; i < 6; i++) {
        char *end;
        errno = 0;
        v[i] = strtod(s, &end);
        if (end == s || errno == ERANGE || !isfinite(v[i])) return 0;
        s = end;
        if (i < 5) {
            if (*s != ',') return 0;
            s++;
        }
    }
    if (*s) return 0;
    for (int k = 0; k < 3; k++) {
        lo[k] = v[k];
        hi[k] = v[k + 3];
        if (!(lo[k] < hi[k])) return 0;
    }
    return 1;
}

static int exit_status(fm_status st)
{
    return st == FM_ERR_LIMIT ? 3 : st == FM_ERR_IO ? 4 : st == FM_ERR_INPUT ? 2 : st ? 5 : 0;
}

static int fail(const char *what, const char *arg)
{
    fprintf(stderr, "frepmill mesh: %s%s\n", what, arg);
    return 2;
}

int fm_cmd_mesh(int argc, char **argv)
{
    const char *path = NULL, *model_name = NULL, *png = NULL;
    const char *outputs[MESH_MAX_OUTPUTS];
    const char *params[64];
    int n_outputs = 0, n_params = 0, have_bounds = 0;
    double lo[3], hi[3], voxel = 0, time = 0;
    int width = 1024, height = 768;

    for (int i = 1; i < argc; i++) {
        const char *a = argv[i];
        const char *v = i + 1 < argc ? argv[i + 1] : NULL;
        if (!strcmp(a, "--help") || !strcmp(a, "-h")) {
            usage(stdout);
            return 0;
        }
        if (a[0] != '-' || !a[1]) {
            if (path) return fail("more than one model given: ", a);
            path = a;
            continue;
        }
        if (!v) return fail("this option needs a value: ", a);
        i++;
        if (!strcmp(a, "--bounds")) {
            if (!parse_bounds(v, lo, hi))
                return fail("--bounds expects X0,Y0,Z0,X1,Y1,Z1 with each lower value first, not ", v);
            have_bounds = 1;
        } else if (!strcmp(a, "--voxel")) {
            if (!parse_number(v, &voxel) || voxel <= 0) return fail("--voxel expects mm above 0, not ", v);
        } else if (!strcmp(a, "--time")) {
            if (!parse_number(v, &time)) return fail("--time expects a number, not ", v);
        } else if (!strcmp(a, "--out")) {
            if (fm_mesh_format_from_path(v) == FM_MESH_FORMAT_UNKNOWN)
                return fail("--out: unknown format (use .drc, .stl, .ply or .obj): ", v);
            if (n_outputs == MESH_MAX_OUTPUTS) return fail("too many --out files", "");
            outputs[n_outputs++] = v;
        } else if (!strcmp(a, "--png")) {
            png = v;
        } else if (!strcmp(a, "--png-size")) {
            char tail;
            if (sscanf(v, "%dx%d%c", &width, &height, &tail) != 2 || width < 16 || height < 16 ||
                width > 8192 || height > 8192)
                return fail("--png-size expects WxH within 16..8192, not ", v);
        } else if (!strcmp(a, "--model")) {
            model_name = v;
        } else if (!strcmp(a, "--param")) {
            if (!strchr(v, '=') || n_params == 64) return fail("--param expects NAME=VALUE, not ", v);
            params[n_params++] = v;
        } else {
            usage(stderr);
            return fail("unknown option ", a);
        }
    }
    if (!path || !have_bounds || voxel <= 0 || (n_outputs == 0 && !png)) {
        usage(stderr);
        return fail(!path ? "no MODEL given" : !have_bounds ? "no --bounds given"
                    : voxel <= 0                  ? "no --voxel given"
                                                  : "nothing to write (give --out or --png)",
                    "");
    }

    fm_graph *g = fm_graph_new(0);
    if (!g) return fail("out of memory", "");
    fm_error err;
    fm_error_clear(&err);
    char buf[1024];
    int status = 0;
    fm_tape *tape = NULL;
    fm_mesh *mesh = NULL;
    fm_field field;
    memset(&field, 0, sizeof field);
    fm_hf_model model;
    fm_status st = fm_hf_compile_file(g, path, model_name, &model, &err);
    for (int i = 0; st == FM_OK && i < n_params; i++) {
        char name[128];
        const char *eq = strchr(params[i], '=');
        size_t len = (size_t)(eq - params[i]);
        double value;
        if (len == 0 || len >= sizeof name || !parse_number(eq + 1, &value)) {
            st = fm_error_set(&err, FM_ERR_INPUT, "bad --param '%s' (expected NAME=VALUE)", params[i]);
            break;
        }
        memcpy(name, params[i], len);
        name[len] = '\0';
        for (char *c = name; *c; c++)
            if (*c >= 'A' && *c <= 'Z') *c = (char)(*c - 'A' + 'a');
        if (fm_graph_set_param(g, name, value) != FM_OK)
            st = fm_error_set(&err, FM_ERR_INPUT, "the model has no parameter '%s'", name);
    }
    if (st == FM_OK) {
        /* HyperFun functions are seldom distances: normalize to first order
         * (Shapiro eq. 4.9), and intersect with the bounds (an exact
         * distance), which closes the mesh there and makes the field
         * negative outside the box as the rasterizer requires. */
        fm_node root = fm_min(g, fm_normalize(g, model.root), fm_block(g, lo, hi));
        if (!root) {
            err = *fm_graph_error(g);
            st = err.code;
        } else if (!(tape = fm_tape_compile(g, root, &err))) {
            st = err.code ? err.code : FM_ERR_INTERNAL;
        } else {
            double flo[3], fhi[3];
            for (int k = 0; k < 3; k++) {
                flo[k] = lo[k] - 2 * voxel;
                fhi[k] = hi[k] + 2 * voxel;
            }
            st = fm_field_from_tape(&field, tape, flo, fhi, time, &err);
        }
    }
    if (st == FM_OK) {
        fm_mesh_extract_options eo;
        fm_mesh_extract_default(&eo);
        mesh = fm_mesh_from_field(&field, voxel, &eo, &err);
        if (!mesh) st = err.code ? err.code : FM_ERR_INTERNAL;
    }
    for (int i = 0; st == FM_OK && i < n_outputs; i++)
        st = fm_mesh_write_file(mesh, outputs[i], NULL, &err);
    if (st == FM_OK && png) {
        fm_render_options ro;
        fm_render_default(&ro);
        ro.width = width;
        ro.height = height;
        st = fm_render_png(mesh, &ro, png, &err);
    }
    if (st != FM_OK) {
        fprintf(stderr, "frepmill mesh: %s\n", fm_error_format(&err, buf, sizeof buf));
        status = exit_status(st);
    } else {
        fprintf(stderr, "frepmill mesh: %zu triangles, %zu vertices, volume %.3f mm3\n",
                mesh->triangle_count, mesh->vertex_count, fm_mesh_volume(mesh));
    }
    fm_mesh_free(mesh);
    fm_field_release(&field);
    fm_tape_free(tape);
    fm_graph_free(g);
    return status;
}
