/* machine.h: the machine file (docs/check.md "Machine file"): travel
 * limits, rapid rate, start position, and the kinematic chain (rotary axes
 * carrying the table or the head, TCP) that `frepmill simulate`, `frepmill
 * check` and the daemon's jobs use. JSON in, lib structures out: lib/ knows
 * no JSON. */
#ifndef FM_MACHINE_FILE_H
#define FM_MACHINE_FILE_H

#include <jansson.h>

#include "check/check.h"

/* {"limits": {"x": [lo, hi], ...}, "rapid_rate": mm/min, "start": [x, y, z],
 * "initial_tool": N (the tool in the spindle before the first M6),
 * "reference_points": [[x, y, z], ...] (Fanuc G28/G30), "tcp": bool, "rotary": [{"axis": "a", "around": [x, y, z], "through":
 * [x, y, z], "carries": "table" | "head", "pivot_length": mm, "limits":
 * [lo, hi] degrees, "wrapped": bool}, ...]}; every member is optional.
 * FM_ERR_INPUT names the file and the member when it is wrong. */
fm_status fm_check_machine_load(const char *path, fm_check_machine *machine, fm_error *err);
/* The same from a JSON value (a job document's machine); name stands for
 * the file in messages. */
fm_status fm_check_machine_from_json(json_t *root, const char *name, fm_check_machine *machine,
                                     fm_error *err);

#endif
