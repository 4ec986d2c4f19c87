/* test_live_map.c: the live_map and live_source settings of live mode from
 * MTConnect (daemon/server/live_source.c): what they accept and how they
 * refuse. */
#include <string.h>

#include "live_source.h"
#include "test.h"

int main(void)
{
    fm_live_map m;
    char msg[256];
    CHECK(fm_live_map_parse("X=X1actw, Z=Z1actw,tool=p1CurrentTool", &m, msg, sizeof msg) == 0);
    CHECK(!strcmp(m.name[0], "X1actw") && !m.name[1][0] && !strcmp(m.name[2], "Z1actw"));
    CHECK(!strcmp(m.name[FM_LIVE_MAP_TOOL], "p1CurrentTool"));
    CHECK(fm_live_map_parse("x=Xpos,y=Ypos,z=Zpos", &m, msg, sizeof msg) == 0);
    CHECK(!strcmp(m.name[1], "Ypos"));
    /* The line, the spindle speed and the rotary axes map too; each key
     * once. */
    CHECK(fm_live_map_parse("X=a,line=p1linenumber,S=Srpm,C=Cpos,A=Apos", &m, msg, sizeof msg) == 0);
    CHECK(!strcmp(m.name[FM_LIVE_MAP_LINE], "p1linenumber") && !strcmp(m.name[FM_LIVE_MAP_SPINDLE], "Srpm"));
    CHECK(!strcmp(m.name[3], "Apos") && !m.name[4][0] && !strcmp(m.name[5], "Cpos"));
    /* A rotary axis must be one of the live machine's (an AC trunnion: A
     * and C, bits 1 << 0 and 1 << 2). */
    CHECK(fm_live_map_check_rotary(&m, 1 | 4, "ac.json", msg, sizeof msg) == 0);
    CHECK(fm_live_map_check_rotary(&m, 1, "a.json", msg, sizeof msg) != 0);
    CHECK_STR_CONTAINS(msg, "maps C, which the machine file a.json has no rotary axis for");
    CHECK(fm_live_map_check_rotary(&m, 0, NULL, msg, sizeof msg) != 0);
    CHECK_STR_CONTAINS(msg, "rotary axes need live_machine");
    CHECK(fm_live_map_parse("X=a,line=b", &m, msg, sizeof msg) == 0);
    CHECK(fm_live_map_check_rotary(&m, 0, NULL, msg, sizeof msg) == 0);
    CHECK(fm_live_map_parse("X=a,x=b", &m, msg, sizeof msg) != 0);
    CHECK_STR_CONTAINS(msg, "X is mapped twice");
    CHECK(fm_live_map_parse("X=a,U=u", &m, msg, sizeof msg) != 0);
    CHECK_STR_CONTAINS(msg, "U cannot be mapped");
    CHECK(fm_live_map_parse("tool=T", &m, msg, sizeof msg) != 0);
    CHECK_STR_CONTAINS(msg, "at least one of X, Y, Z");
    CHECK(fm_live_map_parse("X", &m, msg, sizeof msg) != 0);
    CHECK(fm_live_map_parse("X=", &m, msg, sizeof msg) != 0);
    CHECK(fm_live_map_parse("W=w", &m, msg, sizeof msg) != 0);
    CHECK(fm_live_source_check("shdr://127.0.0.1:7878", msg, sizeof msg) == 0);
    CHECK(fm_live_source_check("mtconnect://agent.local:5000/OKUMA", msg, sizeof msg) == 0);
    CHECK(fm_live_source_check("mtconnect://10.0.0.2:8470/mtconnect/frepmill", msg, sizeof msg) == 0);
    CHECK(fm_live_source_check("shdr://host", msg, sizeof msg) != 0);
    CHECK(fm_live_source_check("shdr://host:port", msg, sizeof msg) != 0);
    CHECK(fm_live_source_check("shdr://host:7878/dev", msg, sizeof msg) != 0);
    CHECK(fm_live_source_check("http://host:80", msg, sizeof msg) != 0);
    return test_summary("live_map");
}
