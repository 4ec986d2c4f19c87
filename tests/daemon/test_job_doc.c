/* test_job_doc.c: unit tests of the job document (daemon/runner/job_doc.h)
 * and the stock-spec parser: canonical form and defaults, every refusal
 * with its reason (the API code of docs/api.md; HTTP's statuses for them
 * are tested in tests/http) and fm_status, line and column
 * of syntax errors, the network rules (files, HyperFun tools, live
 * programs), the run spec a document makes (rapid rate from the options,
 * the machine or the default), base64 (RFC 4648 test vectors) and stock
 * shapes with values worked out by hand. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
#include <unistd.h>

#include "runner/job_doc.h"
#include "runner/stock_spec.h"
#include "test.h"

static const char *TOOLS = "{\"units\": \"mm\", \"tools\": [{\"number\": 1, \"shape\": \"flat\", "
                           "\"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

static fm_job_doc *parse_with(const char *text, const fm_job_doc_rules *rules, fm_error *err)
{
    fm_error_clear(err);
    fm_job_doc *doc = NULL;
    if (fm_job_doc_parse(text, strlen(text), rules, &doc, err) != FM_OK) return NULL;
    return doc;
}

static fm_job_doc *parse(const char *text, fm_error *err)
{
    return parse_with(text, NULL, err);
}

static void test_job_ok(void)
{
    char text[1024];
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-30,100,60,0\", \"tools\": %s, \"program\": {\"gcode\": \"G0 X1\"}}",
             TOOLS);
    fm_error err;
    fm_job_doc *doc = parse(text, &err);
    CHECK(doc != NULL);
    if (!doc) return;
    /* Defaults filled in: voxel 0.1 (the CLI's), empty fixtures and options. */
    CHECK_NEAR(json_number_value(json_object_get(doc->json, "voxel")), 0.1, 0);
    CHECK(json_array_size(json_object_get(doc->json, "fixtures")) == 0);
    CHECK(json_object_size(json_object_get(doc->json, "options")) == 0);
    CHECK(!strcmp(json_string_value(json_object_get(doc->json, "stock")), "box:0,0,-30,100,60,0"));
    /* The run spec. */
    CHECK_NEAR(doc->spec.stock.voxel_mm, 0.1, 0);
    CHECK(doc->spec.program_kind == FM_PROGRAM_GCODE);
    CHECK(doc->spec.program_length == 5 && !memcmp(doc->spec.program_text, "G0 X1", 5));
    CHECK(doc->spec.tools == &doc->tools && doc->tools.count == 1);
    CHECK(doc->spec.stock_spec && !strcmp(doc->spec.stock_spec, "box:0,0,-30,100,60,0"));
    CHECK(doc->spec.check == &doc->check && doc->color_tool == 1);
    CHECK_NEAR(doc->spec.rapid_rate, 5000, 0);
    /* The canonical form parses to itself. */
    char *again = json_dumps(doc->json, JSON_COMPACT);
    fm_job_doc *doc2 = parse(again, &err);
    CHECK(doc2 && json_equal(doc->json, doc2->json));
    free(again);
    fm_job_doc_free(doc2);
    fm_job_doc_free(doc);
    /* options.color: "tool" and "none" are the two mesh colourings */
    const char *colors[2] = {"tool", "none"};
    for (int i = 0; i < 2; i++) {
        snprintf(text, sizeof text,
                 "{\"stock\": \"box:0,0,-30,100,60,0\", \"tools\": %s, \"program\": {\"gcode\": "
                 "\"G0 X1\"}, \"options\": {\"color\": \"%s\"}}",
                 TOOLS, colors[i]);
        doc = parse(text, &err);
        CHECK(doc != NULL && doc->color_tool == (i == 0));
        fm_job_doc_free(doc);
    }
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-30,100,60,0\", \"tools\": %s, \"program\": {\"gcode\": "
             "\"G0 X1\"}, \"options\": {\"color\": \"rainbow\"}}",
             TOOLS);
    doc = parse(text, &err);
    CHECK(doc == NULL && err.code == FM_ERR_INPUT && !strcmp(err.reason, "bad_value"));
    CHECK_STR_CONTAINS(err.message, "options.color must be \"tool\"");
    fm_job_doc_free(doc);
}

/* The refusal's fm_status (400s are FM_ERR_INPUT, 413s FM_ERR_LIMIT in
 * docs/api.md) and reason. */
static void expect_error(const char *text, int status, const char *code)
{
    fm_error err;
    fm_job_doc *doc = parse(text, &err);
    fm_status want = status == 413 ? FM_ERR_LIMIT : FM_ERR_INPUT;
    CHECK(doc == NULL);
    CHECK(err.code == want);
    CHECK(!strcmp(err.reason, code));
    if (doc || err.code != want || strcmp(err.reason, code))
        fprintf(stderr, "  for %s: got %d %s (%s)\n", text, (int)err.code, err.reason, err.message);
    fm_job_doc_free(doc);
}

static void test_job_errors(void)
{
    char text[2048];
    expect_error("", 400, "bad_json");
    expect_error("[1, 2]", 400, "bad_job");
    expect_error("{\"stock\": \"box:0,0,0,1,1,1\"}", 400, "missing_key");
    snprintf(text, sizeof text, "{\"stock\": \"/etc/passwd\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_stock");
    snprintf(text, sizeof text, "{\"stock\": \"/srv/part.vdb\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_stock"); /* a file on the server */
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_stock"); /* five numbers: refused now, not when it runs */
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,-1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_stock"); /* empty x range */
    snprintf(text, sizeof text, "{\"stock\": \"cylinder:0,0,0,10,-2\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_stock");
    snprintf(text, sizeof text, "{\"stock\": {\"stl_base64\": \"@@@@\"}, \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_stock");
    snprintf(text, sizeof text, "{\"stock\": {\"hyperfun\": \"x\", \"stl_base64\": \"AAAA\"}, \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_stock");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"voxel\": 0, \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_value");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"voxel\": \"fine\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_type");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\", \"trajectory\": {}}}", TOOLS);
    expect_error(text, 400, "bad_program");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"basic\": \"10 PRINT\"}}", TOOLS);
    expect_error(text, 400, "unknown_key");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"options\": {\"band\": 1}}", TOOLS);
    expect_error(text, 400, "bad_value");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"options\": {\"band\": 2.5}}", TOOLS);
    expect_error(text, 400, "bad_type");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"options\": {\"color\": \"depth\"}}", TOOLS);
    expect_error(text, 400, "bad_value");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"options\": {\"color\": 1}}", TOOLS);
    expect_error(text, 400, "bad_value");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"fixtures\": [{\"stl\": \"x\"}]}", TOOLS);
    expect_error(text, 400, "bad_fixture");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"stock\": \"box:0,0,0,2,2,2\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_json"); /* duplicate key */
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": {\"units\": \"mm\", \"tools\": [{\"number\": 1}]}, \"program\": {\"gcode\": \"G0\"}}");
    expect_error(text, 400, "bad_tools");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": {\"units\": \"mm\", \"tools\": [{\"number\": 2, \"shape\": \"hyperfun\", \"file\": \"/etc/passwd\", \"diameter\": 6, \"flute_length\": 10, \"length\": 40}]}, \"program\": {\"gcode\": \"G0\"}}");
    expect_error(text, 400, "bad_tools"); /* a file on the server */
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"options\": {\"check\": {\"clearence\": 1}}}", TOOLS);
    expect_error(text, 400, "unknown_key");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"options\": {\"check\": {\"tolerance\": -1}}}", TOOLS);
    expect_error(text, 400, "bad_value");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"machine\": {\"rapid_rate\": 100}, \"options\": {\"check\": {\"machine\": {\"rapid_rate\": 200}}}}", TOOLS);
    expect_error(text, 400, "bad_job"); /* the machine twice */
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"machine\": {\"rapid_rate\": -5}}", TOOLS);
    expect_error(text, 400, "bad_value");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"live\": {}}}", TOOLS);
    expect_error(text, 400, "bad_program"); /* live jobs are the daemon's own */

    /* 65 fixtures: one over the limit. */
    char *many = malloc(65 * 40 + 1024);
    if (many) {
        int n = snprintf(many, 1024, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"fixtures\": [", TOOLS);
        for (int i = 0; i < 65; i++)
            n += sprintf(many + n, "%s{\"hyperfun\": \"x\"}", i ? ", " : "");
        sprintf(many + n, "]}");
        expect_error(many, 413, "too_large");
        free(many);
    }

    /* Line and column of a syntax error: the '}' on line 3, column 12. */
    fm_error err;
    fm_job_doc *doc = parse("{\n  \"stock\": \"box:0,0,0,1,1,1\",\n  \"voxel\": }", &err);
    CHECK(doc == NULL && err.line == 3 && err.column == 12);
    if (err.line != 3 || err.column != 12) fprintf(stderr, "  line %d column %d\n", err.line, err.column);
}

/* The rapid rate a run takes: options.rapid_rate, else the machine's, else
 * 5000 mm/min; the same with the machine under options.check. */
static void test_rapid_rate(void)
{
    char text[1024];
    fm_error err;
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"machine\": {\"rapid_rate\": 12000}}", TOOLS);
    fm_job_doc *doc = parse(text, &err);
    CHECK(doc && doc->has_machine && doc->spec.rapid_rate == 12000);
    fm_job_doc_free(doc);
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"options\": {\"check\": {\"machine\": {\"rapid_rate\": 8000}}}}", TOOLS);
    doc = parse(text, &err);
    CHECK(doc && doc->has_machine && doc->spec.rapid_rate == 8000);
    fm_job_doc_free(doc);
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"machine\": {\"rapid_rate\": 12000}, \"options\": {\"rapid_rate\": 3000}}", TOOLS);
    doc = parse(text, &err);
    CHECK(doc && doc->spec.rapid_rate == 3000 && doc->check.options.machine.rapid_rate == 12000);
    /* the canonical form keeps the machine */
    CHECK(doc && json_is_object(json_object_get(doc->json, "machine")));
    fm_job_doc_free(doc);
}

static void test_rules_and_parts(void)
{
    char text[2048];
    fm_error err;
    /* The daemon's own documents may name files and be live. */
    const fm_job_doc_rules own = {.allow_files = 1, .allow_live = 1};
    snprintf(text, sizeof text, "{\"stock\": \"/srv/part.vdb\", \"tools\": %s, \"program\": {\"live\": {\"feed\": 600}}, \"options\": {\"check\": false}}", TOOLS);
    fm_job_doc *doc = parse_with(text, &own, &err);
    CHECK(doc && doc->spec.program_kind == FM_PROGRAM_LIVE && doc->live_feed == 600);
    CHECK(doc && !strcmp(doc->spec.stock_spec, "/srv/part.vdb") && !doc->spec.check);
    fm_job_doc_free(doc);
    /* An inline STL stock: 84 bytes of zeros are the smallest binary STL
     * (80-byte header, 0 triangles) = 112 base64 characters. */
    char b64[120];
    memset(b64, 'A', 112);
    b64[112] = '\0';
    snprintf(text, sizeof text,
             "{\"stock\": {\"stl_base64\": \"%s\"}, \"tools\": %s, \"program\": {\"trajectory\": "
             "{\"a\": 1}}, \"fixtures\": [{\"hyperfun\": \"my_model(x[3], a[1]) { my_model = 1; }\", "
             "\"name\": \"vise\"}]}",
             b64, TOOLS);
    doc = parse(text, &err);
    CHECK(doc != NULL);
    if (doc) {
        CHECK(doc->stock_model.is_stl && doc->stock_model.size == 84);
        CHECK(doc->spec.stock_spec == NULL); /* until written to a file */
        CHECK(doc->check.fixture_count == 1 && !doc->fixtures[0].is_stl);
        CHECK(!strcmp(doc->fixtures[0].name, "vise"));
        CHECK(doc->spec.program_kind == FM_PROGRAM_TRAJECTORY);
        CHECK(fm_job_doc_set_stock_file(doc, "/tmp/x/stock.stl", &err) == FM_OK);
        CHECK(fm_job_doc_set_fixture_file(doc, 0, "/tmp/x/fixture0.hf", &err) == FM_OK);
        CHECK(!strcmp(doc->spec.stock_spec, "/tmp/x/stock.stl"));
        CHECK(!strcmp(doc->check.fixtures[0], "/tmp/x/fixture0.hf"));
        CHECK(fm_job_doc_set_fixture_file(doc, 1, "/tmp/x/f1.hf", &err) != FM_OK);
    }
    fm_job_doc_free(doc);
    /* 83 bytes are too short for an STL. */
    memset(b64, 'A', 108);
    memcpy(b64 + 108, "AA==", 5); /* 81 + 2 bytes */
    snprintf(text, sizeof text, "{\"stock\": {\"stl_base64\": \"%s\"}, \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", b64, TOOLS);
    doc = parse(text, &err);
    CHECK(doc == NULL && !strcmp(err.reason, "bad_stock"));
}

/* A 100 x 60 x 30 mm box at 0.001 mm needs more than any budget: refused
 * with its reason before anything is built. */
static void test_memory(void)
{
    char text[1024];
    fm_error err;
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,-30,100,60,0\", \"voxel\": 0.001, \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    fm_job_doc *doc = parse(text, &err);
    CHECK(doc != NULL);
    if (!doc) return;
    CHECK(fm_job_doc_check_memory(doc, (size_t)1 << 30, &err) == FM_ERR_LIMIT &&
          !strcmp(err.reason, "memory_budget"));
    doc->spec.stock.voxel_mm = 1;
    CHECK(fm_job_doc_check_memory(doc, (size_t)1 << 30, &err) == FM_OK);
    fm_job_doc_free(doc);
}

static void test_stock_spec(void)
{
    fm_stock_spec s;
    fm_error err;
    CHECK(fm_stock_spec_parse("box:0,0,-30,100,60,0", &s, &err) == FM_OK);
    CHECK(s.shape == FM_STOCK_SHAPE_BOX && s.lo[2] == -30 && s.hi[0] == 100 && s.hi[1] == 60);
    /* 2 (100*60 + 60*30 + 100*30) */
    CHECK_NEAR(fm_stock_spec_projected_area(&s), 21600, 1e-9);
    CHECK(fm_stock_spec_parse("cylinder:5, 6, -10, 10, 4", &s, &err) == FM_OK);
    CHECK(s.shape == FM_STOCK_SHAPE_CYLINDER && s.radius == 4 && s.axis[0] == 5 && s.axis[1] == 6);
    CHECK(s.lo[0] == 1 && s.hi[0] == 9 && s.lo[1] == 2 && s.hi[1] == 10 && s.lo[2] == -10 && s.hi[2] == 10);
    /* caps 2 pi r^2 on z, the side 2 r h on each of x and y, twice */
    CHECK_NEAR(fm_stock_spec_projected_area(&s), 2 * FM_PI * 16 + 8 * 4 * 20, 1e-6);
    CHECK(fm_stock_spec_parse("part.STL", &s, &err) == FM_OK && s.shape == FM_STOCK_SHAPE_STL);
    CHECK(fm_stock_spec_projected_area(&s) < 0);
    CHECK(fm_stock_spec_parse("model.hf", &s, &err) == FM_OK && s.shape == FM_STOCK_SHAPE_HYPERFUN);
    CHECK(fm_stock_spec_parse("snap.vdb", &s, &err) == FM_OK && s.shape == FM_STOCK_SHAPE_SNAPSHOT);
    CHECK(fm_stock_spec_parse("box:1,2,3,4,5", &s, &err) == FM_ERR_INPUT);
    CHECK(fm_stock_spec_parse("box:1,2,3,4,5,6,7", &s, &err) == FM_ERR_INPUT);
    CHECK(fm_stock_spec_parse("box:0,0,0,1,1,nan", &s, &err) == FM_ERR_INPUT);
    CHECK(fm_stock_spec_parse("sphere:0,0,0,1", &s, &err) == FM_ERR_INPUT);
    CHECK(fm_stock_spec_parse("", &s, &err) == FM_ERR_INPUT);
}

static void test_base64(void)
{
    /* RFC 4648 section 10 test vectors. */
    static const char *const plain[] = {"", "f", "fo", "foo", "foob", "fooba", "foobar"};
    static const char *const coded[] = {"", "Zg==", "Zm8=", "Zm9v", "Zm9vYg==", "Zm9vYmE=", "Zm9vYmFy"};
    for (int i = 0; i < 7; i++) {
        uint8_t *out;
        size_t n;
        CHECK(fm_base64_decode(coded[i], strlen(coded[i]), &out, &n) == 0);
        CHECK(n == strlen(plain[i]) && (n == 0 || !memcmp(out, plain[i], n)));
        free(out);
    }
    uint8_t *out;
    size_t n;
    CHECK(fm_base64_decode("Zm9v!", 5, &out, &n) == -1);
    CHECK(fm_base64_decode("Zg==Zg==", 8, &out, &n) == -1); /* data after padding */
    CHECK(fm_base64_decode("Zh==", 4, &out, &n) == -1);     /* non-zero pad bits */
}

/* options.dialect, subroutine_path, calculator_input; the server's
 * defaults (rules) where the job gives none; the machine's reference
 * points. */
static void test_gcode_options(void)
{
    char text[1024];
    fm_error err;
    const char *head = "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}";
    char fmt[256];
    /* no dialect anywhere: the runner's default (NULL) */
    snprintf(fmt, sizeof fmt, "%s}", head);
    snprintf(text, sizeof text, fmt, TOOLS);
    fm_job_doc *doc = parse(text, &err);
    CHECK(doc && doc->spec.dialect == NULL && doc->spec.subroutine_path == NULL &&
          doc->spec.calculator_input == 0);
    fm_job_doc_free(doc);
    /* the server's defaults apply... */
    const fm_job_doc_rules server = {.dialect = "FANUC", .subroutine_path = "/srv/subs:/srv/more"};
    doc = parse_with(text, &server, &err);
    CHECK(doc && doc->spec.dialect && !strcmp(doc->spec.dialect, "fanuc"));
    CHECK(doc && doc->spec.subroutine_path &&
          !strcmp(doc->spec.subroutine_path, "/srv/subs:/srv/more"));
    /* ...without entering the canonical form (the client's document) */
    CHECK(doc && json_object_size(json_object_get(doc->json, "options")) == 0);
    fm_job_doc_free(doc);
    /* ...unless the job gives its own dialect */
    snprintf(fmt, sizeof fmt, "%s, \"options\": {\"dialect\": \"linuxcnc\", \"calculator_input\": true}}", head);
    snprintf(text, sizeof text, fmt, TOOLS);
    doc = parse_with(text, &server, &err);
    CHECK(doc && !strcmp(doc->spec.dialect, "linuxcnc") && doc->spec.calculator_input == 1);
    CHECK(doc && !strcmp(doc->spec.subroutine_path, "/srv/subs:/srv/more"));
    fm_job_doc_free(doc);
    /* bad values and types */
    const char *bad[][2] = {
        {"\"dialect\": \"haas\"", "bad_value"},
        {"\"dialect\": 2", "bad_type"},
        {"\"calculator_input\": 1", "bad_type"},
        {"\"subroutine_path\": \"\"", "bad_value"},
        {"\"subroutine_path\": [\"/srv\"]", "bad_type"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(fmt, sizeof fmt, "%s, \"options\": {%s}}", head, bad[i][0]);
        snprintf(text, sizeof text, fmt, TOOLS);
        expect_error(text, 400, bad[i][1]);
    }
    /* subroutine folders are files: refused over the network, the CLI's own
     * documents may name them */
    snprintf(fmt, sizeof fmt, "%s, \"options\": {\"subroutine_path\": \"/etc\"}}", head);
    snprintf(text, sizeof text, fmt, TOOLS);
    doc = parse(text, &err);
    CHECK(doc == NULL && !strcmp(err.reason, "bad_value"));
    CHECK_STR_CONTAINS(err.message, "options.subroutine_path names folders on the server");
    const fm_job_doc_rules own = {.allow_files = 1, .subroutine_path = "/srv/subs"};
    doc = parse_with(text, &own, &err);
    CHECK(doc && !strcmp(doc->spec.subroutine_path, "/etc"));
    fm_job_doc_free(doc);
    /* machine components are model files: refused over the network */
    snprintf(fmt, sizeof fmt, "%s, \"machine\": {\"components\": [{\"model\": \"vise.stl\", \"link\": \"table\"}]}}", head);
    snprintf(text, sizeof text, fmt, TOOLS);
    doc = parse(text, &err);
    CHECK(doc == NULL && !strcmp(err.reason, "bad_value"));
    CHECK_STR_CONTAINS(err.message, "machine.components name files on the server");
    doc = parse_with(text, &own, &err);
    CHECK(doc && doc->check.options.machine.component_count == 1);
    fm_job_doc_free(doc);
    /* the machine's reference points (G28, G30) reach the run spec */
    snprintf(fmt, sizeof fmt, "%s, \"machine\": {\"reference_points\": [[1, 2, 3], [4, 5, 6]]}}", head);
    snprintf(text, sizeof text, fmt, TOOLS);
    doc = parse(text, &err);
    CHECK(doc != NULL);
    if (doc) {
        const double want[2][3] = {{1, 2, 3}, {4, 5, 6}};
        for (int i = 0; i < 2; i++)
            for (int k = 0; k < 3; k++) CHECK_NEAR(doc->spec.reference_points[i][k], want[i][k], 0);
        CHECK_NEAR(doc->spec.reference_points[2][0], 0, 0);
        CHECK(doc->spec.machine == &doc->check.options.machine.chain);
    }
    fm_job_doc_free(doc);
}

/* "design", options.tolerance and options.stop_at (issue 16): the run
 * spec's design_path, tolerance_mm and stop_at_line; the design obeys the
 * stock's rules (inline over the network, files only for the daemon's own
 * documents). */
static void test_design(void)
{
    char text[2048];
    char b64[120];
    memset(b64, 'A', 112); /* 84 bytes: the smallest binary STL */
    b64[112] = '\0';
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,40,40,0\", \"tools\": %s, \"program\": {\"gcode\": \"G0 X1\"}, "
             "\"design\": {\"stl_base64\": \"%s\"}, \"options\": {\"tolerance\": 0.02, "
             "\"stop_at\": 12, \"sweep_evaluations\": 50}}",
             TOOLS, b64);
    fm_error err;
    fm_job_doc *doc = parse(text, &err);
    CHECK(doc != NULL);
    if (doc) {
        CHECK(doc->design_model.is_stl && doc->design_model.size == 84);
        CHECK(doc->spec.design_path == NULL); /* until written to a file */
        CHECK_NEAR(doc->spec.tolerance_mm, 0.02, 0);
        CHECK(doc->spec.stop_at_line == 12);
        CHECK(doc->spec.sweep_evaluations == 50);
        CHECK(json_object_get(doc->json, "design") != NULL);
        CHECK(fm_job_doc_set_design_file(doc, "/tmp/x/design.stl", &err) == FM_OK);
        CHECK(!strcmp(doc->spec.design_path, "/tmp/x/design.stl"));
        char *again = json_dumps(doc->json, JSON_COMPACT);
        fm_job_doc *doc2 = parse(again, &err);
        CHECK(doc2 && json_equal(doc->json, doc2->json) && doc2->design_model.size == 84 &&
              doc2->spec.sweep_evaluations == 50);
        free(again);
        fm_job_doc_free(doc2);
    }
    fm_job_doc_free(doc);
    /* a HyperFun design */
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,40,40,0\", \"tools\": %s, \"program\": {\"gcode\": \"G0 X1\"}, "
             "\"design\": {\"hyperfun\": \"my_model(x[3], a[1]) { my_model = 1; }\"}}",
             TOOLS);
    doc = parse(text, &err);
    CHECK(doc && !doc->design_model.is_stl && doc->spec.tolerance_mm == 0 &&
          doc->spec.stop_at_line == 0 && doc->spec.sweep_evaluations == 0);
    fm_job_doc_free(doc);
    /* a file: the daemon's own documents (the CLI) only */
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,40,40,0\", \"tools\": %s, \"program\": {\"gcode\": \"G0 X1\"}, "
             "\"design\": \"/srv/part.stl\"}",
             TOOLS);
    expect_error(text, 400, "bad_design");
    const fm_job_doc_rules own = {.allow_files = 1, .allow_live = 1};
    doc = parse_with(text, &own, &err);
    CHECK(doc && doc->spec.design_path && !strcmp(doc->spec.design_path, "/srv/part.stl"));
    fm_job_doc_free(doc);
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,40,40,0\", \"tools\": %s, \"program\": {\"gcode\": \"G0 X1\"}, "
             "\"design\": \"/srv/part.step\"}",
             TOOLS);
    doc = parse_with(text, &own, &err);
    CHECK(doc == NULL && !strcmp(err.reason, "bad_design"));
    CHECK_STR_CONTAINS(err.message, ".stl, .hf or .vdb");
    /* refusals */
    static const char *const bad[][2] = {
        {"\"design\": {\"stl_base64\": \"AAAA\"}", "bad_design"},      /* 3 bytes */
        {"\"design\": {\"obj\": \"v 0 0 0\"}", "bad_design"},
        {"\"design\": 5", "bad_design"},
        {"\"options\": {\"tolerance\": -0.1}", "bad_value"},
        {"\"options\": {\"tolerance\": 101}", "bad_value"},
        {"\"options\": {\"tolerance\": \"0.1\"}", "bad_type"},
        {"\"options\": {\"stop_at\": 0}", "bad_value"},
        {"\"options\": {\"stop_at\": 2.5}", "bad_type"},
        {"\"options\": {\"sweep_evaluations\": 0}", "bad_value"},
        {"\"options\": {\"sweep_evaluations\": 2e9}", "bad_value"},
        {"\"options\": {\"sweep_evaluations\": 10.5}", "bad_type"},
    };
    for (size_t i = 0; i < sizeof bad / sizeof bad[0]; i++) {
        snprintf(text, sizeof text,
                 "{\"stock\": \"box:0,0,-5,40,40,0\", \"tools\": %s, \"program\": {\"gcode\": "
                 "\"G0 X1\"}, %s}",
                 TOOLS, bad[i][0]);
        expect_error(text, 400, bad[i][1]);
    }
}

/* A file's whole contents, NUL-terminated (NULL when it cannot be read). */
static char *slurp(const char *path, size_t *size)
{
    char *buf;
    fm_error err;
    return fm_file_read(path, NULL, 4095, &buf, size, &err) == FM_OK ? buf : NULL;
}

static int writes_seen;
static fm_status counting_write(const char *dir, const char *name, const void *data, size_t size,
                                fm_error *err)
{
    writes_seen++;
    char path[1024];
    snprintf(path, sizeof path, "%s/%s", dir, name);
    FILE *f = fopen(path, "wb");
    if (!f) return fm_error_set(err, FM_ERR_IO, "cannot write %s", path);
    fwrite(data, 1, size, f);
    fclose(f);
    return FM_OK;
}

/* fm_job_doc_materialize: the stock, design and fixtures of a document
 * become files named by their kind, the run spec points at them, the bytes
 * are the document's (the STL decoded from base64), and a second call finds
 * them there and writes nothing. */
static void test_materialize(void)
{
    /* 84 bytes of binary STL (an empty mesh's header and count) in base64:
     * 84 zero bytes are 112 'A's. */
    char stl[113];
    memset(stl, 'A', 112);
    stl[112] = '\0';
    char text[2048];
    snprintf(text, sizeof text,
             "{\"stock\": {\"hyperfun\": \"my_model(x[3], a[1]) { my_model = 1 - x[1]*x[1]; }\"}, "
             "\"tools\": %s, \"program\": {\"gcode\": \"G0 X1\"}, "
             "\"design\": {\"stl_base64\": \"%s\"}, "
             "\"fixtures\": [{\"hyperfun\": \"f(x[3], a[1]) { f = 1; }\", \"name\": \"vise\"}]}",
             TOOLS, stl);
    fm_error err;
    fm_job_doc *doc = parse(text, &err);
    CHECK(doc != NULL);
    if (!doc) return;
    CHECK(doc->spec.stock_spec == NULL); /* an inline model has no file yet */
    char dir[] = "/tmp/fm-test-materialize-XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    writes_seen = 0;
    CHECK(fm_job_doc_materialize(doc, dir, counting_write, &err) == FM_OK);
    CHECK(writes_seen == 3);
    char want[256];
    snprintf(want, sizeof want, "%s/stock.hf", dir);
    CHECK(doc->spec.stock_spec && !strcmp(doc->spec.stock_spec, want));
    size_t n = 0;
    char *got = slurp(want, &n);
    CHECK(got && n == strlen("my_model(x[3], a[1]) { my_model = 1 - x[1]*x[1]; }") &&
          !strcmp(got, "my_model(x[3], a[1]) { my_model = 1 - x[1]*x[1]; }"));
    free(got);
    snprintf(want, sizeof want, "%s/design.stl", dir);
    CHECK(doc->spec.design_path && !strcmp(doc->spec.design_path, want));
    got = slurp(want, &n);
    int zeros = got && n == 84;
    for (size_t i = 0; zeros && i < n; i++) zeros = got[i] == 0;
    CHECK(zeros);
    free(got);
    snprintf(want, sizeof want, "%s/fixture0.hf", dir);
    CHECK(doc->spec.check && doc->spec.check->fixture_count == 1 &&
          !strcmp(doc->spec.check->fixtures[0], want));
    /* read back at start: the files are there, nothing is written again */
    writes_seen = 0;
    CHECK(fm_job_doc_materialize(doc, dir, counting_write, &err) == FM_OK);
    CHECK(writes_seen == 0);
    /* the plain writer (NULL) writes a fresh folder too */
    char dir2[] = "/tmp/fm-test-materialize-XXXXXX";
    CHECK(mkdtemp(dir2) != NULL);
    CHECK(fm_job_doc_materialize(doc, dir2, NULL, &err) == FM_OK);
    snprintf(want, sizeof want, "%s/fixture0.hf", dir2);
    got = slurp(want, &n);
    CHECK(got && !strcmp(got, "f(x[3], a[1]) { f = 1; }"));
    free(got);
    const char *names[] = {"stock.hf", "design.stl", "fixture0.hf"};
    for (int i = 0; i < 3; i++) {
        snprintf(want, sizeof want, "%s/%s", dir, names[i]);
        unlink(want);
        snprintf(want, sizeof want, "%s/%s", dir2, names[i]);
        unlink(want);
    }
    rmdir(dir);
    rmdir(dir2);
    fm_job_doc_free(doc);
}

/* The CLI's file forms (job_flags.c writes them): a tool table, program,
 * machine and fixture named by file are read under the files rules and
 * refused over the network with their reasons. */
static void test_file_forms(void)
{
    char dir[] = "/tmp/fm-test-docfiles-XXXXXX";
    CHECK(mkdtemp(dir) != NULL);
    char tools[256], machine[256];
    snprintf(tools, sizeof tools, "%s/tools.tbl", dir);
    snprintf(machine, sizeof machine, "%s/machine.json", dir);
    FILE *f = fopen(tools, "w");
    if (f) {
        fputs("T4 P4 D8 Z0 ;flat\n", f);
        fclose(f);
    }
    f = fopen(machine, "w");
    if (f) {
        fputs("{\"rapid_rate\": 12000}\n", f);
        fclose(f);
    }
    char text[2048];
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,10,10,0\", \"tools\": \"%s\", \"program\": {\"file\": "
             "\"part.ngc\"}, \"machine\": \"%s\", \"fixtures\": [{\"file\": \"clamp.hf\"}]}",
             tools, machine);
    const fm_job_doc_rules files = {.allow_files = 1};
    fm_error err;
    fm_job_doc *doc = parse_with(text, &files, &err);
    CHECK(doc != NULL);
    if (doc) {
        CHECK(doc->spec.tools == &doc->tools && doc->tools.count == 1);
        if (doc->tools.count == 1) CHECK_NEAR(doc->tools.tools[0].diameter, 8, 0);
        CHECK(doc->spec.tools_path && !strcmp(doc->spec.tools_path, tools));
        CHECK(doc->spec.program_path && !strcmp(doc->spec.program_path, "part.ngc"));
        CHECK(doc->spec.program_kind == FM_PROGRAM_AUTO);
        CHECK(doc->has_machine);
        CHECK_NEAR(doc->spec.rapid_rate, 12000, 0); /* the machine's, no options.rapid_rate */
        /* the check is on by default in a document; the CLI's simulate says false */
        CHECK(doc->spec.check && doc->spec.check->fixture_count == 1 &&
              !strcmp(doc->spec.check->fixtures[0], "clamp.hf"));
        fm_job_doc_free(doc);
    }
    /* over the network each file is refused */
    doc = parse(text, &err);
    CHECK(doc == NULL && !strcmp(err.reason, "bad_tools"));
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,10,10,0\", \"tools\": %s, \"program\": {\"file\": "
             "\"part.ngc\"}}", TOOLS);
    doc = parse(text, &err);
    CHECK(doc == NULL && !strcmp(err.reason, "bad_program"));
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,10,10,0\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, "
             "\"fixtures\": [{\"file\": \"clamp.hf\"}]}", TOOLS);
    doc = parse(text, &err);
    CHECK(doc == NULL && !strcmp(err.reason, "bad_fixture"));
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,10,10,0\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, "
             "\"machine\": \"%s\"}", TOOLS, machine);
    doc = parse(text, &err);
    CHECK(doc == NULL && !strcmp(err.reason, "bad_type"));
    /* a fixture file must be a model a check reads */
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,10,10,0\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, "
             "\"fixtures\": [{\"file\": \"clamp.obj\"}]}", TOOLS);
    doc = parse_with(text, &files, &err);
    CHECK(doc == NULL && !strcmp(err.reason, "bad_fixture"));
    /* a missing tool table is the loader's I/O error, naming the file */
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,10,10,0\", \"tools\": \"%s/none.json\", \"program\": "
             "{\"gcode\": \"G0\"}}", dir);
    doc = parse_with(text, &files, &err);
    CHECK(doc == NULL && err.code == FM_ERR_IO);
    /* the finest voxel is lib/stock's own bound */
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,10,10,0\", \"voxel\": 0.0001, \"tools\": %s, \"program\": "
             "{\"gcode\": \"G0\"}}", TOOLS);
    doc = parse(text, &err);
    CHECK(doc != NULL);
    fm_job_doc_free(doc);
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-5,10,10,0\", \"voxel\": 0.00009, \"tools\": %s, \"program\": "
             "{\"gcode\": \"G0\"}}", TOOLS);
    doc = parse(text, &err);
    CHECK(doc == NULL && !strcmp(err.reason, "bad_value"));
    unlink(tools);
    unlink(machine);
    rmdir(dir);
}

/* options.tools_from_program: no "tools", the program's comments name them
 * (the G-code interpreted once by the document's parser: a comment inside
 * an O-word call body counts as the interpreter reads it), each guessed
 * field in the document's warnings; an explicit table wins (a warning);
 * without either the document is refused; a trajectory has no comments; a
 * Fusion library inline is read as such. */
static void test_tools_from_program(void)
{
    const char *prog =
        "(T1 D=6. CR=0. - ZMIN=-5. - FLAT END MILL)\\n(T4 D=10. CR=2. - ZMIN=-8. - BULL NOSE END MILL)\\n"
        "T1 M6\\nG0 X0 Y0 Z5\\nM2\\n";
    char text[2048];
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-30,100,60,0\", \"program\": {\"gcode\": \"%s\"},"
             " \"options\": {\"tools_from_program\": true}}", prog);
    fm_error err;
    fm_job_doc *doc = parse(text, &err);
    if (!doc) fprintf(stderr, "  %s\n", err.message);
    CHECK(doc != NULL);
    if (doc) {
        /* by hand: flutes 3 D (18, 30), stick-out one D more */
        CHECK(doc->tools.count == 2 && doc->spec.tools == &doc->tools);
        const fm_tool_spec *t1 = fm_tool_table_find(&doc->tools, 1);
        const fm_tool_spec *t4 = fm_tool_table_find(&doc->tools, 4);
        CHECK(t1 && t1->shape == FM_TOOL_FLAT && t1->diameter == 6 && t1->flute_length == 18 &&
              t1->length == 24);
        CHECK(t4 && t4->shape == FM_TOOL_BULL && t4->corner_radius == 2 && t4->flute_length == 30);
        CHECK_STR_CONTAINS(doc->warnings, "program:1: T1 \"FLAT END MILL\" from the program's comment, "
                                          "guessed: flute_length 18 mm");
        CHECK_STR_CONTAINS(doc->warnings, "program:2: T4 \"BULL NOSE END MILL\"");
        CHECK(!json_object_get(doc->json, "tools"));
        /* the canonical form parses to the same tools */
        char *again = json_dumps(doc->json, JSON_COMPACT);
        fm_job_doc *doc2 = parse(again, &err);
        CHECK(doc2 && doc2->tools.count == 2 && json_equal(doc->json, doc2->json));
        fm_job_doc_free(doc2);
        free(again);
        fm_job_doc_free(doc);
    }
    /* an explicit table wins */
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-30,100,60,0\", \"tools\": %s, \"program\": {\"gcode\": \"%s\"},"
             " \"options\": {\"tools_from_program\": true}}", TOOLS, prog);
    doc = parse(text, &err);
    CHECK(doc && doc->tools.count == 1 && fm_tool_table_find(&doc->tools, 1)->flute_length == 20);
    CHECK(doc && doc->warnings && strstr(doc->warnings, "a tool table is given, it wins"));
    fm_job_doc_free(doc);
    /* neither: refused; no tool comment: refused; a trajectory: refused */
    expect_error("{\"stock\": \"box:0,0,-30,100,60,0\", \"program\": {\"gcode\": \"G0 X1\"}}", 400,
                 "missing_key");
    expect_error("{\"stock\": \"box:0,0,-30,100,60,0\", \"program\": {\"gcode\": \"(HELLO)\\nG0 X1\"},"
                 " \"options\": {\"tools_from_program\": true}}", 400, "bad_tools");
    expect_error("{\"stock\": \"box:0,0,-30,100,60,0\", \"program\": {\"trajectory\": {\"segments\": []}},"
                 " \"options\": {\"tools_from_program\": true}}", 400, "bad_tools");
    expect_error("{\"stock\": \"box:0,0,-30,100,60,0\", \"program\": {\"gcode\": \"(T1 D=6.)\"},"
                 " \"options\": {\"tools_from_program\": 1}}", 400, "bad_type");
    /* a Fusion library inline: its description, warnings for its bounding
     * solids */
    doc = parse("{\"stock\": \"box:0,0,-30,100,60,0\", \"program\": {\"gcode\": \"G0 X1\"},"
                " \"tools\": {\"data\": [{\"type\": \"thread mill\", \"description\": \"M6 thread mill\","
                " \"unit\": \"millimeters\", \"post-process\": {\"number\": 3},"
                " \"geometry\": {\"DC\": 4.8, \"LCF\": 12, \"LB\": 30}}]}}", &err);
    if (!doc) fprintf(stderr, "  %s\n", err.message);
    CHECK(doc && doc->tools.count == 1 && !strcmp(doc->tools.tools[0].comment, "M6 thread mill"));
    CHECK(doc && doc->warnings && strstr(doc->warnings, "bounding solid of revolution"));
    fm_job_doc_free(doc);
}

/* The machine's state at the start (issue 34): options.initial_tool, else
 * the machine's initial_tool, else none; a tool the table lacks is
 * bad_value naming the key. The start: the machine's, else the dialect's
 * power-on place (LinuxCNC the origin, Fanuc the first reference point),
 * the check's start the same. */
static void test_start_state(void)
{
    static const char *two = "{\"units\": \"mm\", \"tools\": [{\"number\": 1, \"shape\": "
                             "\"flat\", \"diameter\": 6, \"flute_length\": 20, \"length\": 40}, "
                             "{\"number\": 4, \"shape\": \"ball\", \"diameter\": 4, "
                             "\"flute_length\": 20, \"length\": 40}]}";
    const char *head = "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}";
    char fmt[512], text[1024];
    fm_error err;
    struct {
        const char *tail;
        int tool, has_start;
        double start[3];
    } ok[] = {
        {"}", 0, 1, {0, 0, 0}},
        {", \"options\": {\"initial_tool\": 4}}", 4, 1, {0, 0, 0}},
        {", \"machine\": {\"initial_tool\": 1, \"start\": [1, 2, 30]}}", 1, 1, {1, 2, 30}},
        {", \"machine\": {\"initial_tool\": 1}, \"options\": {\"initial_tool\": 4}}", 4, 1, {0, 0, 0}},
        {", \"machine\": {\"reference_points\": [[5, 6, 7]]}, \"options\": {\"dialect\": \"fanuc\"}}",
         0, 1, {5, 6, 7}},
        {", \"machine\": {\"reference_points\": [[5, 6, 7]], \"start\": [0, 0, 9]}, "
         "\"options\": {\"dialect\": \"fanuc\"}}",
         0, 1, {0, 0, 9}},
    };
    for (size_t i = 0; i < sizeof ok / sizeof ok[0]; i++) {
        snprintf(fmt, sizeof fmt, "%s%s", head, ok[i].tail);
        snprintf(text, sizeof text, fmt, two);
        fm_job_doc *doc = parse(text, &err);
        CHECK(doc != NULL);
        if (!doc) {
            fprintf(stderr, "  %s: %s\n", text, err.message);
            continue;
        }
        CHECK(doc->spec.initial_tool == ok[i].tool);
        CHECK(doc->spec.has_start == ok[i].has_start);
        for (int k = 0; k < 3; k++) {
            CHECK_NEAR(doc->spec.start[k], ok[i].start[k], 0);
            CHECK_NEAR(doc->check.options.machine.start[k], ok[i].start[k], 0);
        }
        fm_job_doc_free(doc);
    }
    snprintf(fmt, sizeof fmt, "%s, \"options\": {\"initial_tool\": 2}}", head);
    snprintf(text, sizeof text, fmt, two);
    expect_error(text, 400, "bad_value");
    fm_job_doc *doc = parse(text, &err);
    CHECK_STR_CONTAINS(err.message, "options.initial_tool 2: tool 2 is not in the tool table (its tools: 1, 4)");
    fm_job_doc_free(doc);
    snprintf(fmt, sizeof fmt, "%s, \"machine\": {\"initial_tool\": 3}}", head);
    snprintf(text, sizeof text, fmt, two);
    expect_error(text, 400, "bad_value");
    snprintf(fmt, sizeof fmt, "%s, \"options\": {\"initial_tool\": -1}}", head);
    snprintf(text, sizeof text, fmt, two);
    expect_error(text, 400, "bad_value");
    snprintf(fmt, sizeof fmt, "%s, \"options\": {\"initial_tool\": 1.5}}", head);
    snprintf(text, sizeof text, fmt, two);
    expect_error(text, 400, "bad_type");
}

int main(void)
{
    test_job_ok();
    test_job_errors();
    test_rapid_rate();
    test_rules_and_parts();
    test_gcode_options();
    test_design();
    test_memory();
    test_stock_spec();
    test_base64();
    test_materialize();
    test_file_forms();
    test_tools_from_program();
    test_start_state();
    return test_summary("job_doc");
}
