/* dynamics.c: the machine file's "dynamics" member -> fm_plan_machine
 * (dynamics.h). */
#include "runner/dynamics.h"

#include <string.h>

static int positive(json_t *v, double *out)
{
    if (!json_is_number(v)) return 0;
    *out = json_number_value(v);
    return *out > 0;
}

static fm_status read_axis(json_t *val, const char *path, const char *name, fm_plan_axis *ax,
                           double *rapid, fm_error *err)
{
    if (!json_is_object(val))
        return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                           "dynamics.axes.%s: expected {\"max_velocity\": ..., \"max_acceleration\": ...}",
                           name);
    const char *key;
    json_t *v;
    json_object_foreach(val, key, v)
    {
        double *slot = !strcmp(key, "max_velocity")                ? &ax->max_velocity
                       : !strcmp(key, "max_acceleration")          ? &ax->max_acceleration
                       : !strcmp(key, "rapid_velocity") && rapid   ? rapid
                                                                   : NULL;
        if (!slot)
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                               "dynamics.axes.%s: unknown member \"%s\" (max_velocity, "
                               "max_acceleration%s)",
                               name, key, rapid ? ", rapid_velocity" : "");
        if (!positive(v, slot))
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                               "dynamics.axes.%s.%s: expected a number above 0 (%s)", name, key,
                               rapid ? "mm/s, mm/s^2" : "deg/s, deg/s^2");
    }
    return FM_OK;
}

fm_status fm_plan_machine_from_json(json_t *dyn, const char *path, fm_plan_machine *m, fm_error *err)
{
    fm_plan_machine_default(m);
    if (!json_is_object(dyn))
        return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                           "dynamics: expected an object {\"axes\": {...}, \"max_velocity\": ...}");
    m->given = 1;
    const char *key;
    json_t *v;
    json_object_foreach(dyn, key, v)
    {
        if (!strcmp(key, "axes")) {
            if (!json_is_object(v))
                return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                   "dynamics.axes: expected {\"x\": {...}, \"y\": {...}, ...}");
            const char *ax;
            json_t *lim;
            json_object_foreach(v, ax, lim)
            {
                static const char letters[] = "xyzabc";
                const char *at = strlen(ax) == 1 ? strchr(letters, ax[0] | 0x20) : NULL;
                if (!at || !ax[0])
                    return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                       "dynamics.axes.%s: expected one of x, y, z, a, b, c", ax);
                int i = (int)(at - letters);
                fm_status st = i < 3 ? read_axis(lim, path, ax, &m->linear[i], &m->rapid_velocity[i], err)
                                     : read_axis(lim, path, ax, &m->rotary[i - 3], NULL, err);
                if (st) return st;
            }
        } else if (!strcmp(key, "lookahead")) {
            if (!json_is_integer(v) || json_integer_value(v) < 2 || json_integer_value(v) > 10000)
                return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                   "dynamics.lookahead: expected a whole number of segments, 2 to 10000");
            m->lookahead = (int)json_integer_value(v);
        } else if (!strcmp(key, "follow_blends")) {
            if (!json_is_boolean(v))
                return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                   "dynamics.follow_blends: expected true or false");
            m->programmed_path = !json_is_true(v);
        } else {
            double *slot = !strcmp(key, "max_velocity")        ? &m->traj_max_velocity
                           : !strcmp(key, "max_acceleration")  ? &m->traj_max_acceleration
                           : !strcmp(key, "tool_change_s")     ? &m->tool_change_s
                           : !strcmp(key, "servo_period_s")    ? &m->servo_period_s
                           : !strcmp(key, "max_feed_override") ? &m->max_feed_override
                                                               : NULL;
            if (!slot)
                return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                   "dynamics: unknown member \"%s\" (axes, max_velocity, "
                                   "max_acceleration, tool_change_s, servo_period_s, "
                                   "max_feed_override, lookahead, follow_blends)",
                                   key);
            if (!json_is_number(v) || !(json_number_value(v) > 0) ||
                (slot == &m->tool_change_s && !(json_number_value(v) >= 0)))
                return fm_error_at(err, FM_ERR_INPUT, path, 0, 0,
                                   "dynamics.%s: expected a number above 0", key);
            *slot = json_number_value(v);
        }
    }
    return FM_OK;
}

fm_status fm_plan_machine_load(const char *path, fm_plan_machine *m, fm_error *err)
{
    fm_plan_machine_default(m);
    json_error_t je;
    json_t *root = json_load_file(path, JSON_REJECT_DUPLICATES, &je);
    if (!root) {
        if (je.line <= 0)
            return fm_error_at(err, FM_ERR_INPUT, path, 0, 0, "cannot read the machine file: %s", je.text);
        return fm_error_at(err, FM_ERR_INPUT, path, je.line, je.column, "%s", je.text);
    }
    fm_status st = FM_OK;
    json_t *dyn = json_object_get(root, "dynamics");
    if (dyn) st = fm_plan_machine_from_json(dyn, path, m, err);
    json_t *rr = json_object_get(root, "rapid_rate");
    if (!st && json_is_number(rr) && json_number_value(rr) > 0) m->rapid_rate = json_number_value(rr);
    json_decref(root);
    return st;
}
