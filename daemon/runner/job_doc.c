/* job_doc.c: parsing and validating the job document (job_doc.h) into the
 * run spec, and its canonical JSON. Every error says which key and why;
 * JSON syntax errors carry their line and column. */
#include "job_doc.h"

#include <ctype.h>
#include <errno.h>
#include <math.h>
#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <sys/stat.h>

#include "dynamics.h"
#include "machine.h"
#include "stock_spec.h"
#include "toolpaths/gcode/gcode.h"
#include "toolpaths/tooltable/tooltable.h"

/* The longest stock spec string (a box or cylinder, or a file path). */
#define DOC_STOCK_TEXT_MAX 4096
#define DOC_NAME_MAX 128
#define DOC_PATH_LIST_MAX 4096

/* ------------------------------------------------------------- base64 -- */

static int base64_value(unsigned char c)
{
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    return -1;
}

int fm_base64_decode(const char *in, size_t len, uint8_t **out, size_t *out_len)
{
    *out = NULL;
    *out_len = 0;
    uint8_t *buf = malloc(len / 4 * 3 + 4);
    if (!buf) return -1;
    size_t n = 0;
    uint32_t acc = 0;
    int bits = 0, padding = 0;
    for (size_t i = 0; i < len; i++) {
        unsigned char c = (unsigned char)in[i];
        if (c == '\n' || c == '\r') continue;
        if (c == '=') {
            padding++;
            continue;
        }
        int v = base64_value(c);
        if (v < 0 || padding) { /* a character after padding is not base64 */
            free(buf);
            return -1;
        }
        acc = (acc << 6) | (uint32_t)v;
        bits += 6;
        if (bits >= 8) {
            bits -= 8;
            buf[n++] = (uint8_t)(acc >> bits);
        }
    }
    /* Leftover bits must be the zero padding of a short final group. */
    if (padding > 2 || bits >= 6 || (acc & ((1u << bits) - 1)) != 0) {
        free(buf);
        return -1;
    }
    *out = buf;
    *out_len = n;
    return 0;
}

/* ---------------------------------------------------------- validation -- */

/* Refusals: FM_ERR_INPUT (FM_ERR_LIMIT for "too_large") with a reason. */
static fm_status refuse(fm_error *err, const char *reason, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 3, 4)))
#endif
    ;
static fm_status refuse(fm_error *err, const char *reason, const char *fmt, ...)
{
    char message[512];
    va_list ap;
    va_start(ap, fmt);
    vsnprintf(message, sizeof message, fmt, ap);
    va_end(ap);
    fm_status code = !strcmp(reason, "too_large") ? FM_ERR_LIMIT : FM_ERR_INPUT;
    return fm_error_set_reason(err, code, reason, "%s", message);
}

static fm_status only_keys(json_t *obj, const char *const *keys, const char *where,
                           fm_error *err)
{
    const char *key;
    json_t *value;
    json_object_foreach(obj, key, value) {
        int known = 0;
        for (const char *const *k = keys; *k; k++)
            if (!strcmp(key, *k)) known = 1;
        if (!known) {
            char list[256] = "";
            for (const char *const *k = keys; *k; k++) {
                strncat(list, k == keys ? "" : ", ", sizeof list - strlen(list) - 1);
                strncat(list, *k, sizeof list - strlen(list) - 1);
            }
            return refuse(err, "unknown_key", "%s: unknown key \"%.64s\" (known: %s)", where, key,
                          list);
        }
    }
    (void)value;
    return FM_OK;
}

static fm_status text_ok(json_t *v, const char *where, size_t max, fm_error *err)
{
    if (!json_is_string(v)) return refuse(err, "bad_type", "%s must be a string", where);
    size_t n = json_string_length(v);
    if (n == 0) return refuse(err, "bad_value", "%s is empty", where);
    if (n > max) return refuse(err, "too_large", "%s is %zu bytes; at most %zu", where, n, max);
    if (memchr(json_string_value(v), '\0', n))
        return refuse(err, "bad_value", "%s contains a NUL character", where);
    return FM_OK;
}

static fm_status number_in(json_t *v, const char *where, double lo, double hi, double *out,
                           fm_error *err)
{
    if (!json_is_number(v)) return refuse(err, "bad_type", "%s must be a number", where);
    double d = json_number_value(v);
    if (!isfinite(d) || d < lo || d > hi)
        return refuse(err, "bad_value", "%s = %g is outside [%g, %g]", where, d, lo, hi);
    if (out) *out = d;
    return FM_OK;
}

static fm_status integer_in(json_t *v, const char *where, double lo, double hi, int *out,
                            fm_error *err)
{
    double d = 0;
    fm_status st = number_in(v, where, lo, hi, &d, err);
    if (st != FM_OK) return st;
    if (!json_is_integer(v)) return refuse(err, "bad_type", "%s must be an integer", where);
    *out = (int)d;
    return FM_OK;
}

static char *dup_bytes(const char *s, size_t n)
{
    char *p = malloc(n + 1);
    if (!p) return NULL;
    memcpy(p, s, n);
    p[n] = '\0';
    return p;
}

/* {"hyperfun": TEXT} or {"stl_base64": TEXT} (+ "name" where allowed) into
 * model; where names the key in messages, reason is the refusal's. */
static fm_status model_of(json_t *obj, const char *where, const char *reason, int named,
                          fm_job_model *model, fm_error *err)
{
    static const char *const plain[] = {"hyperfun", "stl_base64", NULL};
    static const char *const with_name[] = {"hyperfun", "stl_base64", "name", NULL};
    json_t *hf = json_is_object(obj) ? json_object_get(obj, "hyperfun") : NULL;
    json_t *stl = json_is_object(obj) ? json_object_get(obj, "stl_base64") : NULL;
    if (!hf == !stl)
        return refuse(err, reason, "%s must be {\"hyperfun\": TEXT} or {\"stl_base64\": TEXT}",
                      where);
    fm_status st = only_keys(obj, named ? with_name : plain, where, err);
    if (st != FM_OK) return st;
    char sub[96];
    snprintf(sub, sizeof sub, "%s.%s", where, hf ? "hyperfun" : "stl_base64");
    if ((st = text_ok(hf ? hf : stl, sub, FM_JOB_DOC_MAX_TEXT, err)) != FM_OK) return st;
    json_t *name = named ? json_object_get(obj, "name") : NULL;
    if (name) {
        snprintf(sub, sizeof sub, "%s.name", where);
        if ((st = text_ok(name, sub, DOC_NAME_MAX, err)) != FM_OK) return st;
        snprintf(model->name, sizeof model->name, "%s", json_string_value(name));
    }
    if (hf) {
        model->is_stl = 0;
        model->data = dup_bytes(json_string_value(hf), json_string_length(hf));
        model->size = json_string_length(hf);
        if (!model->data) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        return FM_OK;
    }
    uint8_t *bytes;
    size_t n;
    if (fm_base64_decode(json_string_value(stl), json_string_length(stl), &bytes, &n) != 0)
        return refuse(err, reason, "%s.stl_base64 is not valid base64", where);
    if (n < 84) {
        free(bytes);
        return refuse(err, reason, "%s.stl_base64 decodes to %zu bytes, too short for an STL file",
                      where, n);
    }
    model->is_stl = 1;
    model->data = (char *)bytes;
    model->size = n;
    return FM_OK;
}

static fm_status parse_stock(fm_job_doc *doc, json_t *stock, const fm_job_doc_rules *rules,
                             fm_error *err)
{
    if (json_is_string(stock)) {
        fm_status st = text_ok(stock, "stock", DOC_STOCK_TEXT_MAX, err);
        if (st != FM_OK) return st;
        const char *s = json_string_value(stock);
        fm_stock_spec shape;
        fm_error serr;
        if (fm_stock_spec_parse(s, &shape, &serr) != FM_OK)
            return refuse(err, "bad_stock", "%s", serr.message);
        /* Only shapes over the network: a client must never name a file
         * on the server (a .vdb or .hf path); models come inline. */
        if (shape.shape != FM_STOCK_SHAPE_BOX && shape.shape != FM_STOCK_SHAPE_CYLINDER &&
            !rules->allow_files)
            return refuse(err, "bad_stock",
                          "stock \"%.64s\": expected \"box:X0,Y0,Z0,X1,Y1,Z1\", "
                          "\"cylinder:X,Y,Z0,Z1,R\", {\"hyperfun\": TEXT} or "
                          "{\"stl_base64\": TEXT}",
                          s);
        doc->stock_text = dup_bytes(s, json_string_length(stock));
        return doc->stock_text ? FM_OK : fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    }
    if (!json_is_object(stock) || json_object_size(stock) != 1)
        return refuse(err, "bad_stock",
                      "stock must be a spec string or an object with exactly one of "
                      "\"hyperfun\" and \"stl_base64\"");
    return model_of(stock, "stock", "bad_stock", 0, &doc->stock_model, err);
}

/* A tool table reader's warning, kept with the document (one a line). */
static void doc_warning(void *user, const char *message)
{
    fm_job_doc *doc = user;
    size_t have = doc->warnings ? strlen(doc->warnings) : 0, add = strlen(message);
    if (have + add > 65536) return; /* enough to read; the rest are alike */
    char *w = realloc(doc->warnings, have + add + 2);
    if (!w) return;
    memcpy(w + have, message, add);
    w[have + add] = '\n';
    w[have + add + 1] = '\0';
    doc->warnings = w;
}

static fm_status parse_tools(fm_job_doc *doc, json_t *tools, const fm_job_doc_rules *rules,
                             fm_error *err)
{
    const fm_tooltable_options topt = {doc_warning, doc};
    if (json_is_string(tools)) {
        /* a tool table file (JSON or LinuxCNC .tbl): the CLI's --tools */
        fm_status st = text_ok(tools, "tools", DOC_STOCK_TEXT_MAX, err);
        if (st != FM_OK) return st;
        const char *path = json_string_value(tools);
        if (!rules->allow_files)
            return refuse(err, "bad_tools",
                          "tools \"%.64s\" names a file on the server; give the JSON tool table",
                          path);
        if (!(doc->tools_path = dup_bytes(path, strlen(path))))
            return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        /* the loader's own error: file:line:column, and I/O for a missing file */
        if ((st = fm_tooltable_load_with(path, &topt, &doc->tools, err)) != FM_OK) return st;
        if (doc->tools.count == 0)
            return refuse(err, "bad_tools", "the tool table %s has no tools", path);
        doc->spec.tools_path = doc->tools_path;
        return FM_OK;
    }
    if (!json_is_object(tools))
        return refuse(err, "bad_type", "tools must be a JSON tool table (an object) or a file");
    /* parsed once, with the document: no text in between */
    fm_error terr;
    fm_error_clear(&terr);
    fm_status st = fm_tooltable_from_json_with(tools, "tools", &topt, &doc->tools, &terr);
    if (st != FM_OK) return refuse(err, "bad_tools", "tools: %s", terr.message);
    if (doc->tools.count == 0) return refuse(err, "bad_tools", "tools: the table has no tools");
    for (size_t i = 0; i < doc->tools.count && !rules->allow_files; i++)
        if (doc->tools.tools[i].shape == FM_TOOL_HYPERFUN)
            /* Such a tool names a model file on this machine; over the
             * network that would read the server's files. */
            return refuse(err, "bad_tools",
                          "tools: tool %d is a HyperFun tool that names a file; not accepted "
                          "over the network",
                          doc->tools.tools[i].number);
    return FM_OK;
}

/* No table: the program's comments name the tools (with the options the
 * program runs with: dialect, subroutines, machine). Parsed once, here, so
 * that every entrance sees the same tools; a live program has none. */
static fm_status tools_from_program(fm_job_doc *doc, fm_error *err)
{
    if (doc->spec.program_kind == FM_PROGRAM_LIVE)
        return refuse(err, "bad_tools", "options.tools_from_program: a live program has no "
                      "comments to read; give \"tools\"");
    const fm_tooltable_options topt = {doc_warning, doc};
    fm_job_spec probe = doc->spec;
    probe.machine = doc->has_machine ? &doc->check.options.machine.chain : NULL;
    fm_error terr;
    fm_error_clear(&terr);
    fm_status st = fm_job_tools_from_program(&probe, &topt, &doc->tools, &terr);
    if (st == FM_ERR_INPUT) {
        char buf[700];
        return refuse(err, "bad_tools", "%s", fm_error_format(&terr, buf, sizeof buf));
    }
    if (st != FM_OK) *err = terr;
    return st;
}

static fm_status parse_program(fm_job_doc *doc, json_t *program, const fm_job_doc_rules *rules,
                               fm_error *err)
{
    if (!json_is_object(program) || json_object_size(program) != 1)
        return refuse(err, "bad_program",
                      "program must be an object with exactly one of \"gcode\" (text) and "
                      "\"trajectory\" (object)");
    static const char *const keys[] = {"gcode", "trajectory", "live", "file", NULL};
    fm_status st = only_keys(program, keys, "program", err);
    if (st != FM_OK) return st;
    json_t *v;
    if ((v = json_object_get(program, "file"))) {
        /* G-code, or a trajectory (.json) by its extension: the CLI's PROGRAM */
        if ((st = text_ok(v, "program.file", DOC_STOCK_TEXT_MAX, err)) != FM_OK) return st;
        if (!rules->allow_files)
            return refuse(err, "bad_program",
                          "program.file names a file on the server; give \"gcode\" or "
                          "\"trajectory\"");
        doc->program_file = dup_bytes(json_string_value(v), json_string_length(v));
        if (!doc->program_file) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        doc->spec.program_kind = FM_PROGRAM_AUTO;
        doc->spec.program_path = doc->program_file;
        return FM_OK;
    }
    if ((v = json_object_get(program, "gcode"))) {
        if ((st = text_ok(v, "program.gcode", FM_JOB_DOC_MAX_TEXT, err)) != FM_OK) return st;
        doc->program = dup_bytes(json_string_value(v), json_string_length(v));
        doc->program_length = json_string_length(v);
        doc->spec.program_kind = FM_PROGRAM_GCODE;
        doc->spec.program_name = "program";
    } else if ((v = json_object_get(program, "trajectory"))) {
        if (!json_is_object(v)) return refuse(err, "bad_type", "program.trajectory must be an object");
        /* Indented like the tool table: the trajectory's error lines and
         * the toolpath's program text refer to this form. */
        doc->program = json_dumps(v, JSON_INDENT(1));
        if (doc->program && strlen(doc->program) > FM_JOB_DOC_MAX_TEXT)
            return refuse(err, "too_large", "program.trajectory is over %zu bytes",
                          FM_JOB_DOC_MAX_TEXT);
        doc->program_length = doc->program ? strlen(doc->program) : 0;
        doc->spec.program_kind = FM_PROGRAM_TRAJECTORY;
        doc->spec.program_name = "trajectory";
    } else {
        v = json_object_get(program, "live");
        if (!rules->allow_live)
            return refuse(err, "bad_program",
                          "program.live: live jobs are made by the daemon's live mode "
                          "(Modbus registers 110-117), not submitted");
        if (!json_is_object(v)) return refuse(err, "bad_type", "program.live must be an object");
        static const char *const live_keys[] = {"feed", NULL};
        if ((st = only_keys(v, live_keys, "program.live", err)) != FM_OK) return st;
        doc->live_feed = 1000;
        json_t *feed = json_object_get(v, "feed");
        if (feed && (st = number_in(feed, "program.live.feed", 1e-3, 1e7, &doc->live_feed, err)))
            return st;
        doc->program = dup_bytes("", 0);
        doc->spec.program_kind = FM_PROGRAM_LIVE;
        doc->spec.program_name = "live";
        return doc->program ? FM_OK : fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    }
    if (!doc->program) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    doc->spec.program_text = doc->program;
    doc->spec.program_length = doc->program_length;
    return FM_OK;
}

static fm_status parse_machine(fm_job_doc *doc, json_t *machine, const char *where,
                               const fm_job_doc_rules *rules, fm_error *err)
{
    if (doc->has_machine)
        return refuse(err, "bad_job",
                      "the machine is given twice (\"machine\" and options.check.machine); give "
                      "it once, as \"machine\"");
    fm_error merr;
    fm_error_clear(&merr);
    if (json_is_string(machine) && rules->allow_files) {
        /* a machine file (docs/check.md): the CLI's --machine; its loader's
         * error as it is (file, and I/O for a missing file) */
        if (fm_check_machine_load(json_string_value(machine), &doc->check.options.machine,
                                  err) != FM_OK ||
            fm_plan_machine_load(json_string_value(machine), &doc->dynamics, err) != FM_OK)
            return err ? err->code : FM_ERR_INPUT;
    } else if (!json_is_object(machine)) {
        return refuse(err, "bad_type", "%s must be an object", where);
    } else if (fm_check_machine_from_json(machine, where, &doc->check.options.machine, &merr) !=
               FM_OK) {
        return refuse(err, "bad_value", "%s", merr.message);
    } else if (json_object_get(machine, "dynamics") &&
               fm_plan_machine_from_json(json_object_get(machine, "dynamics"), where, &doc->dynamics,
                                         &merr) != FM_OK) {
        return refuse(err, "bad_value", "%s", merr.message);
    }
    /* a component names a model file on this machine: not from a client */
    if (doc->check.options.machine.component_count && !rules->allow_files)
        return refuse(err, "bad_value",
                      "%s.components name files on the server; not accepted over the network "
                      "(give machine components as fixtures)",
                      where);
    doc->has_machine = 1;
    return FM_OK;
}

/* options.check: false, or an object of lib/check's options. */
static fm_status parse_check(fm_job_doc *doc, json_t *check, const fm_job_doc_rules *rules,
                             fm_error *err)
{
    doc->check_enabled = 1;
    if (!check || json_is_true(check)) return FM_OK;
    if (json_is_false(check)) {
        doc->check_enabled = 0;
        return FM_OK;
    }
    if (!json_is_object(check))
        return refuse(err, "bad_type", "options.check must be false (no collision check) or an "
                                       "object");
    fm_check_options *o = &doc->check.options;
    const char *key;
    json_t *v;
    json_object_foreach(check, key, v) {
        if (!strcmp(key, "machine")) {
            fm_status st = parse_machine(doc, v, "options.check.machine", rules, err);
            if (st != FM_OK) return st;
            continue;
        }
        double d = json_is_number(v) ? json_number_value(v) : NAN;
        int ok = isfinite(d);
        if (!strcmp(key, "clearance") && ok && d >= 0 && d <= 1000) {
            o->clearance_mm[FM_CHECK_PART_SHANK] = d;
            o->clearance_mm[FM_CHECK_PART_HOLDER] = d;
            o->clearance_mm[FM_CHECK_PART_HEAD] = d;
        } else if (!strcmp(key, "rapid_clearance") && ok && d >= 0 && d <= 1000) {
            o->clearance_mm[FM_CHECK_PART_FLUTES] = d;
        } else if (!strcmp(key, "tolerance") && ok && d > 0 && d <= 100) {
            o->tolerance_mm = d;
        } else if (!strcmp(key, "max_ramp") && ok && d >= 0 && d <= 90) {
            o->max_ramp_deg = d;
        } else if (!strcmp(key, "voxel") && ok && d >= FM_JOB_DOC_VOXEL_MIN && d <= 100) {
            doc->check.voxel_mm = d;
        } else if (!strcmp(key, "clearance") || !strcmp(key, "rapid_clearance") ||
                   !strcmp(key, "tolerance") || !strcmp(key, "max_ramp") ||
                   !strcmp(key, "voxel")) {
            return refuse(err, "bad_value", "options.check.%s: not a valid value", key);
        } else {
            return refuse(err, "unknown_key",
                          "options.check.%.64s: unknown (clearance, rapid_clearance, tolerance, "
                          "max_ramp, voxel, machine)",
                          key);
        }
    }
    return FM_OK;
}

/* The G-code keys of options: dialect, subroutine_path, calculator_input;
 * the server's defaults (rules) where the job gives none. */
static fm_status parse_gcode_options(fm_job_doc *doc, json_t *options,
                                     const fm_job_doc_rules *rules, fm_error *err)
{
    fm_job_spec *spec = &doc->spec;
    json_t *v = options ? json_object_get(options, "dialect") : NULL;
    const char *dialect = rules->dialect;
    if (v) {
        if (!json_is_string(v))
            return refuse(err, "bad_type", "options.dialect must be a string");
        dialect = json_string_value(v);
    }
    if (dialect) {
        fm_gcode_dialect d;
        if (!fm_gcode_dialect_parse(dialect, &d))
            return refuse(err, "bad_value",
                          "options.dialect \"%.32s\": expected \"linuxcnc\" or \"fanuc\"",
                          dialect);
        snprintf(doc->dialect, sizeof doc->dialect, "%s", fm_gcode_dialect_name(d));
        spec->dialect = doc->dialect;
    }
    v = options ? json_object_get(options, "subroutine_path") : NULL;
    if (v) {
        fm_status st = text_ok(v, "options.subroutine_path", DOC_PATH_LIST_MAX, err);
        if (st != FM_OK) return st;
        /* Folders are files on this machine: a network client must never
         * make the daemon read them (its own setting names them). */
        if (!rules->allow_files)
            return refuse(err, "bad_value",
                          "options.subroutine_path names folders on the server; not accepted "
                          "over the network (the daemon's subroutine_path setting names them)");
        doc->subroutine_path = dup_bytes(json_string_value(v), json_string_length(v));
    } else if (rules->subroutine_path && rules->subroutine_path[0]) {
        doc->subroutine_path = dup_bytes(rules->subroutine_path, strlen(rules->subroutine_path));
    }
    if ((v || (rules->subroutine_path && rules->subroutine_path[0])) && !doc->subroutine_path)
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    spec->subroutine_path = doc->subroutine_path;
    v = options ? json_object_get(options, "calculator_input") : NULL;
    if (v) {
        if (!json_is_boolean(v))
            return refuse(err, "bad_type", "options.calculator_input must be true or false");
        spec->calculator_input = json_is_true(v);
    }
    return FM_OK;
}

/* "design": the intended part to compare the stock with (issue 16,
 * docs/simulate.md), given like a stock model: inline over the network, a
 * file (.stl, .hf, .vdb) only under rules that allow files. */
static fm_status parse_design(fm_job_doc *doc, json_t *design, const fm_job_doc_rules *rules,
                              fm_error *err)
{
    if (json_is_string(design)) {
        fm_status st = text_ok(design, "design", DOC_STOCK_TEXT_MAX, err);
        if (st != FM_OK) return st;
        const char *s = json_string_value(design);
        if (!rules->allow_files)
            return refuse(err, "bad_design",
                          "design \"%.64s\" names a file on the server; give {\"hyperfun\": "
                          "TEXT} or {\"stl_base64\": TEXT}",
                          s);
        if (!fm_path_has_extension(s, ".stl") && !fm_path_has_extension(s, ".hf") &&
            !fm_path_has_extension(s, ".vdb"))
            return refuse(err, "bad_design", "design \"%.64s\": give a .stl, .hf or .vdb file", s);
        doc->design_text = dup_bytes(s, json_string_length(design));
        return doc->design_text ? FM_OK : fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    }
    if (!json_is_object(design) || json_object_size(design) != 1)
        return refuse(err, "bad_design",
                      "design must be an object with exactly one of \"hyperfun\" and "
                      "\"stl_base64\"");
    return model_of(design, "design", "bad_design", 0, &doc->design_model, err);
}

static fm_status parse_options(fm_job_doc *doc, json_t *options, const fm_job_doc_rules *rules,
                               fm_error *err)
{
    fm_job_spec *spec = &doc->spec;
    if (options && !json_is_object(options))
        return refuse(err, "bad_type", "options must be an object");
    fm_status st = parse_gcode_options(doc, options, rules, err);
    if (st != FM_OK) return st;
    if (!options) return parse_check(doc, NULL, rules, err);
    static const char *const keys[] = {"name",    "band",    "batch",
                                       "rapid_rate", "memory_budget_mb", "threads",
                                       "check",   "color",   "dialect",
                                       "subroutine_path", "calculator_input",
                                       "tolerance", "stop_at", "sweep_evaluations",
                                       "tools_from_program", "initial_tool", NULL};
    st = only_keys(options, keys, "options", err);
    if (st != FM_OK) return st;
    json_t *v;
    if ((v = json_object_get(options, "name"))) {
        if ((st = text_ok(v, "options.name", DOC_NAME_MAX, err)) != FM_OK) return st;
        snprintf(doc->name, sizeof doc->name, "%s", json_string_value(v));
    }
    if ((v = json_object_get(options, "color"))) {
        if (!json_is_string(v) ||
            (strcmp(json_string_value(v), "tool") && strcmp(json_string_value(v), "none")))
            return refuse(err, "bad_value",
                          "options.color must be \"tool\" (colour the meshes by the tool that "
                          "cut last) or \"none\"");
        doc->color_tool = !strcmp(json_string_value(v), "tool");
    }
    if ((v = json_object_get(options, "tools_from_program"))) {
        if (!json_is_boolean(v))
            return refuse(err, "bad_type", "options.tools_from_program must be true or false");
        doc->tools_from_program = json_is_true(v);
    }
    if ((v = json_object_get(options, "band")) &&
        (st = integer_in(v, "options.band", 2, 32, &spec->stock.band_voxels, err)))
        return st;
    if ((v = json_object_get(options, "batch")) &&
        (st = number_in(v, "options.batch", -1, 1000, &spec->batch_diameters, err)))
        return st;
    if ((v = json_object_get(options, "rapid_rate")) &&
        (st = number_in(v, "options.rapid_rate", 1e-3, 1e7, &spec->rapid_rate, err)))
        return st;
    if ((v = json_object_get(options, "memory_budget_mb")) &&
        (st = number_in(v, "options.memory_budget_mb", 1, 1e9, &doc->memory_budget_mb, err)))
        return st;
    if ((v = json_object_get(options, "threads"))) {
        if ((st = integer_in(v, "options.threads", 0, 1024, &spec->stock.threads, err))) return st;
        doc->threads_given = 1;
    }
    /* the design comparison's tolerance (mm; 0: half a voxel) and the
     * source line to stop after (`frepmill simulate --tolerance/--stop-at`) */
    if ((v = json_object_get(options, "tolerance")) &&
        (st = number_in(v, "options.tolerance", 0, 100, &spec->tolerance_mm, err)))
        return st;
    if ((v = json_object_get(options, "stop_at")) &&
        (st = integer_in(v, "options.stop_at", 1, 1e9, &spec->stop_at_line, err)))
        return st;
    /* the tool in the spindle before the first M6 (frepmill simulate and
     * check --initial-tool; 0: none): in the table, checked once the
     * tools are known */
    if ((v = json_object_get(options, "initial_tool")) &&
        (st = integer_in(v, "options.initial_tool", 0, 99999999, &spec->initial_tool, err)))
        return st;
    if ((v = json_object_get(options, "sweep_evaluations"))) {
        /* the swept volumes' search budget per point (frepmill simulate
         * --sweep-evaluations): a small one shows the budget warning */
        int n = 0;
        if ((st = integer_in(v, "options.sweep_evaluations", 1, 1e9, &n, err))) return st;
        spec->sweep_evaluations = (size_t)n;
    }
    return parse_check(doc, json_object_get(options, "check"), rules, err);
}

/* The initial tool (options.initial_tool, else the machine's) is one of
 * the table's: a refusal names the key and the table's numbers. */
static fm_status initial_tool_in_table(const fm_job_doc *doc, int from_options, fm_error *err)
{
    int n = doc->spec.initial_tool;
    if (n <= 0 || fm_tool_table_find(&doc->tools, n)) return FM_OK;
    char list[160] = "";
    for (size_t i = 0; i < doc->tools.count; i++) {
        size_t used = strlen(list);
        if (used > sizeof list - 16) {
            snprintf(list + used, sizeof list - used, ", ...");
            break;
        }
        snprintf(list + used, sizeof list - used, "%s%d", i ? ", " : "", doc->tools.tools[i].number);
    }
    return refuse(err, "bad_value", "%s %d: tool %d is not in the tool table (its tools: %s)",
                  from_options ? "options.initial_tool" : "machine.initial_tool", n, n, list);
}

/* {"file": PATH, "name": TEXT}: a fixture file (the CLI's --fixture). */
static fm_status fixture_file(fm_job_doc *doc, size_t i, json_t *f, const fm_job_doc_rules *rules,
                              fm_error *err)
{
    char where[64];
    snprintf(where, sizeof where, "fixtures[%zu]", i);
    static const char *const keys[] = {"file", "name", NULL};
    fm_status st = only_keys(f, keys, where, err);
    if (st != FM_OK) return st;
    json_t *file = json_object_get(f, "file"), *name = json_object_get(f, "name");
    char sub[96];
    snprintf(sub, sizeof sub, "%s.file", where);
    if ((st = text_ok(file, sub, DOC_STOCK_TEXT_MAX, err)) != FM_OK) return st;
    const char *path = json_string_value(file);
    if (!rules->allow_files)
        return refuse(err, "bad_fixture", "%s names a file on the server; give {\"hyperfun\": "
                                          "TEXT} or {\"stl_base64\": TEXT}", sub);
    if (!fm_path_has_extension(path, ".hf") && !fm_path_has_extension(path, ".stl"))
        return refuse(err, "bad_fixture", "fixture %.256s: give a .hf model or an .stl mesh", path);
    if (name) {
        snprintf(sub, sizeof sub, "%s.name", where);
        if ((st = text_ok(name, sub, DOC_NAME_MAX, err)) != FM_OK) return st;
        snprintf(doc->fixtures[i].name, sizeof doc->fixtures[i].name, "%s", json_string_value(name));
    }
    if (!(doc->fixture_paths[i] = dup_bytes(path, strlen(path))))
        return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    doc->check.fixtures[i] = doc->fixture_paths[i];
    return FM_OK;
}

static fm_status parse_fixtures(fm_job_doc *doc, json_t *fixtures, const fm_job_doc_rules *rules,
                                fm_error *err)
{
    if (!json_is_array(fixtures)) return refuse(err, "bad_type", "fixtures must be an array");
    if (json_array_size(fixtures) > FM_JOB_MAX_FIXTURES)
        return refuse(err, "too_large", "%zu fixtures; at most %d", json_array_size(fixtures),
                      FM_JOB_MAX_FIXTURES);
    size_t i;
    json_t *f;
    json_array_foreach(fixtures, i, f) {
        char where[64];
        snprintf(where, sizeof where, "fixtures[%zu]", i);
        fm_status st = json_is_object(f) && json_object_get(f, "file")
                           ? fixture_file(doc, i, f, rules, err)
                           : model_of(f, where, "bad_fixture", 1, &doc->fixtures[i], err);
        if (st != FM_OK) return st;
        doc->check.fixture_count = (int)i + 1;
    }
    return FM_OK;
}

/* ------------------------------------------------------------- public -- */

void fm_job_doc_free(fm_job_doc *doc)
{
    if (!doc) return;
    json_decref(doc->json);
    fm_tool_table_free(&doc->tools);
    free(doc->program);
    free(doc->program_file);
    free(doc->tools_path);
    free(doc->warnings);
    free(doc->stock_text);
    free(doc->subroutine_path);
    free(doc->stock_model.data);
    free(doc->design_text);
    free(doc->design_model.data);
    for (int i = 0; i < FM_JOB_MAX_FIXTURES; i++) {
        free(doc->fixtures[i].data);
        free(doc->fixture_paths[i]);
    }
    free(doc);
}

fm_status fm_job_doc_from_json(json_t *job, const fm_job_doc_rules *rules_in, fm_job_doc **out,
                               fm_error *err)
{
    static const fm_job_doc_rules strict = {0};
    const fm_job_doc_rules *rules = rules_in ? rules_in : &strict;
    *out = NULL;
    if (!json_is_object(job)) return refuse(err, "bad_job", "the job must be a JSON object");
    static const char *const keys[] = {"stock",   "voxel",   "tools",   "program", "fixtures",
                                       "machine", "design",  "options", NULL};
    fm_status st = only_keys(job, keys, "job", err);
    if (st != FM_OK) return st;
    static const char *const required[] = {"stock", "tools", "program"};
    json_t *from_program = json_object_get(json_object_get(job, "options"), "tools_from_program");
    if (from_program && !json_is_boolean(from_program))
        return refuse(err, "bad_type", "options.tools_from_program must be true or false");
    for (int i = 0; i < 3; i++)
        if (!json_object_get(job, required[i]) && !(i == 1 && json_is_true(from_program)))
            return refuse(err, "missing_key", "the job has no \"%s\"%s", required[i],
                          i == 1 ? " (nor options.tools_from_program)" : "");

    fm_job_doc *doc = calloc(1, sizeof *doc);
    if (!doc) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    fm_job_spec_default(&doc->spec);
    fm_job_check_default(&doc->check);
    doc->color_tool = 1;
    doc->spec.stock.voxel_mm = 0.1;
    json_t *v;
    if ((st = parse_stock(doc, json_object_get(job, "stock"), rules, err))) goto fail;
    if ((v = json_object_get(job, "voxel")) &&
        (st = number_in(v, "voxel", FM_JOB_DOC_VOXEL_MIN, 100, &doc->spec.stock.voxel_mm, err)))
        goto fail;
    json_t *tools = json_object_get(job, "tools");
    if (tools && (st = parse_tools(doc, tools, rules, err))) goto fail;
    if ((st = parse_program(doc, json_object_get(job, "program"), rules, err))) goto fail;
    if ((v = json_object_get(job, "fixtures")) && (st = parse_fixtures(doc, v, rules, err))) goto fail;
    if ((v = json_object_get(job, "machine")) && (st = parse_machine(doc, v, "machine", rules, err)))
        goto fail;
    if ((v = json_object_get(job, "design")) && (st = parse_design(doc, v, rules, err))) goto fail;
    json_t *options = json_object_get(job, "options");
    if ((st = parse_options(doc, options, rules, err))) goto fail;
    /* The machine's rapid rate times the whole job unless the options give
     * one: the rule of `frepmill check --machine` and `simulate --machine`. */
    if (doc->has_machine && doc->check.options.machine.rapid_rate > 0 &&
        !json_object_get(options, "rapid_rate"))
        doc->spec.rapid_rate = doc->check.options.machine.rapid_rate;
    /* Its reference points are Fanuc's G28/G30 (and where the tool starts);
     * its rotary axes move the tool, as with frepmill simulate --machine. */
    if (doc->has_machine) {
        memcpy(doc->spec.reference_points, doc->check.options.machine.reference_points,
               sizeof doc->spec.reference_points);
        doc->spec.machine = &doc->check.options.machine.chain;
        if (doc->dynamics.given) doc->spec.dynamics = &doc->dynamics;
    }

    /* The machine's state at the start: one decision for the interpreter
     * and the check (docs/check.md "Machine file"). */
    fm_job_spec_start_state(&doc->spec, doc->has_machine ? &doc->check.options.machine : NULL,
                            doc->spec.initial_tool);
    memcpy(doc->check.options.machine.start, doc->spec.start, sizeof doc->spec.start);

    /* An explicit table always wins over the program's comments. */
    if (tools && doc->tools_from_program)
        doc_warning(doc, "options.tools_from_program: a tool table is given, it wins; the "
                         "program's comments are not read");
    if (!tools && (st = tools_from_program(doc, err))) goto fail;

    if ((st = initial_tool_in_table(doc, json_object_get(options, "initial_tool") != NULL, err)))
        goto fail;

    /* The run spec's pointers into the document. */
    doc->spec.tools = &doc->tools;
    doc->spec.stock_spec = doc->stock_text; /* NULL for an inline model until it has a file */
    doc->spec.design_path = doc->design_text; /* the same for an inline design */
    doc->spec.check = doc->check_enabled ? &doc->check : NULL;

    /* The canonical form: every key present, defaults filled in; the
     * program and models exactly as given. */
    doc->json = json_object();
    json_t *fixtures = json_object_get(job, "fixtures");
    if (!doc->json ||
        json_object_set(doc->json, "stock", json_object_get(job, "stock")) ||
        json_object_set_new(doc->json, "voxel", json_real(doc->spec.stock.voxel_mm)) ||
        (tools && json_object_set(doc->json, "tools", tools)) ||
        json_object_set(doc->json, "program", json_object_get(job, "program")) ||
        json_object_set_new(doc->json, "fixtures", fixtures ? json_incref(fixtures) : json_array()) ||
        json_object_set_new(doc->json, "options", options ? json_incref(options) : json_object()) ||
        (json_object_get(job, "machine") &&
         json_object_set(doc->json, "machine", json_object_get(job, "machine"))) ||
        (json_object_get(job, "design") &&
         json_object_set(doc->json, "design", json_object_get(job, "design")))) {
        st = fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        goto fail;
    }
    *out = doc;
    return FM_OK;
fail:
    fm_job_doc_free(doc);
    return st;
}

fm_status fm_job_doc_parse(const char *text, size_t len, const fm_job_doc_rules *rules,
                           fm_job_doc **out, fm_error *err)
{
    *out = NULL;
    if (len > FM_JOB_DOC_MAX_TEXT * 2)
        return refuse(err, "too_large", "the job is %zu bytes; at most %zu", len,
                      FM_JOB_DOC_MAX_TEXT * 2);
    json_error_t jerr;
    /* JSON_REJECT_DUPLICATES: two "program" keys are a mistake, not a choice. */
    json_t *job = json_loadb(text, len, JSON_REJECT_DUPLICATES, &jerr);
    if (!job) {
        fm_status st = refuse(err, "bad_json", "the job is not valid JSON: %s", jerr.text);
        if (err) {
            err->line = jerr.line > 0 ? jerr.line : 0;
            err->column = jerr.column > 0 ? jerr.column : 0;
        }
        return st;
    }
    fm_status st = fm_job_doc_from_json(job, rules, out, err);
    json_decref(job);
    return st;
}

fm_status fm_job_doc_set_stock_file(fm_job_doc *doc, const char *path, fm_error *err)
{
    char *copy = dup_bytes(path, strlen(path));
    if (!copy) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    free(doc->stock_text);
    doc->stock_text = copy;
    doc->spec.stock_spec = copy;
    return FM_OK;
}

fm_status fm_job_doc_set_design_file(fm_job_doc *doc, const char *path, fm_error *err)
{
    char *copy = dup_bytes(path, strlen(path));
    if (!copy) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    free(doc->design_text);
    doc->design_text = copy;
    doc->spec.design_path = copy;
    return FM_OK;
}

fm_status fm_job_doc_set_fixture_file(fm_job_doc *doc, int i, const char *path, fm_error *err)
{
    if (i < 0 || i >= doc->check.fixture_count)
        return fm_error_set(err, FM_ERR_INTERNAL, "no fixture %d", i);
    char *copy = dup_bytes(path, strlen(path));
    if (!copy) return fm_error_set(err, FM_ERR_LIMIT, "out of memory");
    free(doc->fixture_paths[i]);
    doc->fixture_paths[i] = copy;
    doc->check.fixtures[i] = copy;
    return FM_OK;
}

fm_status fm_job_doc_check_memory(const fm_job_doc *doc, size_t budget, fm_error *err)
{
    if (!doc->stock_text) return FM_OK;
    fm_stock_spec shape;
    if (fm_stock_spec_parse(doc->stock_text, &shape, NULL) != FM_OK) return FM_OK;
    double area = fm_stock_spec_projected_area(&shape);
    if (!(area > 0) || !isfinite(area)) return FM_OK;
    size_t need = fm_stock_estimate_bytes(area, doc->spec.stock.voxel_mm,
                                          doc->spec.stock.band_voxels);
    if (need <= budget) return FM_OK;
    return fm_error_set_reason(err, FM_ERR_LIMIT, "memory_budget",
                               "the stock needs about %.0f MB at voxel %g mm; the budget per job "
                               "is %.0f MB; use a coarser voxel or a smaller stock",
                               (double)need / 1048576.0, doc->spec.stock.voxel_mm,
                               (double)budget / 1048576.0);
}

size_t fm_job_doc_program_bytes(const fm_job_doc *doc)
{
    return doc->program_length;
}

static fm_status plain_write(const char *dir, const char *name, const void *data, size_t size,
                             fm_error *err)
{
    char path[4096];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    size_t n = f ? fwrite(data, 1, size, f) : 0;
    int closed = f ? fclose(f) : EOF;
    if (!f || n != size || closed != 0)
        return fm_error_set(err, FM_ERR_IO, "cannot write %s: %s", path, strerror(errno));
    return FM_OK;
}

static fm_status materialize_one(const char *dir, const char *stem, const fm_job_model *m,
                                 fm_job_doc_writer write, char *path, size_t size, fm_error *err)
{
    char name[64];
    snprintf(name, sizeof name, "%s.%s", stem, m->is_stl ? "stl" : "hf");
    snprintf(path, size, "%s/%s", dir, name);
    struct stat st;
    if (stat(path, &st) == 0 && S_ISREG(st.st_mode) && (size_t)st.st_size == m->size) return FM_OK;
    return (write ? write : plain_write)(dir, name, m->data, m->size, err);
}

fm_status fm_job_doc_materialize(fm_job_doc *doc, const char *dir, fm_job_doc_writer write,
                                 fm_error *err)
{
    char path[4096];
    if (strlen(dir) > sizeof path - 64)
        return fm_error_set(err, FM_ERR_INPUT, "the folder %.64s... is too long", dir);
    fm_status st = FM_OK;
    if (doc->stock_model.size) {
        st = materialize_one(dir, "stock", &doc->stock_model, write, path, sizeof path, err);
        if (st == FM_OK) st = fm_job_doc_set_stock_file(doc, path, err);
    }
    if (st == FM_OK && doc->design_model.size) {
        st = materialize_one(dir, "design", &doc->design_model, write, path, sizeof path, err);
        if (st == FM_OK) st = fm_job_doc_set_design_file(doc, path, err);
    }
    for (int i = 0; st == FM_OK && i < doc->check.fixture_count; i++) {
        if (!doc->fixtures[i].size) continue; /* a file already */
        char stem[32];
        snprintf(stem, sizeof stem, "fixture%d", i);
        st = materialize_one(dir, stem, &doc->fixtures[i], write, path, sizeof path, err);
        if (st == FM_OK) st = fm_job_doc_set_fixture_file(doc, i, path, err);
    }
    return st;
}
