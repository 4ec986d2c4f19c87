/* test_toolpath.c: the toolpath drawn once (daemon/runner/toolpath.c, issue
 * 33), for pictures and for the viewer's document, against hand-made
 * motions and closed forms: a quarter arc of radius 10 has a point every 5
 * degrees on its circle; lines that meet continue one polyline, a rapid
 * starts another, a dwell is one point; past the point bound whole motions
 * are dropped; and on an A table turning 0 -> 90 degrees the document's
 * placement at each point is Rx(A) with A = 90 k / n, so the workpiece
 * point (0, 10, 0) stands at (0, 10 cos A, 10 sin A). */
#include <jansson.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "test.h"
#include "toolpath.h"

static fm_motion motion(fm_motion_kind kind, double x0, double y0, double x1, double y1, double t0,
                        double t1)
{
    fm_motion m;
    memset(&m, 0, sizeof m);
    m.kind = kind;
    m.start[0] = x0;
    m.start[1] = y0;
    m.end[0] = x1;
    m.end[1] = y1;
    m.axis_start[2] = m.axis_end[2] = 1;
    m.t0 = t0;
    m.t1 = t1;
    m.tool = 1;
    m.line = 1;
    m.plane_axis = 2;
    return m;
}

static json_t *document(const fm_toolpath *path, const fm_machine *machine)
{
    size_t len = 0;
    char *members = fm_toolpath_json_members(path, machine, &len);
    CHECK(members != NULL && len == strlen(members));
    if (!members) return NULL;
    char *text = malloc(len + 3);
    snprintf(text, len + 3, "{%s}", members);
    json_error_t jerr;
    json_t *doc = json_loads(text, 0, &jerr);
    if (!doc) printf("not JSON: %s\n", jerr.text);
    CHECK(doc != NULL);
    free(text);
    free(members);
    return doc;
}

static void test_arc_and_lines(void)
{
    fm_toolpath *path = fm_toolpath_new(0);
    /* a feed line (0,0) -> (10,0), then the quarter arc G3 about the origin
     * from (10,0) to (0,10), then a feed line from (0,10): the line and the
     * arc are one polyline; the arc's last point is cos 90 degrees away
     * from x = 0 (not bit for bit the next line's start), so the line
     * starts another */
    fm_motion a = motion(FM_MOTION_LINE, 0, 0, 10, 0, 0, 1);
    fm_motion b = motion(FM_MOTION_ARC, 10, 0, 0, 10, 1, 2);
    b.turns = 1;
    fm_motion c = motion(FM_MOTION_LINE, 0, 10, 0, 20, 2, 3);
    /* a dwell where c ended, then a rapid away (a new polyline), then a
     * feed from where the rapid ended (another) */
    fm_motion d = motion(FM_MOTION_DWELL, 0, 20, 0, 20, 3, 4);
    fm_motion e = motion(FM_MOTION_RAPID, 0, 20, 30, 20, 4, 5);
    fm_motion f = motion(FM_MOTION_LINE, 30, 20, 30, 0, 5, 6);
    const fm_motion *all[] = {&a, &b, &c, &d, &e, &f};
    for (int i = 0; i < 6; i++) fm_toolpath_add(path, all[i]);
    CHECK(!fm_toolpath_truncated(path));

    json_t *doc = document(path, NULL);
    json_t *motions = json_object_get(doc, "motions");
    json_t *points = json_object_get(doc, "points");
    CHECK(json_array_size(motions) == 6);
    CHECK(json_object_get(doc, "placements") == NULL && json_object_get(doc, "machine") == NULL);
    CHECK(json_is_false(json_object_get(doc, "truncated")));
    /* points per motion: a line 2, the 90 degree arc 90 / 5 + 1 = 19, a dwell 1 */
    const int want_count[6] = {2, 19, 2, 1, 2, 2};
    const int want_kind[6] = {1, 2, 1, 4, 0, 1};
    int first = 0;
    for (size_t i = 0; i < 6; i++) {
        json_t *m = json_array_get(motions, i);
        CHECK(json_integer_value(json_array_get(m, 0)) == want_kind[i]);
        CHECK(json_integer_value(json_array_get(m, 5)) == first);
        CHECK(json_integer_value(json_array_get(m, 6)) == want_count[i]);
        CHECK_NEAR(json_number_value(json_array_get(m, 2)), (double)i, 1e-9);
        first += want_count[i];
    }
    CHECK(json_array_size(points) == (size_t)(3 * first));
    /* the arc's point k at angle 5k degrees on the circle of radius 10 */
    for (int k = 0; k < 19; k++) {
        double th = 5.0 * k * FM_PI / 180;
        size_t p = (size_t)(3 * (2 + k));
        CHECK_NEAR(json_number_value(json_array_get(points, p)), 10 * cos(th), 1e-3);
        CHECK_NEAR(json_number_value(json_array_get(points, p + 1)), 10 * sin(th), 1e-3);
    }
    json_decref(doc);

    /* the picture: a and b one feed polyline (2 + 19 points), c and the
     * dwell where it ended another (2 + 1), e a rapid, f a feed on its own
     * (a different kind starts a polyline) */
    fm_render_polyline *lines = NULL;
    size_t count = 0;
    fm_error err;
    CHECK(fm_toolpath_polylines(path, &lines, &count, &err) == FM_OK);
    CHECK(count == 4);
    if (count == 4) {
        CHECK(lines[0].count == 21 && !lines[0].rapid);
        CHECK(lines[1].count == 3 && !lines[1].rapid);
        CHECK(lines[2].count == 2 && lines[2].rapid);
        CHECK(lines[3].count == 2 && !lines[3].rapid);
        CHECK_NEAR(lines[3].points[0], 30, 1e-12);
        CHECK_NEAR(lines[3].points[4], 0, 1e-12);
    }
    free(lines);
    fm_toolpath_free(path);
}

static void test_truncated(void)
{
    /* bound 5: the third line (points 4..5) still goes in (4 points were
     * kept, not more than 5), the fourth is dropped (6 kept) */
    fm_toolpath *path = fm_toolpath_new(5);
    for (int i = 0; i < 4; i++) {
        fm_motion m = motion(FM_MOTION_LINE, i, 0, i + 1, 0, i, i + 1);
        fm_toolpath_add(path, &m);
    }
    CHECK(fm_toolpath_truncated(path));
    json_t *doc = document(path, NULL);
    CHECK(json_array_size(json_object_get(doc, "motions")) == 3);
    CHECK(json_is_true(json_object_get(doc, "truncated")));
    json_decref(doc);
    fm_toolpath_free(path);
}

static void test_table_placements(void)
{
    /* examples/indexer_machine.json: A turns the table about X through the
     * origin; the tool stands still at (0, 0, 20) while A goes 0 -> 90 */
    fm_machine mc;
    memset(&mc, 0, sizeof mc);
    mc.rotary_count = 1;
    mc.rotary[0].letter = 0;
    mc.rotary[0].carries = FM_ROTARY_TABLE;
    mc.rotary[0].around[0] = 1;
    fm_motion m = motion(FM_MOTION_LINE, 0, 0, 0, 0, 0, 1.5);
    m.start[2] = m.end[2] = 20;
    m.machine = &mc;
    m.rotary_end[0] = 90;
    fm_toolpath *path = fm_toolpath_new(0);
    fm_toolpath_add(path, &m);
    json_t *doc = document(path, &mc);
    json_t *table = json_object_get(json_object_get(doc, "machine"), "table");
    CHECK(json_array_size(table) == 1);
    const char *axis = json_string_value(json_object_get(json_array_get(table, 0), "axis"));
    CHECK(axis && !strcmp(axis, "a"));
    json_t *mo = json_array_get(json_object_get(doc, "motions"), 0);
    size_t n = (size_t)json_integer_value(json_array_get(mo, 6));
    /* a point every 5 degrees of A: 18 pieces */
    CHECK(n == 19);
    CHECK(json_array_size(mo) == 13);
    CHECK_NEAR(json_number_value(json_array_get(mo, 10)), 90, 1e-9);
    json_t *P = json_object_get(doc, "placements");
    CHECK(json_array_size(P) == 12 * n);
    for (size_t k = 0; k < n && json_array_size(P) == 12 * n; k++) {
        double A = 90.0 * (double)k / (double)(n - 1) * FM_PI / 180, q[12];
        for (int i = 0; i < 12; i++) q[i] = json_number_value(json_array_get(P, 12 * k + (size_t)i));
        /* Rx(A), row-major, no translation */
        const double want[12] = {1, 0, 0, 0, cos(A), -sin(A), 0, sin(A), cos(A), 0, 0, 0};
        for (int i = 0; i < 12; i++) CHECK_NEAR(q[i], want[i], 1e-8);
        /* (0, 10, 0) of the workpiece on the machine */
        CHECK_NEAR(q[4] * 10 + q[9], 10 * cos(A), 1e-7);
        CHECK_NEAR(q[7] * 10 + q[10], 10 * sin(A), 1e-7);
    }
    json_decref(doc);
    fm_toolpath_free(path);
}

int main(void)
{
    test_arc_and_lines();
    test_truncated();
    test_table_placements();
    return test_summary("test_toolpath");
}
