/* dynamics.h: a machine file's "dynamics" member (docs/plan.md "The machine
 * file's dynamics"): per-axis and trajectory velocity and acceleration
 * limits, rapid rates, tool change time, as LinuxCNC's INI gives them, into
 * toolpaths/plan's fm_plan_machine. */
#ifndef FM_RUNNER_DYNAMICS_H
#define FM_RUNNER_DYNAMICS_H

#include <jansson.h>

#include "toolpaths/plan/plan.h"

/* {"axes": {"x": {"max_velocity": mm/s, "max_acceleration": mm/s^2,
 * "rapid_velocity": mm/s}, ..., "a": {deg/s, deg/s^2}}, "max_velocity":
 * mm/s, "max_acceleration": mm/s^2, "tool_change_s": s, "servo_period_s": s,
 * "max_feed_override": ratio, "lookahead": segments, "follow_blends":
 * true/false (m->programmed_path is its negation)}: every member is
 * optional; *m gets the defaults and given = 1. FM_ERR_INPUT names path and
 * the member when it is wrong. */
fm_status fm_plan_machine_from_json(json_t *dynamics, const char *path, fm_plan_machine *m,
                                    fm_error *err);
/* The dynamics of a machine file: its "dynamics" member (given = 0 without
 * one: feed-only times) and its "rapid_rate" for the feed-only figure. */
fm_status fm_plan_machine_load(const char *path, fm_plan_machine *m, fm_error *err);

#endif
