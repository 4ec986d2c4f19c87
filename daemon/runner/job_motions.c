/* job_motions.c: the motions a job's program made, kept so that the
 * program is interpreted once per job (job.h, fm_job_motions): in memory
 * up to a budget, the rest spilled to a file (the job's own when the spec
 * names one, else an anonymous temporary file), replayed in order. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "job_internal.h"

#define LOG_MAGIC "FMMOTN01"

struct fm_job_motions {
    fm_motion *memory;
    size_t count, cap, memory_max; /* motions in memory; the most kept there */
    FILE *file;                    /* motions after the first memory_max, or all of them */
    long spilled;
    long data_offset;              /* where the motions start in file */
    int usable;                    /* 0 once a motion cannot be kept (a PARAM path) */
    fm_status status;              /* the first write failure */
};

fm_job_motions *job_motions_new(size_t memory_bytes, FILE *file)
{
    fm_job_motions *log = calloc(1, sizeof *log);
    if (!log) return NULL;
    log->memory_max = memory_bytes / sizeof(fm_motion);
    log->file = file;
    log->usable = 1;
    return log;
}

void fm_job_motions_free(fm_job_motions *log)
{
    if (!log) return;
    free(log->memory);
    if (log->file) fclose(log->file);
    free(log);
}

long fm_job_motions_count(const fm_job_motions *log)
{
    return log ? (long)log->count + log->spilled : 0;
}

int job_motions_usable(const fm_job_motions *log)
{
    return log && log->usable && log->status == FM_OK;
}

void job_motions_add(fm_job_motions *log, const fm_motion *m)
{
    if (!log || !log->usable) return;
    if (m->kind == FM_MOTION_PARAM) {
        /* its path lives only while the front end runs: interpret again */
        log->usable = 0;
        return;
    }
    fm_motion copy = *m;
    copy.machine = NULL; /* the spec's: set again on replay */
    if (log->count < log->memory_max) {
        if (log->count == log->cap) {
            size_t cap = log->cap ? 2 * log->cap : 1024;
            if (cap > log->memory_max) cap = log->memory_max;
            fm_motion *p = realloc(log->memory, cap * sizeof *p);
            if (!p) {
                log->usable = 0;
                return;
            }
            log->memory = p;
            log->cap = cap;
        }
        log->memory[log->count++] = copy;
        return;
    }
    if (!log->file && !(log->file = tmpfile())) {
        log->usable = 0;
        return;
    }
    if (fwrite(&copy, sizeof copy, 1, log->file) != 1) {
        log->usable = 0;
        return;
    }
    log->spilled++;
}

void job_motions_spoil(fm_job_motions *log)
{
    if (log) log->usable = 0;
}

fm_status fm_job_motions_replay(fm_job_motions *log, const fm_machine *machine,
                                fm_motion_sink sink, void *user, fm_error *err)
{
    if (!job_motions_usable(log))
        return fm_error_set(err, FM_ERR_INTERNAL, "the program's motions were not kept");
    for (size_t i = 0; i < log->count; i++) {
        fm_motion m = log->memory[i];
        m.machine = machine;
        if (sink(user, &m)) return FM_OK;
    }
    if (!log->spilled) return FM_OK;
    if (fflush(log->file) != 0 || fseek(log->file, log->data_offset, SEEK_SET))
        return fm_error_set(err, FM_ERR_IO, "cannot read the spilled motions back");
    fm_motion m;
    for (long i = 0; i < log->spilled; i++) {
        if (fread(&m, sizeof m, 1, log->file) != 1)
            return fm_error_set(err, FM_ERR_IO, "cannot read the spilled motions back");
        m.machine = machine;
        m.path = NULL;
        if (sink(user, &m)) break;
    }
    /* later writes go to the end again */
    fseek(log->file, 0, SEEK_END);
    return FM_OK;
}

fm_job_motions *job_motions_open_log(const char *path, fm_error *err)
{
    /* the job's own file: every motion goes there, after a magic header
     * that says which build wrote it (its fm_motion's size); written as
     * PATH.part and renamed once whole (job_motions_keep), so that a reader
     * finds all of a program's motions or none */
    char part[4096];
    if (snprintf(part, sizeof part, "%s.part", path) >= (int)sizeof part) {
        fm_error_set(err, FM_ERR_INPUT, "the motion log's path is too long");
        return NULL;
    }
    FILE *f = fopen(part, "w+b");
    if (!f) {
        fm_error_set(err, FM_ERR_IO, "cannot write the motion log %s", path);
        return NULL;
    }
    unsigned size = (unsigned)sizeof(fm_motion);
    if (fwrite(LOG_MAGIC, strlen(LOG_MAGIC), 1, f) != 1 || fwrite(&size, sizeof size, 1, f) != 1) {
        fclose(f);
        fm_error_set(err, FM_ERR_IO, "cannot write the motion log %s", path);
        return NULL;
    }
    fm_job_motions *log = job_motions_new(0, f);
    if (!log) {
        fclose(f);
        fm_error_set(err, FM_ERR_LIMIT, "out of memory");
        return NULL;
    }
    log->data_offset = ftell(f);
    return log;
}

fm_status job_motions_keep(fm_job_motions *log, const char *path, int keep)
{
    char part[4096];
    snprintf(part, sizeof part, "%s.part", path);
    if (!keep || !job_motions_usable(log) || fflush(log->file) != 0) {
        remove(part);
        remove(path); /* an earlier run's: not this program's motions */
        return FM_OK;
    }
    return rename(part, path) == 0 ? FM_OK : FM_ERR_IO;
}

fm_status fm_job_motions_replay_file(const char *path, const fm_machine *machine,
                                     fm_motion_sink sink, void *user, fm_error *err)
{
    FILE *f = fopen(path, "rb");
    if (!f) return fm_error_set(err, FM_ERR_IO, "no motion log %s", path);
    char magic[sizeof LOG_MAGIC];
    unsigned size = 0;
    fm_status st = FM_OK;
    if (fread(magic, strlen(LOG_MAGIC), 1, f) != 1 || memcmp(magic, LOG_MAGIC, strlen(LOG_MAGIC)) ||
        fread(&size, sizeof size, 1, f) != 1 || size != sizeof(fm_motion))
        st = fm_error_set(err, FM_ERR_INPUT, "%s is not a motion log of this build", path);
    fm_motion m;
    while (st == FM_OK && fread(&m, sizeof m, 1, f) == 1) {
        m.machine = machine;
        m.path = NULL;
        if (sink(user, &m)) break;
    }
    if (st == FM_OK && ferror(f)) st = fm_error_set(err, FM_ERR_IO, "cannot read %s", path);
    fclose(f);
    return st;
}
