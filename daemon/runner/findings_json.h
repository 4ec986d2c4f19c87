/* findings_json.h: the findings of a check (lib/check) as the JSON of
 * issue 8 and docs/check.md: {"findings": [{"kind", "severity", "part",
 * "line", "block", "time_s", "position", "penetration_mm", "contact"}]},
 * for `frepmill check`, `frepmill simulate` and the daemon. */
#ifndef FM_FINDINGS_JSON_H
#define FM_FINDINGS_JSON_H

#include <jansson.h>

#include "check/check.h"

/* One finding (new reference); an uncertain one carries "points". */
json_t *fm_finding_json(const fm_check_finding *finding);
/* The array of findings (new reference). */
json_t *fm_findings_json_array(const fm_check *check);
/* {"findings": [...], "errors": n, "warnings": n} (new reference). */
json_t *fm_findings_json(const fm_check *check);

/* A machine file (docs/check.md): {"limits": {"x": [lo, hi], "y": [...],
 * "z": [...]}, "rapid_rate": mm/min, "start": [x, y, z]}; every member is
 * optional. FM_ERR_INPUT names the file and the member when it is wrong. */
fm_status fm_check_machine_load(const char *path, fm_check_machine *machine, fm_error *err);
/* The same from a JSON value (the daemon's options.check.machine); name
 * stands for the file in messages. */
fm_status fm_check_machine_from_json(json_t *root, const char *name, fm_check_machine *machine,
                                     fm_error *err);

#endif
