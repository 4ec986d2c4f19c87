/* comments.c: tools from a program's comments (--tools-from-program). CAM
 * posts list the tools in the program's header: Fusion's and posts like it
 * "(T1 D=6. CR=0. TAPER=45DEG - ZMIN=-5. - FLAT END MILL)", LinuxCNC-style
 * "(T1 D6 ball)". A comment names a tool when it starts with T<number>
 * followed by a diameter; what it does not say is guessed, and every guess
 * is listed in a warning (docs/tooltable.md). */
#include "tooltable_internal.h"

#include <ctype.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

typedef struct ctool {
    fm_tool_spec spec;
    int line;
    char guessed[200];
} ctool;

struct fm_tooltable_comments {
    char name[256];
    int inch;
    ctool *tools;
    size_t count, cap;
    int overflow; /* more tools than FM_TOOLTABLE_MAX_TOOLS, or out of memory */
};

fm_tooltable_comments *fm_tooltable_comments_new(const char *name, int inch)
{
    fm_tooltable_comments *c = calloc(1, sizeof *c);
    if (!c) return NULL;
    tt_copy(c->name, sizeof c->name, name ? name : "");
    c->inch = inch;
    return c;
}

void fm_tooltable_comments_free(fm_tooltable_comments *c)
{
    if (!c) return;
    free(c->tools);
    free(c);
}

/* "6." "-5" "0.25" at p (may be followed by a unit such as DEG): the value
 * and the characters read, 0 when there is no number. */
static size_t number_at(const char *p, double *out)
{
    char *end;
    double x = strtod(p, &end);
    if (end == p || !isfinite(x)) return 0;
    /* strtod reads "1e5", "inf", hex: accept plain decimals only */
    for (const char *q = p; q < end; q++)
        if (!isdigit((unsigned char)*q) && *q != '.' && *q != '-' && *q != '+') return 0;
    *out = x;
    return (size_t)(end - p);
}

static void append(char *buf, size_t size, const char *text)
{
    size_t n = strlen(buf);
    if (n + 1 < size) snprintf(buf + n, size - n, "%s%s", n ? ", " : "", text);
}

/* One comment: a tool into *t (0), or not a tool comment (-1). */
static int parse_comment(const fm_tooltable_comments *c, const char *text, size_t len, ctool *t)
{
    char buf[256], lower[256];
    if (len >= sizeof buf) len = sizeof buf - 1;
    memcpy(buf, text, len);
    buf[len] = '\0';
    for (size_t i = 0; i < len; i++)
        if (!buf[i] || buf[i] == '\t' || buf[i] == '|') buf[i] = ' ';
    char *p = buf;
    while (*p == ' ') p++;
    if (toupper((unsigned char)*p) != 'T' || !isdigit((unsigned char)p[1])) return -1;
    char *end;
    long number = strtol(p + 1, &end, 10);
    if (number < 1 || number > 99999 || (*end && *end != ' ')) return -1;
    double unit = c->inch ? 25.4 : 1.0;
    double d = -1, cr = -1, taper = -1, zmin = 1;
    char desc[128] = "";
    /* the rest: KEY=value words, D<value>, " - " separators, and words; the
     * description is the words after the last separator (Fusion puts the
     * type last) or all of them */
    for (char *q = end; *q;) {
        while (*q == ' ') q++;
        if (!*q) break;
        char *w = q;
        while (*q && *q != ' ') q++;
        char save = *q;
        *q = '\0';
        double x;
        size_t k;
        char *eq = strchr(w, '=');
        if (!strcmp(w, "-")) {
            desc[0] = '\0';
        } else if (eq && eq > w && (k = number_at(eq + 1, &x))) {
            *eq = '\0';
            for (char *u = w; *u; u++) *u = (char)toupper((unsigned char)*u);
            if (!strcmp(w, "D")) d = x;
            else if (!strcmp(w, "CR") || !strcmp(w, "R")) cr = x;
            else if (!strcmp(w, "TAPER")) taper = x;
            else if (!strcmp(w, "ZMIN")) zmin = x;
            *eq = '=';
        } else if (toupper((unsigned char)w[0]) == 'D' && (k = number_at(w + 1, &x)) &&
                   !w[1 + k] && d < 0) {
            d = x;
        } else {
            size_t n = strlen(desc);
            if (n + strlen(w) + 2 < sizeof desc) snprintf(desc + n, sizeof desc - n, "%s%s",
                                                          n ? " " : "", w);
        }
        *q = save;
    }
    if (!(d > 0)) return -1;
    memset(t, 0, sizeof *t);
    fm_tool_spec *s = &t->spec;
    s->number = (int)number;
    s->center_cutting = 1;
    s->diameter = d * unit;
    tt_copy(s->comment, sizeof s->comment, desc);
    size_t n = strlen(desc);
    for (size_t i = 0; i <= n; i++) lower[i] = (char)tolower((unsigned char)desc[i]);
    double r = s->diameter / 2;
    double crmm = cr > 0 ? cr * unit : 0;
    char g[96];
    /* the shape: named by the description, else by the corner radius */
    if (tt_has_word(lower, "drill")) {
        s->shape = FM_TOOL_DRILL;
        /* Fusion's TAPER of a drill is its point angle */
        if (taper > 0 && taper < 180) s->point_angle = taper;
        else {
            s->point_angle = 118;
            append(t->guessed, sizeof t->guessed, "point_angle 118");
        }
    } else if (tt_has_word(lower, "chamfer") || tt_has_word(lower, "countersink") ||
               tt_has_word(lower, "sink") || tt_has_word(lower, "vbit") || tt_has_word(lower, "v-bit") ||
               tt_has_word(lower, "engraving")) {
        s->shape = FM_TOOL_VBIT;
        /* a chamfer mill's TAPER is per side */
        if (taper > 0 && taper < 90) s->angle = 2 * taper;
        else {
            s->angle = 90;
            append(t->guessed, sizeof t->guessed, "angle 90");
        }
    } else if (tt_has_word(lower, "ball") || (crmm > 0 && fabs(crmm - r) < 1e-9)) {
        s->shape = FM_TOOL_BALL;
    } else if (tt_has_word(lower, "bull") || tt_has_word(lower, "bullnose") || crmm > 0) {
        if (crmm > 0) { /* lib/tools refuses one larger than the radius */
            s->shape = FM_TOOL_BULL;
            s->corner_radius = crmm;
        } else {
            s->shape = FM_TOOL_BULL;
            s->corner_radius = r / 4;
            snprintf(g, sizeof g, "corner_radius %g mm (D / 8)", r / 4);
            append(t->guessed, sizeof t->guessed, g);
        }
    } else if (tt_has_word(lower, "tapered") && taper > 0 && taper < 90) {
        s->shape = FM_TOOL_TAPERED;
        s->taper_angle = taper;
    } else {
        s->shape = FM_TOOL_FLAT;
        if (!desc[0]) append(t->guessed, sizeof t->guessed, "shape flat");
    }
    /* the lengths: flutes three diameters long and at least the deepest Z
     * the post reports, the stick-out one diameter more */
    double depth = zmin < 0 ? -zmin * unit : 0;
    s->flute_length = fmax(3 * s->diameter, depth);
    s->length = s->flute_length + s->diameter;
    s->shank_diameter = s->diameter;
    snprintf(g, sizeof g, "flute_length %g mm (3 x D%s)", s->flute_length,
             depth > 3 * s->diameter ? ", the depth ZMIN" : "");
    append(t->guessed, sizeof t->guessed, g);
    snprintf(g, sizeof g, "length %g mm (flute length + D)", s->length);
    append(t->guessed, sizeof t->guessed, g);
    append(t->guessed, sizeof t->guessed, "shank_diameter = D");
    append(t->guessed, sizeof t->guessed, "no holder");
    return 0;
}

void fm_tooltable_comments_add(void *comments, int line, const char *text, size_t len)
{
    fm_tooltable_comments *c = comments;
    if (!c || !text || c->overflow) return;
    ctool t;
    if (parse_comment(c, text, len, &t)) return;
    for (size_t i = 0; i < c->count; i++)
        if (c->tools[i].spec.number == t.spec.number) return; /* the first names it */
    if (c->count >= FM_TOOLTABLE_MAX_TOOLS) {
        c->overflow = 1;
        return;
    }
    if (c->count == c->cap) {
        size_t nc = c->cap ? c->cap * 2 : 16;
        ctool *nt = realloc(c->tools, nc * sizeof *nt);
        if (!nt) {
            c->overflow = 1;
            return;
        }
        c->tools = nt;
        c->cap = nc;
    }
    t.line = line;
    c->tools[c->count++] = t;
}

fm_status fm_tooltable_comments_finish(fm_tooltable_comments *c, const fm_tooltable_options *opt,
                                       fm_tool_table *out, fm_error *err)
{
    fm_error local;
    if (!err) err = &local;
    fm_error_clear(err);
    out->count = 0;
    out->tools = NULL;
    if (!c) return fm_error_set(err, FM_ERR_LIMIT, "out of memory (tool comments)");
    tt_reader r = {c->name, opt, err};
    if (c->overflow)
        return fm_error_at(err, FM_ERR_LIMIT, c->name, 0, 0,
                           "tool comments: more than %d tools (or out of memory)",
                           FM_TOOLTABLE_MAX_TOOLS);
    size_t cap = 0;
    for (size_t i = 0; i < c->count; i++) {
        ctool *t = &c->tools[i];
        char where[192];
        snprintf(where, sizeof where, "line %d (T%d \"%.60s\")", t->line, t->spec.number,
                 t->spec.comment);
        fm_status st;
        if ((st = tt_validate(&r, &t->spec, where))) {
            err->line = t->line;
            fm_tool_table_free(out);
            return st;
        }
        if ((st = tt_push(&r, out, &cap, &t->spec, where))) return st;
        tt_warn(&r, "%s:%d: T%d \"%s\" from the program's comment%s, guessed: %s", c->name, t->line,
                t->spec.number, t->spec.comment, c->inch ? " (inches)" : "", t->guessed);
    }
    return FM_OK;
}
