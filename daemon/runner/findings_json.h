/* findings_json.h: the findings of a check (lib/check) as the JSON of
 * issue 8 and docs/check.md: {"findings": [{"kind", "severity", "part",
 * "line", "block", "time_s", "position", "penetration_mm", "contact"}]},
 * for `frepmill check`, `frepmill simulate` and the daemon. */
#ifndef FM_FINDINGS_JSON_H
#define FM_FINDINGS_JSON_H

#include <jansson.h>

#include "check/check.h"
/* The machine file reader (fm_check_machine_load) lives in machine.c. */
#include "machine.h"

/* One finding (new reference); an uncertain one carries "points". */
json_t *fm_finding_json(const fm_check_finding *finding);
/* The array of findings (new reference). */
json_t *fm_findings_json_array(const fm_check *check);
/* {"findings": [...], "errors": n, "warnings": n} (new reference). */
json_t *fm_findings_json(const fm_check *check);

#endif
