/* test_plan_reference: frepmill's planner against LinuxCNC's. For each
 * program of tests/plan/programs that tests/plan/lcnc_times.json has timed on
 * LinuxCNC's simulator (tests/plan/lcnc_reference.py records them), the
 * planner with the simulator's limits (read from the same table) must agree
 * within 2% on the program's machine time. Both sides are measured above
 * the program baseline.ngc (a 2 mm move), which holds LinuxCNC's fixed cost
 * of a run (reading and queueing the program, the display's polling). The
 * feed-only figure is printed beside each. Usage: test_plan_reference
 * [TABLE.json [PROGRAM_DIR]] (default: plan/lcnc_times.json, plan/programs). */
#include <jansson.h>

#include "toolpaths/gcode/gcode.h"
#include "toolpaths/plan/plan.h"
#include "test.h"

static int load_machine(json_t *root, fm_plan_machine *m)
{
    fm_plan_machine_default(m);
    json_t *lim = json_object_get(root, "limits");
    if (!lim) return -1;
    const char *names[3] = {"x", "y", "z"};
    for (int i = 0; i < 3; i++) {
        json_t *ax = json_object_get(json_object_get(lim, "axes"), names[i]);
        m->linear[i].max_velocity = json_number_value(json_object_get(ax, "max_velocity"));
        m->linear[i].max_acceleration = json_number_value(json_object_get(ax, "max_acceleration"));
    }
    json_t *traj = json_object_get(lim, "traj");
    m->traj_max_velocity = json_number_value(json_object_get(traj, "max_velocity"));
    m->traj_max_acceleration = json_number_value(json_object_get(traj, "max_acceleration"));
    m->servo_period_s = json_number_value(json_object_get(lim, "servo_period_s"));
    m->max_feed_override = json_number_value(json_object_get(lim, "max_feed_override"));
    m->given = 1;
    return 0;
}

static int plan_program(const char *path, const fm_plan_machine *m, fm_plan_totals *tot)
{
    fm_error err = {0};
    fm_planner *p = fm_planner_new(m, NULL, NULL, &err);
    if (!p) return -1;
    fm_gcode_options opt;
    fm_gcode_options_default(&opt);
    fm_status st = fm_gcode_run_file(path, &opt, fm_planner_motion_sink, p, NULL, &err);
    if (!st) st = fm_planner_finish(p, tot, &err);
    if (st) {
        char buf[512];
        fprintf(stderr, "%s: %s\n", path, fm_error_format(&err, buf, sizeof buf));
    }
    fm_planner_free(p);
    return st ? -1 : 0;
}

int main(int argc, char **argv)
{
    const char *table = argc > 1 ? argv[1] : "plan/lcnc_times.json";
    const char *dir = argc > 2 ? argv[2] : "plan/programs";
    json_error_t jerr;
    json_t *root = json_load_file(table, 0, &jerr);
    CHECK(root != NULL);
    if (!root) return 1;
    fm_plan_machine m;
    CHECK(load_machine(root, &m) == 0);
    json_t *secs = json_object_get(root, "seconds");
    char path[1024];
    snprintf(path, sizeof path, "%s/baseline.ngc", dir);
    fm_plan_totals base = {0};
    CHECK(plan_program(path, &m, &base) == 0);
    double lcnc_base = json_number_value(json_object_get(secs, "baseline.ngc"));
    CHECK(lcnc_base > 0.0);
    printf("%-22s %10s %10s %10s %8s\n", "program", "linuxcnc", "frepmill", "feed-only", "diff");
    const char *name;
    json_t *v;
    int compared = 0;
    json_object_foreach(secs, name, v) {
        if (!strcmp(name, "baseline.ngc")) continue;
        snprintf(path, sizeof path, "%s/%s", dir, name);
        fm_plan_totals tot = {0};
        CHECK(plan_program(path, &m, &tot) == 0);
        double ref = json_number_value(v) - lcnc_base + base.cycle_time_s;
        double diff = (tot.cycle_time_s - ref) / ref;
        printf("%-22s %10.3f %10.3f %10.3f %+7.2f%%\n", name, ref, tot.cycle_time_s, tot.feed_only_s,
               100.0 * diff);
        CHECK(fabs(diff) <= 0.02);
        compared++;
    }
    CHECK(compared >= 6);
    json_decref(root);
    return test_summary("plan_reference");
}
