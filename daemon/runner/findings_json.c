/* findings_json.c: lib/check's findings as JSON (jansson); lib/ itself
 * knows no JSON (DESIGN.md sec. 1). */
#include "findings_json.h"

#include <math.h>
#include <string.h>

static json_t *triple(const double v[3])
{
    return json_pack("[f, f, f]", v[0], v[1], v[2]);
}

json_t *fm_finding_json(const fm_check_finding *f)
{
    json_t *o = json_pack("{s:s, s:s, s:s, s:i, s:I, s:f, s:o, s:f, s:o, s:i, s:I}", "kind",
                          fm_check_kind_name(f->kind), "severity",
                          fm_check_severity_name(f->severity), "part",
                          fm_check_part_name(f->part), "line", f->line, "block",
                          (json_int_t)f->block, "time_s", f->time_s, "position",
                          triple(f->position), "penetration_mm", f->penetration_mm, "contact",
                          triple(f->contact), "last_line", f->last_line, "motions",
                          (json_int_t)f->motions);
    if (o && f->fixture >= 0) json_object_set_new(o, "fixture", json_integer(f->fixture));
    if (o && f->kind == FM_CHECK_UNCERTAIN)
        json_object_set_new(o, "points", json_integer((json_int_t)f->points));
    return o;
}

json_t *fm_findings_json_array(const fm_check *check)
{
    json_t *arr = json_array();
    for (size_t i = 0; i < fm_check_count(check); i++) {
        json_t *o = fm_finding_json(fm_check_get(check, i));
        if (o) json_array_append_new(arr, o);
    }
    return arr;
}

json_t *fm_findings_json(const fm_check *check)
{
    return json_pack("{s:o, s:I, s:I}", "findings", fm_findings_json_array(check), "errors",
                     (json_int_t)fm_check_count_severity(check, FM_CHECK_ERROR), "warnings",
                     (json_int_t)fm_check_count_severity(check, FM_CHECK_WARNING));
}

static int number(json_t *v, double *out)
{
    if (!json_is_number(v)) return 0;
    *out = json_number_value(v);
    return isfinite(*out);
}

fm_status fm_check_machine_load(const char *path, fm_check_machine *m, fm_error *err)
{
    memset(m, 0, sizeof *m);
    json_error_t je;
    json_t *root = json_load_file(path, 0, &je);
    if (!root) {
        if (je.line <= 0)
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "cannot read the machine file: %s",
                               je.text);
        return fm_error_at(err, FM_ERR_INPUT, path, je.line, je.column, "%s", je.text);
    }
    fm_status st = fm_check_machine_from_json(root, path, m, err);
    json_decref(root);
    return st;
}

fm_status fm_check_machine_from_json(json_t *root, const char *path, fm_check_machine *m,
                                     fm_error *err)
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
                st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                 "\"limits\" is an object {\"x\": [lo, hi], ...}");
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
                double lo, hi;
                if (a < 0 || !json_is_array(lim) || json_array_size(lim) != 2 ||
                    !number(json_array_get(lim, 0), &lo) || !number(json_array_get(lim, 1), &hi) ||
                    !(lo <= hi)) {
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
                st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                 "rapid_rate: expected mm/min above 0");
                goto done;
            }
        } else if (!strcmp(key, "start")) {
            if (!json_is_array(val) || json_array_size(val) != 3 ||
                !number(json_array_get(val, 0), &m->start[0]) ||
                !number(json_array_get(val, 1), &m->start[1]) ||
                !number(json_array_get(val, 2), &m->start[2])) {
                st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "start: expected [x, y, z] in mm");
                goto done;
            }
        } else if (!strcmp(key, "reference_points")) {
            size_t n = json_is_array(val) ? json_array_size(val) : 0;
            int ok = n >= 1 && n <= 4;
            for (size_t i = 0; ok && i < n; i++) {
                json_t *p = json_array_get(val, i);
                ok = json_is_array(p) && json_array_size(p) == 3 &&
                     number(json_array_get(p, 0), &m->reference_points[i][0]) &&
                     number(json_array_get(p, 1), &m->reference_points[i][1]) &&
                     number(json_array_get(p, 2), &m->reference_points[i][2]);
            }
            if (!ok) {
                st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                 "reference_points: expected 1 to 4 points [x, y, z] in mm (G28, "
                                 "then G30 P2-P4)");
                goto done;
            }
            m->reference_point_count = (int)n;
        } else if (strcmp(key, "units") && strcmp(key, "name") && strcmp(key, "comment")) {
            st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                             "unknown member \"%s\" (limits, rapid_rate, start, reference_points, "
                             "units, name, comment)",
                             key);
            goto done;
        }
    }
    json_t *u = json_object_get(root, "units");
    if (u && (!json_is_string(u) || strcmp(json_string_value(u), "mm"))) {
        st = fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "units: only \"mm\" is understood");
        goto done;
    }
done:
    return st;
}
