/* toolpath.c: the motion stream as tool tip points with a record per
 * motion (toolpath.h), and what is drawn from it: picture polylines and
 * the viewer's toolpath document. */
#include "toolpath.h"

#include <stdarg.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "sweep/sweep.h"

/* A point every 5 degrees of arc or of any rotary joint at most. */
#define TP_ARC_STEP (FM_PI / 36)
#define TP_PARAM_PIECES 32
#define TP_MAX_PIECES 100000

typedef struct tp_motion {
    int kind; /* 0 rapid, 1 line, 2 arc, 3 parametric, 4 dwell */
    int line, tool;
    double t0, t1;
    size_t first, count;
    int rotary; /* the joints below are the motion's (a machine with rotary axes) */
    double joints0[3], joints1[3];
} tp_motion;

typedef struct tp_line {
    size_t first, count;
    int rapid;
} tp_line;

struct fm_toolpath {
    double *points;
    size_t count, capacity, max_points;
    tp_motion *motions;
    size_t motion_count, motion_capacity;
    tp_line *lines;
    size_t line_count, line_capacity;
    int truncated;
};

fm_toolpath *fm_toolpath_new(size_t max_points)
{
    fm_toolpath *p = calloc(1, sizeof *p);
    if (p) p->max_points = max_points ? max_points : 4000000;
    return p;
}

void fm_toolpath_free(fm_toolpath *path)
{
    if (!path) return;
    free(path->points);
    free(path->motions);
    free(path->lines);
    free(path);
}

int fm_toolpath_truncated(const fm_toolpath *path)
{
    return path && path->truncated;
}

static int grow(void **array, size_t *capacity, size_t need, size_t item, size_t first)
{
    if (need <= *capacity) return 1;
    size_t cap = *capacity ? *capacity : first;
    while (cap < need) cap *= 2;
    void *t = realloc(*array, cap * item);
    if (!t) return 0;
    *array = t;
    *capacity = cap;
    return 1;
}

/* The picture's polylines follow the motions: a motion continues the last
 * polyline when it is of the same kind (rapid or not) and starts at its
 * last point, a dwell when it stands there; the points of a continued
 * polyline are contiguous (the repeated start point draws nothing). */
static int extend_lines(fm_toolpath *p, const tp_motion *m)
{
    const double *start = p->points + 3 * m->first;
    tp_line *last = p->line_count ? &p->lines[p->line_count - 1] : NULL;
    int joined = last && last->first + last->count == m->first &&
                 !memcmp(p->points + 3 * (m->first - 1), start, 3 * sizeof *start);
    if (m->kind == 4) {
        if (joined) last->count += m->count;
        return 1;
    }
    if (joined && last->rapid == (m->kind == 0)) {
        last->count += m->count;
        return 1;
    }
    if (!grow((void **)&p->lines, &p->line_capacity, p->line_count + 1, sizeof *p->lines, 256))
        return 0;
    p->lines[p->line_count++] = (tp_line){m->first, m->count, m->kind == 0};
    return 1;
}

void fm_toolpath_add(fm_toolpath *path, const fm_motion *m)
{
    if (!path || path->truncated) return;
    if (path->count > path->max_points) {
        path->truncated = 1;
        return;
    }
    tp_motion r;
    memset(&r, 0, sizeof r);
    r.kind = m->kind == FM_MOTION_RAPID ? 0
             : m->kind == FM_MOTION_LINE ? 1
             : m->kind == FM_MOTION_ARC  ? 2
             : m->kind == FM_MOTION_PARAM ? 3
                                          : 4;
    r.line = m->line;
    r.tool = m->tool;
    r.t0 = m->t0;
    r.t1 = m->t1;
    r.first = path->count;
    int pieces = 0;
    if (r.kind != 4) {
        pieces = fm_motion_pieces(m, TP_ARC_STEP, TP_PARAM_PIECES, TP_MAX_PIECES);
        if (r.kind == 2 && pieces < 2) pieces = 2;
        if (pieces < 1) pieces = 1;
    }
    r.count = (size_t)pieces + 1;
    if (m->machine && m->machine->rotary_count) {
        r.rotary = 1;
        memcpy(r.joints0, m->rotary_start, sizeof r.joints0);
        memcpy(r.joints1, m->rotary_end, sizeof r.joints1);
    }
    if (!grow((void **)&path->points, &path->capacity, path->count + r.count, 3 * sizeof *path->points,
              1024) ||
        !grow((void **)&path->motions, &path->motion_capacity, path->motion_count + 1,
              sizeof *path->motions, 256)) {
        path->truncated = 1;
        return;
    }
    double axis[3];
    for (int i = 0; i <= pieces; i++)
        fm_motion_pose_at(m, pieces ? (double)i / pieces : 0, path->points + 3 * (path->count + (size_t)i),
                          axis);
    path->count += r.count;
    path->motions[path->motion_count++] = r;
    if (!extend_lines(path, &r)) path->truncated = 1;
}

fm_status fm_toolpath_polylines(const fm_toolpath *path, fm_render_polyline **out, size_t *count,
                                fm_error *err)
{
    *out = NULL;
    *count = 0;
    if (!path || !path->line_count) return FM_OK;
    fm_render_polyline *lines = calloc(path->line_count, sizeof *lines);
    if (!lines) return fm_error_set(err, FM_ERR_LIMIT, "out of memory for the toolpath overlay");
    for (size_t i = 0; i < path->line_count; i++) {
        lines[i].points = path->points + 3 * path->lines[i].first;
        lines[i].count = path->lines[i].count;
        lines[i].rapid = path->lines[i].rapid;
    }
    *out = lines;
    *count = path->line_count;
    return FM_OK;
}

/* ------------------------------------------------------------ document -- */

typedef struct tp_text {
    char *text;
    size_t len, cap;
    int failed;
} tp_text;

static void tp_printf(tp_text *b, const char *fmt, ...)
#if defined(__GNUC__)
    __attribute__((format(printf, 2, 3)))
#endif
    ;
static void tp_printf(tp_text *b, const char *fmt, ...)
{
    if (b->failed) return;
    for (;;) {
        va_list ap;
        va_start(ap, fmt);
        /* NULL + 0 is undefined in C (clang's UBSan stops there): the
         * first call, before any allocation, only measures. */
        int n = vsnprintf(b->text ? b->text + b->len : NULL, b->cap - b->len, fmt, ap);
        va_end(ap);
        if (n < 0) {
            b->failed = 1;
            return;
        }
        if ((size_t)n < b->cap - b->len) {
            b->len += (size_t)n;
            return;
        }
        size_t cap = b->cap * 2 + (size_t)n + 1;
        char *t = realloc(b->text, cap);
        if (!t) {
            b->failed = 1;
            return;
        }
        b->text = t;
        b->cap = cap;
    }
}

char *fm_toolpath_json_members(const fm_toolpath *path, const fm_machine *machine, size_t *len)
{
    tp_text b = {0};
    int tables = 0;
    for (int i = 0; machine && i < machine->rotary_count; i++) {
        const fm_rotary_axis *ax = &machine->rotary[i];
        if (ax->carries != FM_ROTARY_TABLE) continue;
        tp_printf(&b, "%s{\"axis\":\"%c\",\"around\":[%.9g,%.9g,%.9g],\"through\":[%.9g,%.9g,%.9g]}",
                  tables++ ? "," : "\"machine\":{\"table\":[", 'a' + ax->letter, ax->around[0],
                  ax->around[1], ax->around[2], ax->through[0], ax->through[1], ax->through[2]);
    }
    if (tables) tp_printf(&b, "]},");
    tp_printf(&b, "\"motions\":[");
    for (size_t i = 0; i < path->motion_count; i++) {
        const tp_motion *m = &path->motions[i];
        tp_printf(&b, "%s[%d,%d,%.4f,%.4f,%d,%zu,%zu", i ? "," : "", m->kind, m->line, m->t0, m->t1,
                  m->tool, m->first, m->count);
        if (m->rotary)
            tp_printf(&b, ",%.6f,%.6f,%.6f,%.6f,%.6f,%.6f", m->joints0[0], m->joints0[1],
                      m->joints0[2], m->joints1[0], m->joints1[1], m->joints1[2]);
        tp_printf(&b, "]");
    }
    tp_printf(&b, "],\"points\":[");
    for (size_t i = 0; i < path->count; i++) {
        const double *p = path->points + 3 * i;
        tp_printf(&b, "%s%.3f,%.3f,%.3f", i ? "," : "", p[0], p[1], p[2]);
    }
    tp_printf(&b, "]");
    if (tables) {
        /* The joints move linearly in time within a motion, and its points
         * are at equal steps of time: point k of n + 1 has the joints at
         * k / n of the way (motion.h). */
        tp_printf(&b, ",\"placements\":[");
        for (size_t i = 0; i < path->motion_count; i++) {
            const tp_motion *m = &path->motions[i];
            for (size_t k = 0; k < m->count; k++) {
                double u = m->count > 1 ? (double)k / (double)(m->count - 1) : 0;
                double joints[3] = {0, 0, 0}, rot[9], trans[3];
                if (m->rotary)
                    for (int a = 0; a < 3; a++)
                        joints[a] = m->joints0[a] + (m->joints1[a] - m->joints0[a]) * u;
                fm_machine_table_transform(machine, joints, -1, rot, trans);
                tp_printf(&b, "%s%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g,%.9g",
                          i || k ? "," : "", rot[0], rot[1], rot[2], rot[3], rot[4], rot[5], rot[6],
                          rot[7], rot[8], trans[0], trans[1], trans[2]);
            }
        }
        tp_printf(&b, "]");
    }
    tp_printf(&b, ",\"truncated\":%s", path->truncated ? "true" : "false");
    if (b.failed) {
        free(b.text);
        return NULL;
    }
    *len = b.len;
    return b.text;
}
