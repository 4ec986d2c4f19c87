/* job_flags.c: the CLI's job flags into a job document (job_flags.h). */
#include "job_flags.h"

#include <errno.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

int fm_job_flags_exit_status(fm_status st)
{
    switch (st) {
    case FM_OK: return 0;
    case FM_ERR_LIMIT: return 3;
    case FM_ERR_IO: return 4;
    case FM_ERR_INPUT: return 2;
    default: return 5;
    }
}

static int parse_number(const char *s, double *out)
{
    char *end;
    errno = 0;
    *out = strtod(s, &end);
    return end != s && *end == '\0' && errno != ERANGE && isfinite(*out);
}

static const fm_job_flag *find(const fm_job_flags *f, const char *flag)
{
    for (const fm_job_flag *t = f->table; t->flag; t++)
        if (!strcmp(t->flag, flag)) return t;
    return NULL;
}

const char *fm_job_flags_value(const fm_job_flags *f, const char *flag)
{
    for (int i = f->count - 1; i >= 0; i--)
        if (!strcmp(f->given[i]->flag, flag)) return f->value[i];
    return NULL;
}

int fm_job_flags_take(fm_job_flags *f, int argc, char **argv, int *i)
{
    const char *a = argv[*i];
    const int positional = a[0] != '-' || !a[1];
    const fm_job_flag *flag = find(f, positional ? "PROGRAM" : a);
    if (!flag) return 0;
    if (f->count == FM_JOB_FLAGS_MAX) {
        fprintf(stderr, "%s: more than %d job flags\n", f->command, FM_JOB_FLAGS_MAX);
        return -1;
    }
    const char *v = "true";
    if (positional) {
        const char *before = fm_job_flags_value(f, "PROGRAM");
        if (before) {
            fprintf(stderr, "%s: more than one program given ('%s' and '%s')\n", f->command,
                    before, a);
            return -1;
        }
        v = a;
    } else if (flag->kind != FM_JOB_FLAG_SWITCH) {
        if (*i + 1 >= argc) {
            fprintf(stderr, "%s: %s needs a value\n", f->command, a);
            return -1;
        }
        v = argv[++*i];
        double d;
        if ((flag->kind == FM_JOB_FLAG_NUMBER || flag->kind == FM_JOB_FLAG_INTEGER) &&
            !parse_number(v, &d)) {
            fprintf(stderr, "%s: %s %s: not a valid value\n", f->command, a, v);
            return -1;
        }
    }
    f->given[f->count] = flag;
    f->value[f->count++] = v;
    return 1;
}

/* Set value at the dotted key of doc, making the objects on the way. */
static int set_key(json_t *doc, const char *key, json_t *value)
{
    char part[64];
    json_t *at = doc;
    for (;;) {
        const char *dot = strchr(key, '.');
        if (!dot) return json_object_set_new(at, key, value);
        size_t n = (size_t)(dot - key);
        if (n >= sizeof part) {
            json_decref(value);
            return -1;
        }
        memcpy(part, key, n);
        part[n] = '\0';
        json_t *next = json_object_get(at, part);
        if (!json_is_object(next)) {
            next = json_object();
            if (json_object_set_new(at, part, next)) {
                json_decref(value);
                return -1;
            }
        }
        at = next;
        key = dot + 1;
    }
}

static json_t *value_json(const fm_job_flag *flag, const char *v)
{
    double d = 0;
    switch (flag->kind) {
    case FM_JOB_FLAG_NUMBER:
        parse_number(v, &d);
        return json_real(d);
    case FM_JOB_FLAG_INTEGER:
        /* a whole number as a JSON integer; else a real the document refuses */
        parse_number(v, &d);
        return d == floor(d) && fabs(d) < 9e15 ? json_integer((json_int_t)d) : json_real(d);
    case FM_JOB_FLAG_SWITCH: return json_true();
    case FM_JOB_FLAG_FIXTURE: return json_pack("{s:s}", "file", v);
    default: return json_string(v);
    }
}

/* The flag whose key a refusal names (its message starts with the key). */
static int refused_flag(const fm_job_flags *f, const char *message)
{
    for (int i = f->count - 1; i >= 0; i--) {
        const fm_job_flag *g = f->given[i];
        size_t n = strlen(g->key);
        if (!strncmp(message, g->key, n) && strchr(" :=", message[n])) return i;
    }
    return -1;
}

int fm_job_flags_document(const fm_job_flags *f, json_t *base, fm_job_doc **out)
{
    *out = NULL;
    int failed = !base;
    for (int i = 0; i < f->count && !failed; i++) {
        const fm_job_flag *g = f->given[i];
        json_t *v = value_json(g, f->value[i]);
        if (!strcmp(g->key, "program.file")) {
            failed = !v || json_object_set_new(base, "program", json_pack("{s:o}", "file", v));
        } else if (g->kind == FM_JOB_FLAG_FIXTURE) {
            json_t *list = json_object_get(base, "fixtures");
            if (!json_is_array(list)) json_object_set_new(base, "fixtures", list = json_array());
            failed = !v || json_array_append_new(list, v);
        } else {
            failed = !v || set_key(base, g->key, v);
        }
    }
    if (failed) {
        json_decref(base);
        fprintf(stderr, "%s: out of memory\n", f->command);
        return 3;
    }
    /* the CLI's documents may name files on this machine; live programs
     * are the daemon's */
    const fm_job_doc_rules rules = {.allow_files = 1};
    fm_error err;
    fm_error_clear(&err);
    fm_status st = fm_job_doc_from_json(base, &rules, out, &err);
    json_decref(base);
    if (st == FM_OK) {
        /* the tool table's warnings: a bounding solid, a guessed field */
        for (const char *w = (*out)->warnings; w && *w;) {
            const char *e = strchr(w, '\n');
            int n = e ? (int)(e - w) : (int)strlen(w);
            fprintf(stderr, "%s: warning: %.*s\n", f->command, n, w);
            w = e ? e + 1 : w + n;
        }
        return 0;
    }
    char buf[1024];
    int i = refused_flag(f, err.message);
    const int number = i >= 0 && (f->given[i]->kind == FM_JOB_FLAG_NUMBER ||
                                  f->given[i]->kind == FM_JOB_FLAG_INTEGER);
    if (number)
        fprintf(stderr, "%s: %s %s: not a valid value (%s)\n", f->command, f->given[i]->flag,
                f->value[i], err.message);
    else if (i >= 0)
        fprintf(stderr, "%s: %s %s: %s\n", f->command, f->given[i]->flag, f->value[i],
                err.message);
    else
        fprintf(stderr, "%s: %s\n", f->command, fm_error_format(&err, buf, sizeof buf));
    return fm_job_flags_exit_status(st);
}
