/* test_http_parse.c: unit tests of the HTTP layer's parsers: job requests
 * (canonical form, defaults, every refusal with its status and code, line
 * and column of syntax errors), base64 (RFC 4648 test vectors), multipart
 * bodies built here by hand (parts, file names, bounds, malformed input)
 * and the multipart-to-job assembly. */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "protocols/http/http_server.h"
#include "test.h"

static const char *TOOLS = "{\"units\": \"mm\", \"tools\": [{\"number\": 1, \"shape\": \"flat\", "
                           "\"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

static json_t *parse(const char *text, fm_http_error *err)
{
    memset(err, 0, sizeof *err);
    return fm_http_job_parse(text, strlen(text), err);
}

static void test_job_ok(void)
{
    char text[1024];
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-30,100,60,0\", \"tools\": %s, \"program\": {\"gcode\": \"G0 X1\"}}",
             TOOLS);
    fm_http_error err;
    json_t *job = parse(text, &err);
    CHECK(job != NULL);
    if (!job) return;
    /* Defaults filled in: voxel 0.1 (the CLI's), empty fixtures and options. */
    CHECK_NEAR(json_number_value(json_object_get(job, "voxel")), 0.1, 0);
    CHECK(json_array_size(json_object_get(job, "fixtures")) == 0);
    CHECK(json_object_size(json_object_get(job, "options")) == 0);
    CHECK(!strcmp(json_string_value(json_object_get(job, "stock")), "box:0,0,-30,100,60,0"));
    /* The canonical form parses to itself. */
    char *again = json_dumps(job, JSON_COMPACT);
    json_t *job2 = parse(again, &err);
    CHECK(job2 && json_equal(job, job2));
    free(again);
    json_decref(job2);
    json_decref(job);
    /* options.color: "tool" and "none" are the two mesh colourings */
    const char *colors[2] = {"tool", "none"};
    for (int i = 0; i < 2; i++) {
        snprintf(text, sizeof text,
                 "{\"stock\": \"box:0,0,-30,100,60,0\", \"tools\": %s, \"program\": {\"gcode\": "
                 "\"G0 X1\"}, \"options\": {\"color\": \"%s\"}}",
                 TOOLS, colors[i]);
        job = parse(text, &err);
        CHECK(job != NULL);
        json_decref(job);
    }
    snprintf(text, sizeof text,
             "{\"stock\": \"box:0,0,-30,100,60,0\", \"tools\": %s, \"program\": {\"gcode\": "
             "\"G0 X1\"}, \"options\": {\"color\": \"rainbow\"}}",
             TOOLS);
    job = parse(text, &err);
    CHECK(job == NULL && err.status == 400);
    CHECK_STR_CONTAINS(err.message, "options.color must be \"tool\"");
    json_decref(job);
}

static void expect_error(const char *text, int status, const char *code)
{
    fm_http_error err;
    json_t *job = parse(text, &err);
    CHECK(job == NULL);
    CHECK(err.status == status);
    CHECK(!strcmp(err.code, code));
    if (job || err.status != status || strcmp(err.code, code))
        fprintf(stderr, "  for %s: got %d %s (%s)\n", text, err.status, err.code, err.message);
    json_decref(job);
}

static void test_job_errors(void)
{
    char text[2048];
    expect_error("", 400, "bad_json");
    expect_error("[1, 2]", 400, "bad_job");
    expect_error("{\"stock\": \"box:0,0,0,1,1,1\"}", 400, "missing_key");
    snprintf(text, sizeof text, "{\"stock\": \"/etc/passwd\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
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
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"options\": {\"color\": \"depth\"}}", TOOLS);
    expect_error(text, 400, "bad_value");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"options\": {\"color\": 1}}", TOOLS);
    expect_error(text, 400, "bad_value");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}, \"fixtures\": [{\"stl\": \"x\"}]}", TOOLS);
    expect_error(text, 400, "bad_fixture");
    snprintf(text, sizeof text, "{\"stock\": \"box:0,0,0,1,1,1\", \"stock\": \"box:0,0,0,2,2,2\", \"tools\": %s, \"program\": {\"gcode\": \"G0\"}}", TOOLS);
    expect_error(text, 400, "bad_json"); /* duplicate key */

    /* Line and column of a syntax error: the '}' on line 3, column 12. */
    fm_http_error err;
    json_t *job = parse("{\n  \"stock\": \"box:0,0,0,1,1,1\",\n  \"voxel\": }", &err);
    CHECK(job == NULL && err.line == 3 && err.column == 12);
    if (err.line != 3 || err.column != 12) fprintf(stderr, "  line %d column %d\n", err.line, err.column);
}

static void test_base64(void)
{
    /* RFC 4648 section 10 test vectors. */
    static const char *const plain[] = {"", "f", "fo", "foo", "foob", "fooba", "foobar"};
    static const char *const coded[] = {"", "Zg==", "Zm8=", "Zm9v", "Zm9vYg==", "Zm9vYmE=", "Zm9vYmFy"};
    for (int i = 0; i < 7; i++) {
        uint8_t *out;
        size_t n;
        CHECK(fm_http_base64_decode(coded[i], strlen(coded[i]), &out, &n) == 0);
        CHECK(n == strlen(plain[i]) && (n == 0 || !memcmp(out, plain[i], n)));
        free(out);
    }
    uint8_t *out;
    size_t n;
    CHECK(fm_http_base64_decode("Zm9v!", 5, &out, &n) == -1);
    CHECK(fm_http_base64_decode("Zg==Zg==", 8, &out, &n) == -1); /* data after padding */
    CHECK(fm_http_base64_decode("Zh==", 4, &out, &n) == -1);     /* non-zero pad bits */
}

static void test_multipart(void)
{
    const char *type = "multipart/form-data; boundary=\"XyZ\"";
    const char *body = "preamble\r\n"
                       "--XyZ\r\n"
                       "Content-Disposition: form-data; name=\"job\"\r\n"
                       "Content-Type: application/json\r\n"
                       "\r\n"
                       "{\"a\": 1}\r\n"
                       "--XyZ\r\n"
                       "Content-Disposition: form-data; name=\"program\"; filename=\"p;1.ngc\"\r\n"
                       "\r\n"
                       "G0 X1\r\n--Xy\r\nG1 X2\r\n"
                       "--XyZ--\r\n";
    fm_http_part parts[4];
    fm_http_error err;
    int n = fm_http_multipart_parse(type, body, strlen(body), parts, 4, &err);
    CHECK(n == 2);
    if (n != 2) return;
    CHECK(!strcmp(parts[0].name, "job") && parts[0].filename[0] == '\0');
    CHECK(!strcmp(parts[0].content_type, "application/json"));
    CHECK(parts[0].size == 8 && !memcmp(parts[0].data, "{\"a\": 1}", 8));
    CHECK(!strcmp(parts[1].name, "program") && !strcmp(parts[1].filename, "p;1.ngc"));
    /* A line that starts like the boundary but is not it stays in the data. */
    const char *expect = "G0 X1\r\n--Xy\r\nG1 X2";
    CHECK(parts[1].size == strlen(expect) && !memcmp(parts[1].data, expect, strlen(expect)));

    CHECK(fm_http_multipart_parse(type, body, strlen(body), parts, 1, &err) == -1 && err.status == 413);
    CHECK(fm_http_multipart_parse("multipart/form-data", body, strlen(body), parts, 4, &err) == -1);
    CHECK(fm_http_multipart_parse("text/plain; boundary=XyZ", body, strlen(body), parts, 4, &err) == -1);
    const char *unterminated = "--XyZ\r\nContent-Disposition: form-data; name=\"job\"\r\n\r\nabc";
    CHECK(fm_http_multipart_parse(type, unterminated, strlen(unterminated), parts, 4, &err) == -1);
    const char *no_name = "--XyZ\r\nContent-Disposition: form-data\r\n\r\nabc\r\n--XyZ--";
    CHECK(fm_http_multipart_parse(type, no_name, strlen(no_name), parts, 4, &err) == -1);
    /* Headers without an end within 8 KiB are refused, not searched forever. */
    size_t big = 20000;
    char *huge = malloc(big + 64);
    int m = snprintf(huge, 64, "--XyZ\r\nContent-Disposition: form-data; name=\"a\"\r\nX: ");
    memset(huge + m, 'x', big);
    CHECK(fm_http_multipart_parse(type, huge, (size_t)m + big, parts, 4, &err) == -1);
    free(huge);
}

static void test_multipart_job(void)
{
    char spec[1024];
    snprintf(spec, sizeof spec, "{\"stock\": \"box:0,0,-5,10,10,0\", \"voxel\": 0.5, \"tools\": %s}", TOOLS);
    fm_http_part parts[2];
    memset(parts, 0, sizeof parts);
    snprintf(parts[0].name, sizeof parts[0].name, "job");
    parts[0].data = spec;
    parts[0].size = strlen(spec);
    snprintf(parts[1].name, sizeof parts[1].name, "program");
    snprintf(parts[1].filename, sizeof parts[1].filename, "a.ngc");
    parts[1].data = "G0 X1\nG1 X2 F100\n";
    parts[1].size = strlen(parts[1].data);
    fm_http_error err;
    json_t *job = fm_http_job_from_multipart(parts, 2, &err);
    CHECK(job != NULL);
    if (job) {
        const char *g = json_string_value(json_object_get(json_object_get(job, "program"), "gcode"));
        CHECK(g && !strcmp(g, "G0 X1\nG1 X2 F100\n"));
        CHECK_NEAR(json_number_value(json_object_get(job, "voxel")), 0.5, 0);
    }
    json_decref(job);
    parts[1].data = "G0\0X1";
    parts[1].size = 5;
    CHECK(fm_http_job_from_multipart(parts, 2, &err) == NULL && !strcmp(err.code, "bad_program"));
    snprintf(parts[1].name, sizeof parts[1].name, "extra");
    CHECK(fm_http_job_from_multipart(parts, 2, &err) == NULL && err.status == 400);
}

int main(void)
{
    test_job_ok();
    test_job_errors();
    test_base64();
    test_multipart();
    test_multipart_job();
    return test_summary("http_parse");
}
