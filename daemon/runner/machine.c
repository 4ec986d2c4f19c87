/* machine.c: the machine file reader (docs/check.md "Machine file"): travel
 * limits, rapid rate, the state at the start (where the tool tip is, which
 * tool the spindle holds), and the kinematic
 * chain (rotary axes, TCP) that the G-code front end and the sweep use.
 * Every member is optional; a wrong one is an input error naming the file
 * and the member. */
#include "machine.h"

#include <math.h>
#include <stdio.h>
#include <string.h>

#include "dynamics.h"
#include "sweep/sweep.h"

static int number(json_t *v, double *out)
{
    if (!json_is_number(v)) return 0;
    *out = json_number_value(v);
    return isfinite(*out);
}

static int triple(json_t *v, double out[3])
{
    return json_is_array(v) && json_array_size(v) == 3 && number(json_array_get(v, 0), &out[0]) &&
           number(json_array_get(v, 1), &out[1]) && number(json_array_get(v, 2), &out[2]);
}

static int axis_letter(const char *s)
{
    if (!s[0] || s[1]) return -1;
    char c = s[0];
    return c == 'a' || c == 'A' ? 0 : c == 'b' || c == 'B' ? 1 : c == 'c' || c == 'C' ? 2 : -1;
}

static fm_status read_rotary(json_t *arr, const char *path, fm_machine *mc, fm_error *err)
{
    if (!json_is_array(arr))
        return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                           "\"rotary\" is an array of axes in chain order from the base: "
                           "[{\"axis\": \"a\", \"around\": [1, 0, 0], \"carries\": \"table\"}, ...]");
    if (json_array_size(arr) > FM_MACHINE_MAX_ROTARY)
        return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "rotary: at most %d axes (a, b, c), not %zu",
                           FM_MACHINE_MAX_ROTARY, json_array_size(arr));
    size_t i;
    json_t *ax;
    json_array_foreach(arr, i, ax)
    {
        fm_rotary_axis *r = &mc->rotary[i];
        memset(r, 0, sizeof *r);
        r->letter = -1;
        r->carries = (fm_rotary_link)-1;
        if (!json_is_object(ax))
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "rotary[%zu]: expected an object", i);
        int has_around = 0;
        const char *key;
        json_t *v;
        json_object_foreach(ax, key, v)
        {
            if (!strcmp(key, "axis")) {
                if (!json_is_string(v) || (r->letter = axis_letter(json_string_value(v))) < 0)
                    return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                       "rotary[%zu].axis: expected \"a\", \"b\" or \"c\"", i);
            } else if (!strcmp(key, "around")) {
                if (!triple(v, r->around))
                    return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                       "rotary[%zu].around: expected a direction [x, y, z]", i);
                has_around = 1;
            } else if (!strcmp(key, "through")) {
                if (!triple(v, r->through))
                    return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                       "rotary[%zu].through: expected a point [x, y, z] in mm", i);
            } else if (!strcmp(key, "carries")) {
                const char *c = json_is_string(v) ? json_string_value(v) : "";
                if (!strcmp(c, "table")) r->carries = FM_ROTARY_TABLE;
                else if (!strcmp(c, "head")) r->carries = FM_ROTARY_HEAD;
                else
                    return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                       "rotary[%zu].carries: expected \"table\" or \"head\"", i);
            } else if (!strcmp(key, "pivot_length")) {
                if (!number(v, &r->pivot_length))
                    return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                       "rotary[%zu].pivot_length: expected mm (pivot to spindle gauge line)",
                                       i);
            } else if (!strcmp(key, "limits")) {
                if (!json_is_array(v) || json_array_size(v) != 2 || !number(json_array_get(v, 0), &r->limit_lo) ||
                    !number(json_array_get(v, 1), &r->limit_hi) || !(r->limit_lo <= r->limit_hi))
                    return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                       "rotary[%zu].limits: expected [lo, hi] in degrees, lo <= hi", i);
                r->has_limits = 1;
            } else if (!strcmp(key, "wrapped")) {
                if (!json_is_boolean(v))
                    return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "rotary[%zu].wrapped: expected true or false",
                                       i);
                r->wrapped = json_is_true(v);
            } else if (strcmp(key, "name") && strcmp(key, "comment")) {
                return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                   "rotary[%zu]: unknown member \"%s\" (axis, around, through, carries, "
                                   "pivot_length, limits, wrapped, name, comment)",
                                   i, key);
            }
        }
        if (r->letter < 0 || !has_around || (int)r->carries < 0)
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "rotary[%zu]: \"axis\", \"around\" and \"carries\" are required",
                               i);
        if (r->carries == FM_ROTARY_TABLE && r->pivot_length != 0)
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                               "rotary[%zu].pivot_length: only head axes have a pivot length; a table axis's "
                               "line is placed by \"through\"",
                               i);
        mc->rotary_count = (int)i + 1;
    }
    fm_error verr;
    fm_status st = fm_machine_validate(mc, &verr);
    if (st != FM_OK) return fm_error_at(err, st, path, 0, 0, "rotary: %.400s", verr.message);
    return st;
}

/* "components": [{"model": FILE.hf|FILE.stl, "link": L}]: solids of the
 * machine on a table link: "table" (the machine table, under every rotary
 * table axis) or the letter of a table axis (the link it turns: on an AC
 * trunnion "a" is the cradle, "c" the platter that carries the
 * workpiece). The check sweeps the tool in that link's frame and reports
 * contacts as machine_contact. Components on the head (a spindle housing)
 * move with the tool and are not handled yet: refused, not ignored. */
static fm_status read_components(json_t *val, const char *path, fm_check_machine *m, fm_error *err)
{
    size_t n = json_is_array(val) ? json_array_size(val) : 0;
    if (!json_is_array(val) || n > FM_CHECK_MAX_COMPONENTS)
        return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                           "components: expected an array of at most %d {\"model\": FILE, \"link\": L}",
                           FM_CHECK_MAX_COMPONENTS);
    /* The table links from the base: "table", then each table axis's. */
    static const char *const letters[3] = {"a", "b", "c"};
    const char *links[FM_MACHINE_MAX_ROTARY + 1] = {"table"};
    int nlinks = 1;
    for (int i = 0; i < m->chain.rotary_count && i < FM_MACHINE_MAX_ROTARY; i++)
        if (m->chain.rotary[i].carries == FM_ROTARY_TABLE && (unsigned)m->chain.rotary[i].letter < 3)
            links[nlinks++] = letters[m->chain.rotary[i].letter];
    for (size_t i = 0; i < n; i++) {
        json_t *c = json_array_get(val, i);
        if (!json_is_object(c))
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "components[%zu]: expected an object", i);
        const char *model = NULL, *link = NULL, *key;
        json_t *v;
        json_object_foreach(c, key, v)
        {
            if (!strcmp(key, "model") && json_is_string(v)) {
                model = json_string_value(v);
            } else if (!strcmp(key, "link") && json_is_string(v)) {
                link = json_string_value(v);
            } else if (strcmp(key, "name") && strcmp(key, "comment")) {
                return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                   "components[%zu]: unknown or mistyped member \"%s\" (model and link "
                                   "are strings; name, comment)",
                                   i, key);
            }
        }
        if (!model || !link)
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                               "components[%zu]: \"model\" (a .hf or .stl file) and \"link\" are required", i);
        size_t len = strlen(model);
        if (len >= FM_CHECK_COMPONENT_PATH ||
            !((len > 3 && !strcmp(model + len - 3, ".hf")) || (len > 4 && !strcmp(model + len - 4, ".stl"))))
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                               "components[%zu].model: a .hf model or an .stl mesh (path under %d bytes)", i,
                               FM_CHECK_COMPONENT_PATH);
        int at = -1;
        for (int k = 0; k < nlinks; k++)
            if (!strcmp(link, links[k])) at = k;
        if (at < 0) {
            int head = 0;
            for (int k = 0; k < m->chain.rotary_count && k < FM_MACHINE_MAX_ROTARY; k++)
                if (m->chain.rotary[k].carries == FM_ROTARY_HEAD && (unsigned)m->chain.rotary[k].letter < 3 &&
                    !strcmp(link, letters[m->chain.rotary[k].letter]))
                    head = 1;
            if (head || !strcmp(link, "head") || !strcmp(link, "spindle"))
                return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                   "components[%zu].link \"%.16s\": components on the head move with the tool "
                                   "and are not handled yet; give table links (\"table\" or a table axis)",
                                   i, link);
            char known[48] = "";
            for (int k = 0; k < nlinks; k++) {
                size_t used = strlen(known);
                snprintf(known + used, sizeof known - used, "%s\"%s\"", k ? ", " : "", links[k]);
            }
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                               "components[%zu].link \"%.16s\": not a table link of this machine (%s)", i, link,
                               known);
        }
        m->component_frame_up[i] = nlinks - 1 - at;
        memcpy(m->component_path[i], model, len + 1);
        m->component_count = (int)i + 1;
    }
    return FM_OK;
}

/* "head": [{"diameter": D, "length": L, "diameter_top": T}, ...]: the
 * round parts of the machine's head (spindle nose, housing), solids of
 * revolution about the spindle stacked up from the spindle's face (the
 * top of each tool's holder), as a tool's holder segments are. */
static fm_status read_head(json_t *val, const char *path, fm_check_machine *m, fm_error *err)
{
    size_t n = json_is_array(val) ? json_array_size(val) : 0;
    if (n < 1 || n > FM_TOOL_MAX_HOLDER)
        return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                           "head: expected 1 to %d round segments [{\"diameter\": D, \"length\": L}, ...] "
                           "stacked up from the spindle's face",
                           FM_TOOL_MAX_HOLDER);
    for (size_t i = 0; i < n; i++) {
        json_t *g = json_array_get(val, i);
        fm_holder_segment *h = &m->head[i];
        memset(h, 0, sizeof *h);
        if (!json_is_object(g))
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "head[%zu]: expected an object", i);
        const char *key;
        json_t *v;
        json_object_foreach(g, key, v)
        {
            double d;
            if (!strcmp(key, "diameter") && number(v, &d) && d > 0 && d <= 1e4) {
                h->diameter = d;
            } else if (!strcmp(key, "diameter_top") && number(v, &d) && d >= 0 && d <= 1e4) {
                h->diameter_top = d;
            } else if (!strcmp(key, "length") && number(v, &d) && d > 0 && d <= 1e4) {
                h->length = d;
            } else if (strcmp(key, "name") && strcmp(key, "comment")) {
                return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                   "head[%zu].%s: expected diameter and length (mm, above 0, at most "
                                   "10000), diameter_top (0 or above), name, comment",
                                   i, key);
            }
        }
        if (!(h->diameter > 0) || !(h->length > 0))
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "head[%zu]: \"diameter\" and \"length\" are required",
                               i);
    }
    m->head_count = (int)n;
    return FM_OK;
}

fm_status fm_check_machine_load(const char *path, fm_check_machine *m, fm_error *err)
{
    memset(m, 0, sizeof *m);
    json_error_t je;
    json_t *root = json_load_file(path, JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        if (je.line <= 0)
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "cannot read the machine file: %s", je.text);
        return fm_error_at(err, FM_ERR_INPUT, path, je.line, je.column, "%s", je.text);
    }
    fm_status st = fm_check_machine_from_json(root, path, m, err);
    json_decref(root);
    return st;
}

fm_status fm_check_machine_from_json(json_t *root, const char *path, fm_check_machine *m, fm_error *err)
{
    memset(m, 0, sizeof *m);
    fm_status st = FM_OK;
    if (!json_is_object(root)) {
        st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "a machine file is a JSON object");
        goto done;
    }
    const char *key;
    json_t *val;
    json_object_foreach(root, key, val)
    {
        if (!strcmp(key, "limits")) {
            if (!json_is_object(val)) {
                st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "\"limits\" is an object {\"x\": [lo, hi], ...}");
                goto done;
            }
            const char *ax;
            json_t *lim;
            json_object_foreach(val, ax, lim)
            {
                int a = !strcmp(ax, "x") || !strcmp(ax, "X")   ? 0
                        : !strcmp(ax, "y") || !strcmp(ax, "Y") ? 1
                        : !strcmp(ax, "z") || !strcmp(ax, "Z") ? 2
                                                               : -1;
                if (axis_letter(ax) >= 0) {
                    st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                     "limits.%s: a rotary axis's limits go with the axis: \"rotary\": "
                                     "[{\"axis\": \"%s\", ..., \"limits\": [lo, hi]}]",
                                     ax, ax);
                    goto done;
                }
                double lo, hi;
                if (a < 0 || !json_is_array(lim) || json_array_size(lim) != 2 ||
                    !number(json_array_get(lim, 0), &lo) || !number(json_array_get(lim, 1), &hi) || !(lo <= hi)) {
                    st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                     "limits.%s: expected one of x, y, z with [lo, hi] in mm, "
                                     "lo <= hi",
                                     ax);
                    goto done;
                }
                m->has_limit[a] = 1;
                m->limit_lo[a] = lo;
                m->limit_hi[a] = hi;
            }
        } else if (!strcmp(key, "rapid_rate")) {
            if (!number(val, &m->rapid_rate) || !(m->rapid_rate > 0)) {
                st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "rapid_rate: expected mm/min above 0");
                goto done;
            }
        } else if (!strcmp(key, "start")) {
            if (!triple(val, m->start)) {
                st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "start: expected [x, y, z] in mm");
                goto done;
            }
            m->has_start = 1;
        } else if (!strcmp(key, "initial_tool")) {
            /* the tool in the spindle before the first M6; the job checks
             * it against its tool table */
            double t;
            if (!json_is_integer(val) || !number(val, &t) || t < 0 || t > 99999999) {
                st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                 "initial_tool: expected the number of the tool in the spindle at "
                                 "the start (0: none)");
                goto done;
            }
            m->initial_tool = (int)t;
        } else if (!strcmp(key, "reference_points")) {
            size_t n = json_is_array(val) ? json_array_size(val) : 0;
            int ok = n >= 1 && n <= 4;
            for (size_t i = 0; ok && i < n; i++) ok = triple(json_array_get(val, i), m->reference_points[i]);
            if (!ok) {
                st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                 "reference_points: expected 1 to 4 points [x, y, z] in mm (G28, "
                                 "then G30 P2-P4)");
                goto done;
            }
            m->reference_point_count = (int)n;
        } else if (!strcmp(key, "tcp")) {
            if (!json_is_boolean(val)) {
                st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                 "tcp: expected true (tool centre point control) or false");
                goto done;
            }
            m->chain.tcp = json_is_true(val);
        } else if (!strcmp(key, "rotary")) {
            if ((st = read_rotary(val, path, &m->chain, err)) != FM_OK) goto done;
        } else if (!strcmp(key, "head")) {
            if ((st = read_head(val, path, m, err)) != FM_OK) goto done;
        } else if (!strcmp(key, "dynamics")) {
            /* the planner's (runner/dynamics.c): checked here so that every
             * reader of the file refuses the same mistakes */
            fm_plan_machine dyn;
            if ((st = fm_plan_machine_from_json(val, path, &dyn, err)) != FM_OK) goto done;
        } else if (!strcmp(key, "components")) {
            /* read after the loop: the chain decides which link is the workpiece's */
        } else if (strcmp(key, "units") && strcmp(key, "name") && strcmp(key, "comment")) {
            st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                             "unknown member \"%s\" (limits, rapid_rate, start, initial_tool, "
                             "reference_points, tcp, rotary, head, components, dynamics, units, name, "
                             "comment)",
                             key);
            goto done;
        }
    }
    json_t *comp = json_object_get(root, "components");
    if (comp && (st = read_components(comp, path, m, err)) != FM_OK) goto done;
    json_t *u = json_object_get(root, "units");
    if (u && (!json_is_string(u) || strcmp(json_string_value(u), "mm"))) {
        st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "units: only \"mm\" is understood");
        goto done;
    }
    if (m->chain.tcp && m->chain.rotary_count == 0) {
        st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "tcp: true needs rotary axes (\"rotary\": [...])");
        goto done;
    }
done:
    if (st != FM_OK) memset(m, 0, sizeof *m);
    return st;
}
