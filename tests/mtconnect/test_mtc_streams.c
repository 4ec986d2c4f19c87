/* test_mtc_streams.c: the reader of an agent's Streams documents against
 * hand-written documents: observations in sequence order (not document
 * order) with their names, ids, values and timestamps, nextSequence, and
 * the refusals (not XML with its line, another document, over the size
 * bound) with nothing handed over. */
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "protocols/mtconnect/mtconnect.h"
#include "test.h"

typedef struct got {
    int n;
    uint64_t seq[8];
    char name[8][32], id[8][32], value[8][32];
    double time[8];
} got;

static void take(void *ctx, const fm_mtc_observation *o)
{
    got *g = ctx;
    if (g->n >= 8) return;
    g->seq[g->n] = o->sequence;
    snprintf(g->name[g->n], sizeof g->name[0], "%s", o->name ? o->name : "(none)");
    snprintf(g->id[g->n], sizeof g->id[0], "%s", o->data_item_id ? o->data_item_id : "(none)");
    snprintf(g->value[g->n], sizeof g->value[0], "%s", o->value);
    g->time[g->n] = o->time;
    g->n++;
}

static const char DOC[] =
    "<?xml version=\"1.0\"?>\n"
    "<MTConnectStreams xmlns=\"urn:mtconnect.org:MTConnectStreams:2.0\">\n"
    "<Header nextSequence=\"12\" firstSequence=\"1\" lastSequence=\"11\"/>\n"
    "<Streams><DeviceStream name=\"m\"><ComponentStream component=\"Path\">\n"
    "<Events><Line dataItemId=\"ln\" name=\"line\" sequence=\"9\" "
    "timestamp=\"1970-01-02T00:00:01.5Z\">42</Line>\n"
    "<Execution dataItemId=\"ex\" sequence=\"3\">ACTIVE</Execution></Events>\n"
    "<Samples><Position dataItemId=\"xp\" name=\"Xpos\" sequence=\"5\" "
    "timestamp=\"1970-01-01T00:00:10+01:00\">-12.5</Position>\n"
    "<Position dataItemId=\"bad\" sequence=\"5x\">1</Position></Samples>\n"
    "</ComponentStream></DeviceStream></Streams></MTConnectStreams>\n";

static void test_document(void)
{
    got g = {0};
    uint64_t next = 0;
    char why[256] = "";
    CHECK(fm_mtc_streams_read(DOC, strlen(DOC), take, &g, &next, why, sizeof why) == 0);
    CHECK(next == 12);
    /* sequence order 3, 5, 9; "5x" is not a sequence number */
    CHECK(g.n == 3);
    if (g.n != 3) return;
    CHECK(g.seq[0] == 3 && !strcmp(g.id[0], "ex") && !strcmp(g.name[0], "(none)") &&
          !strcmp(g.value[0], "ACTIVE") && isnan(g.time[0]));
    CHECK(g.seq[1] == 5 && !strcmp(g.name[1], "Xpos") && !strcmp(g.value[1], "-12.5"));
    CHECK_NEAR(g.time[1], 10.0 - 3600.0, 1e-9); /* 00:00:10 at +01:00 */
    CHECK(g.seq[2] == 9 && !strcmp(g.name[2], "line") && !strcmp(g.id[2], "ln") &&
          !strcmp(g.value[2], "42"));
    CHECK_NEAR(g.time[2], 86401.5, 1e-9);
}

static void test_refusals(void)
{
    got g = {0};
    uint64_t next = 77;
    char why[256] = "";
    const char broken[] = "<MTConnectStreams>\n<Header nextSequence=\"3\"/>\n<Streams>\n</Stream>";
    CHECK(fm_mtc_streams_read(broken, strlen(broken), take, &g, &next, why, sizeof why) == -1);
    printf("not XML: %s\n", why);
    CHECK(strstr(why, "not XML") && strstr(why, "line 4"));
    CHECK(g.n == 0 && next == 77);

    const char error[] = "<MTConnectError><Errors><Error errorCode=\"OUT_OF_RANGE\">x</Error>"
                         "</Errors></MTConnectError>";
    CHECK(fm_mtc_streams_read(error, strlen(error), take, &g, &next, why, sizeof why) == -1);
    CHECK(strstr(why, "MTConnectError") != NULL);
    CHECK(g.n == 0 && next == 77);

    CHECK(fm_mtc_streams_read(DOC, FM_MTC_STREAMS_MAX + 1, take, &g, &next, why, sizeof why) == -1);
    CHECK(strstr(why, "over") != NULL && g.n == 0);

    /* an empty Streams: no observation, the header read */
    const char empty[] = "<MTConnectStreams><Header nextSequence=\"18446744073709551615\"/>"
                         "<Streams/></MTConnectStreams>";
    CHECK(fm_mtc_streams_read(empty, strlen(empty), take, &g, &next, why, sizeof why) == 0);
    CHECK(g.n == 0 && next == UINT64_MAX);
    /* one past uint64_t is no number: nextSequence left as it was */
    const char over[] = "<MTConnectStreams><Header nextSequence=\"18446744073709551616\"/>"
                        "</MTConnectStreams>";
    next = 5;
    CHECK(fm_mtc_streams_read(over, strlen(over), take, &g, &next, why, sizeof why) == 0);
    CHECK(next == 5);
}

int main(void)
{
    test_document();
    test_refusals();
    return test_summary("mtconnect_streams");
}
