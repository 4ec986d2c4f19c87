/* test_mtc_agent.c: the agent over a fake service whose snapshot the test
 * sets. Every document kind (probe, current, sample, assets, errors, a
 * streamed part) is validated with xmllint against the MTConnect 2.7
 * schemas (../shared/mtconnect/schemas) and read back with libxml2's XPath:
 * the values, sequence numbers and buffer bounds are those the test's own
 * sequence of snapshots implies. */
#include <libxml/parser.h>
#include <libxml/xpath.h>
#include <libxml/xpathInternals.h>
#include <math.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "protocols/mtconnect/mtconnect.h"
#include "test.h"

static fm_mtc_snapshot g_snap;
static fm_mtc_tool g_tools[2];
static int g_tool_count;
static const char *g_data;
static int g_validated;

static void fake_snapshot(void *ctx, fm_mtc_snapshot *out)
{
    (void)ctx;
    *out = g_snap;
}

static int fake_tools(void *ctx, fm_mtc_tool *out, int cap)
{
    (void)ctx;
    int n = g_tool_count < cap ? g_tool_count : cap;
    memcpy(out, g_tools, sizeof *out * (size_t)n);
    return n;
}

/* xmllint --schema SCHEMA on the document: 1 when it validates. */
static int validates(const char *doc, size_t size, const char *schema)
{
    char file[] = "/tmp/fm_mtc_XXXXXX";
    int fd = mkstemp(file);
    if (fd < 0) return 0;
    int ok = write(fd, doc, size) == (ssize_t)size;
    close(fd);
    char cmd[2048];
    snprintf(cmd, sizeof cmd, "xmllint --noout --schema %s/schemas/%s %s 2>/tmp/fm_mtc_xmllint.err",
             g_data, schema, file);
    ok = ok && system(cmd) == 0;
    if (!ok) {
        fprintf(stderr, "xmllint refused a document (%s):\n%.*s\n", schema, (int)(size > 3000 ? 3000 : size),
                doc);
        system("cat /tmp/fm_mtc_xmllint.err >&2");
    }
    unlink(file);
    g_validated++;
    return ok;
}

typedef struct parsed {
    xmlDocPtr doc;
    xmlXPathContextPtr xp;
} parsed;

static int parse(parsed *p, const fm_mtc_reply *r, const char *ns)
{
    p->xp = NULL;
    p->doc = r->body ? xmlReadMemory(r->body, (int)r->size, "reply.xml", NULL, XML_PARSE_NONET) : NULL;
    if (!p->doc) return 0;
    p->xp = xmlXPathNewContext(p->doc);
    xmlXPathRegisterNs(p->xp, (const xmlChar *)"m", (const xmlChar *)ns);
    return 1;
}

static void unparse(parsed *p)
{
    if (p->xp) xmlXPathFreeContext(p->xp);
    if (p->doc) xmlFreeDoc(p->doc);
    p->xp = NULL;
    p->doc = NULL;
}

static double number(parsed *p, const char *xpath)
{
    xmlXPathObjectPtr o = p->xp ? xmlXPathEvalExpression((const xmlChar *)xpath, p->xp) : NULL;
    double v = o ? xmlXPathCastToNumber(o) : NAN;
    xmlXPathFreeObject(o);
    return v;
}

static void string(parsed *p, const char *xpath, char *out, size_t cap)
{
    xmlXPathObjectPtr o = p->xp ? xmlXPathEvalExpression((const xmlChar *)xpath, p->xp) : NULL;
    xmlChar *s = o ? xmlXPathCastToString(o) : NULL;
    snprintf(out, cap, "%s", s ? (const char *)s : "");
    xmlFree(s);
    xmlXPathFreeObject(o);
}

static void request(fm_mtc_agent *a, const char *path, const char *query, fm_mtc_reply *r)
{
    fm_error err;
    CHECK(fm_mtc_agent_request(a, path, query, r, &err) == FM_OK);
    CHECK(r->body != NULL || r->stream != NULL);
}

static void blank(void)
{
    memset(&g_snap, 0, sizeof g_snap);
    g_snap.available = 1;
    g_snap.execution = FM_MTC_EXEC_READY;
    g_snap.line = -1;
    g_snap.tool = -1;
    for (int i = 0; i < 3; i++) g_snap.position[i] = NAN;
    for (int i = 0; i < 3; i++) g_snap.rotary[i] = NAN;
    g_snap.spindle_rpm = g_snap.removed_mm3 = g_snap.stock_mm3 = NAN;
    g_snap.progress_percent = g_snap.uncertain_voxels = NAN;
}

#define NS_S "urn:mtconnect.org:MTConnectStreams:2.7"

int main(int argc, char **argv)
{
    g_data = argc > 1 ? argv[1] : "../../shared/mtconnect";
    char probe_path[1100];
    snprintf(probe_path, sizeof probe_path, "%s/schemas/MTConnectStreams_2.7_1.0.xsd", g_data);
    if (access(probe_path, R_OK) != 0)
        return test_skip("the MTConnect schemas are missing (../shared/mtconnect/schemas; cmake "
                         "-DFM_MTCONNECT_DATA=...)");
    if (system("xmllint --version >/dev/null 2>&1") != 0)
        return test_skip("xmllint is missing (Debian package libxml2-utils)");

    blank();
    fm_mtc_config cfg;
    fm_mtc_config_default(&cfg);
    cfg.buffer_size = 64;
    cfg.instance_id = 77;
    cfg.device.rotary_count = 2;
    cfg.device.rotary[0] = 'A';
    cfg.device.rotary[1] = 'C';
    fm_mtc_service svc = {NULL, fake_snapshot, fake_tools};
    fm_mtc_agent *a = NULL;
    fm_error err;
    CHECK(fm_mtc_agent_new(&cfg, &svc, &a, &err) == FM_OK);
    if (!a) return test_summary("mtconnect_agent");

    /* probe: the device model. */
    fm_mtc_reply r;
    request(a, "probe", NULL, &r);
    CHECK(r.status == 200);
    CHECK(validates(r.body, r.size, "MTConnectDevices_2.7_1.0.xsd"));
    parsed p;
    CHECK(parse(&p, &r, "urn:mtconnect.org:MTConnectDevices:2.7"));
    CHECK(number(&p, "count(//m:Linear)") == 3);
    CHECK(number(&p, "count(//m:Rotary[@name='A' or @name='C'])") == 2);
    CHECK(number(&p, "count(//m:Rotary[@name='B'])") == 0);
    CHECK(number(&p, "count(//m:Controller/m:Components/m:Path)") == 1);
    CHECK(number(&p, "count(//m:DataItem[@units='CUBIC_MILLIMETER'])") == 2);
    CHECK(number(&p, "count(//m:DataItem[@type='POSITION'][@units='MILLIMETER'])") == 3);
    CHECK(number(&p, "count(//m:DataItem[@type='ANGLE'][@units='DEGREE'])") == 2);
    CHECK(number(&p, "/m:MTConnectDevices/m:Header/@instanceId") == 77);
    int items = (int)number(&p, "count(//m:DataItem)");
    unparse(&p);
    free(r.body);

    /* The first items observations are each data item's UNAVAILABLE; the
     * first update (when made) turned avail, exec and the conditions. */
    uint64_t first, next;
    fm_mtc_agent_sequences(a, &first, &next);
    CHECK(first == 1);
    /* avail AVAILABLE, exec READY, system NORMAL, motion NORMAL. */
    CHECK(next == (uint64_t)items + 1 + 4);

    /* A position: three Position values, the path position, the line and
     * the tool (and its asset id), the execution: 8 observations. */
    g_snap.position[0] = 1.5;
    g_snap.position[1] = -2.25;
    g_snap.position[2] = 3.0;
    g_snap.line = 12;
    g_snap.tool = 3;
    g_snap.execution = FM_MTC_EXEC_ACTIVE;
    fm_mtc_agent_update(a);
    uint64_t next2;
    fm_mtc_agent_sequences(a, &first, &next2);
    CHECK(next2 == next + 8);
    fm_mtc_agent_update(a); /* nothing changed: nothing added */
    fm_mtc_agent_sequences(a, &first, &next);
    CHECK(next == next2);

    request(a, "current", NULL, &r);
    CHECK(r.status == 200);
    CHECK(validates(r.body, r.size, "MTConnectStreams_2.7_1.0.xsd"));
    CHECK(parse(&p, &r, NS_S));
    CHECK(number(&p, "//m:Position[@dataItemId='Xpos']") == 1.5);
    CHECK(number(&p, "//m:Position[@dataItemId='Ypos']") == -2.25);
    CHECK(number(&p, "//m:LineNumber") == 12);
    CHECK(number(&p, "//m:ToolNumber") == 3);
    char text[256];
    string(&p, "//m:Execution", text, sizeof text);
    CHECK(!strcmp(text, "ACTIVE"));
    string(&p, "//m:Angle[@dataItemId='Apos']", text, sizeof text);
    CHECK(!strcmp(text, "UNAVAILABLE"));
    CHECK(number(&p, "//m:Header/@nextSequence") == (double)next);
    CHECK(number(&p, "//m:Header/@lastSequence") == (double)next - 1);
    CHECK(number(&p, "//m:Header/@firstSequence") == 1);
    CHECK(number(&p, "count(//m:ComponentStream[@component='Linear'])") == 3);
    unparse(&p);
    free(r.body);

    /* path: the subset. */
    request(a, "current", "path=//Linear[@name=%22X%22]", &r);
    CHECK(r.status == 200 && parse(&p, &r, NS_S));
    CHECK(number(&p, "count(//m:Samples/*|//m:Events/*|//m:Condition/*)") == 1);
    CHECK(number(&p, "//m:Position[@dataItemId='Xpos']") == 1.5);
    unparse(&p);
    free(r.body);
    request(a, "current", "path=//DataItem[@type=\"POSITION\"]|//Path//DataItem[@category='CONDITION']", &r);
    CHECK(r.status == 200 && parse(&p, &r, NS_S));
    CHECK(number(&p, "count(//m:Position)") == 3);
    CHECK(number(&p, "count(//m:Condition/*)") == 1);
    unparse(&p);
    free(r.body);

    /* sample from a sequence: count observations in order. */
    char q[128];
    snprintf(q, sizeof q, "from=%llu&count=5", (unsigned long long)(next - 8));
    request(a, "sample", q, &r);
    CHECK(r.status == 200);
    CHECK(validates(r.body, r.size, "MTConnectStreams_2.7_1.0.xsd"));
    CHECK(parse(&p, &r, NS_S));
    CHECK(number(&p, "count(//*[@sequence])") == 5);
    CHECK(number(&p, "//m:Header/@nextSequence") == (double)(next - 3));
    CHECK(number(&p, "sum(//*[@sequence]/@sequence)") == 5.0 * (double)(next - 8) + 10.0);
    unparse(&p);
    free(r.body);

    /* A collision at line 12 is a FAULT with the line as its native code;
     * a second finding a WARNING; then both gone: NORMAL. */
    g_snap.finding_count = 2;
    g_snap.findings[0].level = FM_MTC_FAULT;
    g_snap.findings[0].line = 12;
    snprintf(g_snap.findings[0].text, sizeof g_snap.findings[0].text, "holder collision, 0.8 mm deep");
    g_snap.findings[1].level = FM_MTC_WARNING;
    g_snap.findings[1].line = 30;
    snprintf(g_snap.findings[1].text, sizeof g_snap.findings[1].text, "rapid into stock");
    fm_mtc_agent_update(a);
    request(a, "current", "path=//Path", &r);
    CHECK(validates(r.body, r.size, "MTConnectStreams_2.7_1.0.xsd"));
    CHECK(parse(&p, &r, NS_S));
    CHECK(number(&p, "//m:Fault[@type='MOTION_PROGRAM']/@nativeCode") == 12);
    CHECK(number(&p, "//m:Warning[@type='MOTION_PROGRAM']/@nativeCode") == 30);
    string(&p, "//m:Fault", text, sizeof text);
    CHECK(!strcmp(text, "holder collision, 0.8 mm deep"));
    unparse(&p);
    free(r.body);
    g_snap.finding_count = 0;
    fm_mtc_agent_update(a);
    request(a, "current", "path=//DataItem[@id='motion']", &r);
    CHECK(parse(&p, &r, NS_S));
    CHECK(number(&p, "count(//m:Normal[@type='MOTION_PROGRAM'])") == 1);
    CHECK(number(&p, "count(//m:Fault)") == 0);
    unparse(&p);
    free(r.body);

    /* The buffer is bounded: 100 new X values; then 64 kept, the first
     * sequence 64 before the next; "at" rebuilds X as it was. Each update
     * adds two observations (Xpos and the path position). */
    fm_mtc_agent_sequences(a, &first, &next);
    uint64_t x_seq_first = next; /* X = 100 is at this sequence */
    for (int k = 0; k < 100; k++) {
        g_snap.position[0] = 100 + k;
        fm_mtc_agent_update(a);
    }
    fm_mtc_agent_sequences(a, &first, &next);
    CHECK(next == x_seq_first + 200);
    CHECK(next - first == 64);
    /* X = 100 + k is at x_seq_first + 2k: at that sequence, current says so. */
    uint64_t at = next - 20; /* k = 90 */
    snprintf(q, sizeof q, "at=%llu", (unsigned long long)at);
    request(a, "current", q, &r);
    CHECK(r.status == 200);
    CHECK(validates(r.body, r.size, "MTConnectStreams_2.7_1.0.xsd"));
    CHECK(parse(&p, &r, NS_S));
    CHECK(number(&p, "//m:Position[@dataItemId='Xpos']") == 100.0 + (double)(at - x_seq_first) / 2.0);
    /* What was set before the window is kept: the line and the tool. */
    CHECK(number(&p, "//m:LineNumber") == 12);
    unparse(&p);
    free(r.body);

    /* Errors, each a valid MTConnectError with its HTTP status. */
    struct {
        const char *path, *query, *element;
        int status;
    } bad[] = {
        {"sample", "from=1", "OutOfRange", 400},
        {"current", "at=999999", "QueryError", 400},
        {"sample", "count=100000", "OutOfRange", 400},
        {"sample", "from=abc", "QueryError", 400},
        {"sample", "bogus=1", "InvalidRequest", 400},
        {"current", "path=//Linear[", "InvalidXPath", 400},
        {"current", "path=//Nothing", "InvalidXPath", 400},
        {"elsewhere/current", NULL, "NoDevice", 404},
        {"nothing", NULL, "InvalidURI", 400},
        {"asset/T99", NULL, "AssetNotFound", 404},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        request(a, bad[i].path, bad[i].query, &r);
        CHECK(r.status == bad[i].status);
        CHECK(validates(r.body, r.size, "MTConnectError_2.7_1.0.xsd"));
        char want[64];
        snprintf(want, sizeof want, "<%s>", bad[i].element);
        CHECK_STR_CONTAINS(r.body, want);
        free(r.body);
    }

    /* Assets: a CuttingTool per tool with its measures. */
    g_tool_count = 2;
    g_tools[0] = (fm_mtc_tool){1, "6 mm flat end mill", 6.0, 20.0, 60.0, NAN, 6.0};
    g_tools[1] = (fm_mtc_tool){4, "10 mm bull nose", 10.0, 25.0, 75.0, 1.0, 10.0};
    request(a, "assets", NULL, &r);
    CHECK(r.status == 200);
    CHECK(validates(r.body, r.size, "MTConnectAssets_2.7_1.0.xsd"));
    CHECK(parse(&p, &r, "urn:mtconnect.org:MTConnectAssets:2.7"));
    CHECK(number(&p, "count(//m:CuttingTool)") == 2);
    CHECK(number(&p, "//m:CuttingTool[@assetId='T4']//m:CuttingDiameterMax") == 10.0);
    CHECK(number(&p, "//m:CuttingTool[@assetId='T4']//m:CornerRadius") == 1.0);
    CHECK(number(&p, "//m:CuttingTool[@assetId='T1']//m:OverallToolLength") == 60.0);
    CHECK(number(&p, "//m:Header/@assetCount") == 2);
    unparse(&p);
    free(r.body);
    request(a, "asset/T1", NULL, &r);
    CHECK(r.status == 200 && strstr(r.body, "assetId=\"T1\"") && !strstr(r.body, "T4"));
    free(r.body);

    /* A streamed sample: a part with its own headers and a valid document;
     * with nothing new, the heartbeat's empty document after 10+ ms. */
    request(a, "sample", "interval=0&heartbeat=50&count=3", &r);
    CHECK(r.stream != NULL);
    CHECK_STR_CONTAINS(r.content_type, "multipart/x-mixed-replace;boundary=");
    if (r.stream) {
        g_snap.position[1] = 42.0;
        fm_mtc_agent_update(a);
        char buf[65536];
        long n = 0, got;
        while ((got = fm_mtc_stream_read(r.stream, buf + n, sizeof buf - 1 - (size_t)n, 500)) > 0) {
            n += got;
            buf[n] = '\0';
            if (strstr(buf, "</MTConnectStreams>") && !strcmp(buf + n - 2, "\r\n")) break;
        }
        buf[n] = '\0';
        const char *boundary = strstr(r.content_type, "boundary=") + 9;
        CHECK(!strncmp(buf, "--", 2) && !strncmp(buf + 2, boundary, strlen(boundary)));
        const char *len = strstr(buf, "Content-length: ");
        const char *body = strstr(buf, "\r\n\r\n");
        CHECK(len && body);
        if (len && body) {
            body += 4;
            size_t size = (size_t)atol(len + 16);
            CHECK(body + size + 2 == buf + n);
            CHECK(validates(body, size, "MTConnectStreams_2.7_1.0.xsd"));
            CHECK(strstr(body, ">42.0000</Position>") != NULL);
        }
        fm_mtc_stream_free(r.stream);
    }

    fm_mtc_agent_free(a);
    printf("%d documents validated with xmllint\n", g_validated);
    return test_summary("mtconnect_agent");
}
