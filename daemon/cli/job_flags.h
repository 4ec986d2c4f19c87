/* job_flags.h: the CLI's job flags turned into a job document
 * (daemon/runner/job_doc.h), so that `frepmill simulate`, `frepmill check`
 * and every other entrance reach the one parser and validator: a command
 * lists its flags and the document key each sets; the values' syntax
 * (a number, an integer) is read here, their ranges and defaults are the
 * document's. */
#ifndef FM_JOB_FLAGS_H
#define FM_JOB_FLAGS_H

#include <jansson.h>

#include "runner/job_doc.h"

typedef enum fm_job_flag_kind {
    FM_JOB_FLAG_TEXT = 1, /* a string: a spec, a file, a name */
    FM_JOB_FLAG_NUMBER,   /* a finite number */
    FM_JOB_FLAG_INTEGER,  /* a whole number */
    FM_JOB_FLAG_SWITCH,   /* no value: true */
    FM_JOB_FLAG_FIXTURE   /* a file appended to "fixtures" as {"file": FILE} */
} fm_job_flag_kind;

typedef struct fm_job_flag {
    const char *flag; /* "--voxel"; "PROGRAM" for the one positional argument */
    const char *key;  /* the document's key, dotted: "options.check.voxel" */
    fm_job_flag_kind kind;
} fm_job_flag;

#define FM_JOB_FLAGS_MAX 128

typedef struct fm_job_flags {
    const char *command;       /* "frepmill simulate", for messages */
    const fm_job_flag *table;  /* ends with {NULL} */
    int count;                 /* flags given, in order */
    const fm_job_flag *given[FM_JOB_FLAGS_MAX];
    const char *value[FM_JOB_FLAGS_MAX];
} fm_job_flags;

/* Take argv[*i] when it is one of the table's flags (or the positional
 * PROGRAM), with its value (*i moves past it): 1 taken, 0 not a job flag,
 * -1 refused (a missing or malformed value, a second PROGRAM: printed). */
int fm_job_flags_take(fm_job_flags *f, int argc, char **argv, int *i);

/* The value given for flag, or NULL. */
const char *fm_job_flags_value(const fm_job_flags *f, const char *flag);

/* The document: base (a skeleton of the command's defaults, or a job
 * file's document; a reference is taken) with every flag given set in it,
 * parsed and validated by fm_job_doc_from_json under the CLI's rules
 * (files allowed). A refusal of a flag's value names the flag. On error
 * prints and returns the exit status (2 bad input, 3 limit, 4 I/O); 0 and
 * *out on success. */
int fm_job_flags_document(const fm_job_flags *f, json_t *base, fm_job_doc **out);

/* The exit status of a status: 0, 2 input, 3 limit, 4 I/O, 5 otherwise. */
int fm_job_flags_exit_status(fm_status st);

#endif
