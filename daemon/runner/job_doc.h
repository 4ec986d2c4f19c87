/* job_doc.h: the job document. A job is one JSON object; this file and
 * job_doc.c are where it is defined, parsed and validated, once, into the
 * run spec the job runner takes (fm_job_spec, job.h). The daemon's HTTP API
 * (POST /v1/jobs, POST /v1/check), its job store (spec.json), Modbus live
 * mode, the Redis queue, `frepmill simulate --job FILE` and the flags of
 * `frepmill simulate` and `frepmill check` (daemon/cli/job_flags.c turns
 * them into a document) read jobs through here: every range and default
 * of a job is here.
 *
 *   {
 *     "stock":   "box:X0,Y0,Z0,X1,Y1,Z1" | "cylinder:X,Y,Z0,Z1,R"      (mm)
 *                | {"hyperfun": TEXT} | {"stl_base64": BASE64}         (inline models)
 *                | "FILE.hf" | "FILE.stl" | "FILE.vdb"                 (files: CLI only)
 *     "voxel":   MM                                  (default 0.1; 0.0001..100)
 *     "tools":   {...}                               (a tool table in any JSON format
 *                                                    docs/tooltable.md reads; a file with the
 *                                                    CLI's rules; absent with
 *                                                    options.tools_from_program)
 *                | "FILE"                            (a JSON or .tbl file: CLI only)
 *     "program": {"gcode": TEXT} | {"trajectory": {...}}               (docs/trajectory.md)
 *                | {"file": FILE}                    (G-code, or a .json trajectory: CLI only)
 *                | {"live": {"feed": MM_PER_MIN}}    (positions from a controller; the daemon
 *                                                     makes these, POST /v1/jobs refuses them)
 *     "fixtures": [{"hyperfun": TEXT | "stl_base64": BASE64 | "file": FILE, "name": TEXT}, ...]
 *                                                    (at most 64; files .hf or .stl: CLI only)
 *     "machine": {"limits": {"x": [LO, HI], ...}, "rapid_rate": MM_PER_MIN,
 *                 "start": [X, Y, Z], "initial_tool": N,
 *                 "reference_points": [[X, Y, Z], ...]}
 *                | "FILE.json"                       (the machine file: CLI only)
 *                                                    (docs/check.md's machine file)
 *     "design":  {"hyperfun": TEXT} | {"stl_base64": BASE64}         (the intended part:
 *                | "FILE.stl" | "FILE.hf" | "FILE.vdb"  the report's "design" compares the
 *                                                     stock with it; files: CLI only)
 *     "options": {
 *       "name": TEXT, "band": 2..32, "batch": -1..1000, "rapid_rate": MM_PER_MIN,
 *       "memory_budget_mb": MB, "threads": 0..1024, "color": "tool" | "none",
 *       "dialect": "linuxcnc" | "fanuc"              (docs/gcode.md; default: the server's,
 *                                                     else linuxcnc)
 *       "subroutine_path": "DIR:DIR"                 (subprogram folders: files, CLI only;
 *                                                     the daemon's own setting otherwise)
 *       "calculator_input": false | true             (Fanuc: X5 is 5 mm, not 0.005)
 *       "tolerance": MM                              (design: deviations up to it count as on
 *                                                     the design; 0..100, default half a voxel)
 *       "stop_at": LINE                              (stop after this source line's motions)
 *       "initial_tool": N                            (the tool in the spindle before the first
 *                                                     M6; 0..99999999, a tool of the table;
 *                                                     default the machine's initial_tool, else
 *                                                     none: a one-tool table's tool cuts)
 *       "check": false | {"clearance", "rapid_clearance", "tolerance", "max_ramp", "voxel",
 *                         "machine": {...}  (the same as the top-level "machine")}
 *     }
 *   }
 *
 * Unknown keys anywhere are refused (a typo must not be silently ignored).
 * The rapid rate of the run is options.rapid_rate, else the machine's, else
 * 5000 mm/min: the same rule for the CLI, the check and the daemon, so one
 * program and machine give one set of findings.
 *
 * The machine's reference_points are the run's (Fanuc G28/G30).
 *
 * The machine's state at the start (fm_job_spec_start_state): the tool tip
 * stands at the machine's start, else at the dialect's power-on place
 * (LinuxCNC the origin, Fanuc the first reference point), for the
 * interpreter and the check alike; the spindle holds options.initial_tool,
 * else the machine's initial_tool, else nothing.
 *
 * "design", "options.tolerance" and "options.stop_at" are `frepmill simulate
 * --design/--tolerance/--stop-at` (fm_job_spec.design_path, tolerance_mm,
 * stop_at_line). */
#ifndef FM_JOB_DOC_H
#define FM_JOB_DOC_H

#include <jansson.h>
#include <stddef.h>

#include "core/core.h"
#include "job.h"

/* The finest voxel a job may ask for (mm): lib/stock's own bound; the
 * memory budget refuses what is too fine for the stock's size. */
#define FM_JOB_DOC_VOXEL_MIN 1e-4

/* The largest text (program, tool table, model) inside a job, bytes. */
#define FM_JOB_DOC_MAX_TEXT ((size_t)256 << 20)

typedef struct fm_job_doc_rules {
    /* Stocks and tools that name files on this machine are refused unless
     * set: a network client must never make the daemon read its files. */
    int allow_files;
    /* Live programs are made by the daemon itself (Modbus live mode). */
    int allow_live;
    /* The server's defaults for jobs that give none (frepmilld's dialect
     * and subroutine_path settings); NULL: none. */
    const char *dialect;
    const char *subroutine_path;
} fm_job_doc_rules;

/* An inline model of the document (the stock or a fixture). */
typedef struct fm_job_model {
    int is_stl;        /* 1: STL bytes (decoded base64); 0: HyperFun text */
    char *data;        /* owned */
    size_t size;
    char name[129];
} fm_job_model;

typedef struct fm_job_doc {
    /* The run spec; its pointers point into this document. Inline models
     * must be written to files (fm_job_doc_materialize) before it runs. */
    fm_job_spec spec;
    /* The canonical JSON: every key present, defaults filled in. The store
     * writes it and reads it back through fm_job_doc_parse. */
    json_t *json;
    char name[129];
    double memory_budget_mb;   /* options.memory_budget_mb, 0 if absent */
    int threads_given;         /* options.threads was given */
    int color_tool;            /* options.color: 1 "tool" (default), 0 "none" */
    double live_feed;          /* program.live.feed, mm/min */
    /* The check's options, machine and fixtures; spec.check points here
     * unless options.check is false. */
    fm_job_check check;
    int check_enabled;
    int has_machine;           /* "machine" (or options.check.machine) was given */
    fm_plan_machine dynamics;  /* its "dynamics" (docs/plan.md); given = 0 without */
    /* Owned storage behind spec. */
    fm_tool_table tools;
    char *program;             /* G-code text or the trajectory's JSON */
    char *program_file;        /* program.file (files rules only) */
    char *tools_path;          /* "tools" given as a file (files rules only) */
    int tools_from_program;    /* options.tools_from_program: the program's comments are the
                                  tools when "tools" is absent */
    char *warnings;            /* what the tool table's reader warns of (a bounding solid, a
                                  guessed field, a skipped entry), one a line; NULL: none */
    size_t program_length;
    char *stock_text;          /* the spec string, or the materialized model's path */
    char dialect[16];          /* spec.dialect's storage */
    char *subroutine_path;     /* spec.subroutine_path's */
    fm_job_model stock_model;  /* an inline stock model (size 0 if none) */
    char *design_text;         /* the design's file (given, or the materialized model's) */
    fm_job_model design_model; /* an inline design model (size 0 if none) */
    fm_job_model fixtures[FM_JOB_MAX_FIXTURES];
    char *fixture_paths[FM_JOB_MAX_FIXTURES];
} fm_job_doc;

/* Parse and validate text (len bytes) into *out (free with
 * fm_job_doc_free). On error *out is NULL and err has FM_ERR_INPUT (or
 * FM_ERR_LIMIT for sizes), the reason ("bad_json", "missing_key",
 * "unknown_key", "bad_type", "bad_value", "bad_stock", "bad_program",
 * "bad_fixture", "bad_tools", "bad_design", "too_large") and, for JSON syntax errors, the
 * line and column in text. rules may be NULL (the strict network rules). */
fm_status fm_job_doc_parse(const char *text, size_t len, const fm_job_doc_rules *rules,
                           fm_job_doc **out, fm_error *err);
/* The same from a JSON value (a reference is not taken). */
fm_status fm_job_doc_from_json(json_t *value, const fm_job_doc_rules *rules, fm_job_doc **out,
                               fm_error *err);
void fm_job_doc_free(fm_job_doc *doc);

/* lib/stock and lib/check read models from files: once the owner of the
 * document (the daemon's job store) has written an inline model to a file,
 * it points the spec at it. */
fm_status fm_job_doc_set_stock_file(fm_job_doc *doc, const char *path, fm_error *err);
fm_status fm_job_doc_set_fixture_file(fm_job_doc *doc, int i, const char *path, fm_error *err);
fm_status fm_job_doc_set_design_file(fm_job_doc *doc, const char *path, fm_error *err);

/* Write one file durably or not: the shape of the daemon's crash-safe
 * writer (fm_store_write_atomic). */
typedef fm_status (*fm_job_doc_writer)(const char *dir, const char *name, const void *data,
                                       size_t size, fm_error *err);

/* The one place a document's inline models become files: the stock, the
 * design and each fixture are written to dir as stock.EXT, design.EXT and
 * fixtureN.EXT (EXT: stl or hf) with write (NULL: a plain write), and the
 * run spec is pointed at them. A file of the model's size already there is
 * kept (a document read back at start finds its models where it left
 * them). The CLI (--job) and the daemon's job store both call it. */
fm_status fm_job_doc_materialize(fm_job_doc *doc, const char *dir, fm_job_doc_writer write,
                                 fm_error *err);

/* Would the stock's grid exceed budget bytes? Known before anything is
 * built for box and cylinder stocks only (others pass and meet the budget
 * when built). FM_ERR_LIMIT, reason "memory_budget", when over. */
fm_status fm_job_doc_check_memory(const fm_job_doc *doc, size_t budget, fm_error *err);

/* The bytes of the program (G-code text or trajectory JSON). */
size_t fm_job_doc_program_bytes(const fm_job_doc *doc);

/* Decode standard base64 (padding optional, no whitespace but line breaks)
 * into a malloc'd buffer. 0 on success, -1 for invalid text. */
int fm_base64_decode(const char *in, size_t len, uint8_t **out, size_t *out_len);

#endif
