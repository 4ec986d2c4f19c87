/* test_machine_file.c: the machine file reader (daemon/runner/machine.c):
 * the kinematic chain (rotary axes, TCP, per-axis limits) as documented in
 * docs/check.md, and the errors that name the member at fault. */
#include "test.h"
#include "runner/machine.h"

#include <stdlib.h>
#include <string.h>

static fm_status load_text(const char *text, fm_check_machine *m, fm_error *err)
{
    char path[] = "/tmp/fm_machine_XXXXXX";
    int fd = mkstemp(path);
    if (fd < 0) return FM_ERR_IO;
    FILE *f = fdopen(fd, "w");
    fputs(text, f);
    fclose(f);
    fm_status st = fm_check_machine_load(path, m, err);
    remove(path);
    return st;
}

static void check_trunnion(void)
{
    fm_check_machine m;
    fm_error err;
    fm_status st = fm_check_machine_load("check/corpus_machine/trunnion.json", &m, &err);
    CHECK(st == FM_OK);
    if (st != FM_OK) {
        fprintf(stderr, "%s\n", err.message);
        return;
    }
    CHECK(m.chain.tcp == 1);
    CHECK(m.chain.rotary_count == 2);
    CHECK(m.chain.rotary[0].letter == 0 && m.chain.rotary[1].letter == 2);
    CHECK(m.chain.rotary[0].carries == FM_ROTARY_TABLE);
    CHECK_NEAR(m.chain.rotary[0].through[2], -50, 0);
    CHECK(m.chain.rotary[0].has_limits && m.chain.rotary[0].limit_lo == -120 && m.chain.rotary[0].limit_hi == 30);
    CHECK(m.chain.rotary[1].wrapped && !m.chain.rotary[1].has_limits);
    CHECK(m.has_limit[0] && m.limit_hi[2] == 50);
    /* head axes, upper-case letters, directions normalized */
    st = load_text("{\"rotary\": [{\"axis\": \"C\", \"around\": [0, 0, 2], \"carries\": \"head\"},"
                   " {\"axis\": \"b\", \"around\": [0, 3, 0], \"carries\": \"head\", \"pivot_length\": 150}]}",
                   &m, &err);
    CHECK(st == FM_OK);
    CHECK(m.chain.rotary_count == 2 && m.chain.rotary[0].letter == 2 && m.chain.rotary[1].carries == FM_ROTARY_HEAD);
    CHECK_NEAR(m.chain.rotary[0].around[2], 1, 1e-15);
    CHECK_NEAR(m.chain.rotary[1].around[1], 1, 1e-15);
    CHECK_NEAR(m.chain.rotary[1].pivot_length, 150, 0);
    CHECK(!m.chain.tcp);
    /* components on table links: the workpiece's (the last table axis, C
     * here, after A: 0 links below it), A's cradle (1 below), the machine
     * table (2 below) */
    st = load_text("{\"rotary\": [{\"axis\": \"a\", \"around\": [1, 0, 0], \"carries\": \"table\"},"
                   " {\"axis\": \"c\", \"around\": [0, 0, 1], \"carries\": \"table\"}],"
                   " \"components\": [{\"name\": \"platter\", \"model\": \"p.hf\", \"link\": \"c\"},"
                   " {\"model\": \"base.stl\", \"link\": \"c\"}, {\"model\": \"cradle.stl\", \"link\": \"a\"},"
                   " {\"model\": \"bed.hf\", \"link\": \"table\"}]}",
                   &m, &err);
    CHECK(st == FM_OK);
    CHECK(m.component_count == 4);
    CHECK(!strcmp(m.component_path[0], "p.hf") && !strcmp(m.component_path[1], "base.stl"));
    CHECK(m.component_frame_up[0] == 0 && m.component_frame_up[1] == 0);
    CHECK(m.component_frame_up[2] == 1 && m.component_frame_up[3] == 2);
    st = load_text("{\"rotary\": [{\"axis\": \"b\", \"around\": [0, 1, 0], \"carries\": \"head\"}],"
                   " \"components\": [{\"model\": \"vise.stl\", \"link\": \"table\"}]}",
                   &m, &err);
    CHECK(st == FM_OK && m.component_count == 1 && m.component_frame_up[0] == 0);
    /* the head's round parts, stacked from the spindle's face */
    st = load_text("{\"head\": [{\"name\": \"nose\", \"diameter\": 100, \"length\": 40},"
                   " {\"diameter\": 160, \"diameter_top\": 180, \"length\": 200}]}",
                   &m, &err);
    CHECK(st == FM_OK && m.head_count == 2);
    CHECK(m.head[0].diameter == 100 && m.head[0].length == 40 && m.head[0].diameter_top == 0);
    CHECK(m.head[1].diameter == 160 && m.head[1].diameter_top == 180 && m.head[1].length == 200);
}

static void check_errors(void)
{
    struct {
        const char *text, *want;
    } cases[] = {
        {"{\"rotary\": {}}", "\"rotary\" is an array"},
        {"{\"rotary\": [{\"axis\": \"d\", \"around\": [1, 0, 0], \"carries\": \"table\"}]}", "rotary[0].axis"},
        {"{\"rotary\": [{\"axis\": \"a\", \"carries\": \"table\"}]}", "are required"},
        {"{\"rotary\": [{\"axis\": \"a\", \"around\": [1, 0], \"carries\": \"table\"}]}", "rotary[0].around"},
        {"{\"rotary\": [{\"axis\": \"a\", \"around\": [0, 0, 0], \"carries\": \"table\"}]}", "non-zero direction"},
        {"{\"rotary\": [{\"axis\": \"a\", \"around\": [1, 0, 0], \"carries\": \"table\"},"
         " {\"axis\": \"a\", \"around\": [0, 1, 0], \"carries\": \"head\"}]}",
         "given twice"},
        {"{\"rotary\": [{\"axis\": \"b\", \"around\": [0, 1, 0], \"carries\": \"spindle\"}]}", "rotary[0].carries"},
        {"{\"rotary\": [{\"axis\": \"b\", \"around\": [0, 1, 0], \"carries\": \"table\", \"limits\": [5, -5]}]}",
         "rotary[0].limits"},
        {"{\"rotary\": [{\"axis\": \"b\", \"around\": [0, 1, 0], \"carries\": \"table\", \"pivot_length\": 9}]}",
         "only head axes"},
        {"{\"rotary\": [{\"axis\": \"b\", \"around\": [0, 1, 0], \"carries\": \"table\", \"speed\": 9}]}",
         "unknown member \"speed\""},
        {"{\"tcp\": true}", "needs rotary axes"},
        {"{\"tcp\": 1}", "tcp: expected"},
        {"{\"limits\": {\"a\": [0, 90]}}", "go with the axis"},
        {"{\"rapid_rate\": 1, \"rapid_rate\": 2}", "duplicate"},
        {"{\"rotary\": [{\"axis\": \"a\", \"around\": [1, 0, 0], \"carries\": \"table\"},"
         " {\"axis\": \"c\", \"around\": [0, 0, 1], \"carries\": \"table\"}],"
         " \"components\": [{\"model\": \"cradle.stl\", \"link\": \"b\"}]}",
         "components[0].link \"b\": not a table link of this machine (\"table\", \"a\", \"c\")"},
        {"{\"rotary\": [{\"axis\": \"b\", \"around\": [0, 1, 0], \"carries\": \"head\"}],"
         " \"components\": [{\"model\": \"housing.stl\", \"link\": \"b\"}]}",
         "components[0].link \"b\": components on the head move with the tool"},
        {"{\"components\": [{\"model\": \"housing.stl\", \"link\": \"spindle\"}]}",
         "components on the head move with the tool"},
        {"{\"components\": [{\"model\": \"t.step\", \"link\": \"table\"}]}", "components[0].model"},
        {"{\"head\": []}", "head: expected 1 to 8 round segments"},
        {"{\"head\": [{\"diameter\": 100}]}", "head[0]: \"diameter\" and \"length\" are required"},
        {"{\"head\": [{\"diameter\": -1, \"length\": 5}]}", "head[0].diameter: expected"},
        {"{\"components\": [{\"model\": \"t.hf\"}]}", "are required"},
        {"{\"components\": {}}", "components: expected an array"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        fm_check_machine m;
        fm_error err;
        fm_error_clear(&err);
        CHECK(load_text(cases[i].text, &m, &err) == FM_ERR_INPUT);
        CHECK_STR_CONTAINS(err.message, cases[i].want);
        CHECK(m.chain.rotary_count == 0 && !m.chain.tcp);
    }
}

int main(void)
{
    check_trunnion();
    check_errors();
    printf("%d checks, %d failures\n", fm_test_checks, fm_test_failures);
    return fm_test_failures ? 1 : 0;
}
