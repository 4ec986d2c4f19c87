/* findings_json.c: lib/check's findings as JSON (jansson); lib/ itself
 * knows no JSON (ARCHITECTURE.md, "The layers"). */
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
