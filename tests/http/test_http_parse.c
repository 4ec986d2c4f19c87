/* test_http_parse.c: unit tests of the HTTP layer's own parsing: multipart
 * bodies built here by hand (parts, file names, bounds, malformed input),
 * the multipart-to-job assembly, and the mapping of a service's error
 * reasons to the statuses of docs/api.md. (The job document itself is
 * validated in daemon/runner: tests/daemon/test_job_doc.c.) */
#include <stdio.h>
#include <stdlib.h>
#include <string.h>

#include "protocols/http/http_server.h"
#include "test.h"

static const char *TOOLS = "{\"units\": \"mm\", \"tools\": [{\"number\": 1, \"shape\": \"flat\", "
                           "\"diameter\": 6, \"flute_length\": 20, \"length\": 40}]}";

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
        /* the tools part is absent: the job part's table stays */
        CHECK(json_is_object(json_object_get(job, "tools")));
    }
    json_decref(job);
    /* a trajectory part (.json) becomes program.trajectory */
    snprintf(parts[1].filename, sizeof parts[1].filename, "path.json");
    parts[1].data = "{\"segments\": []}";
    parts[1].size = strlen(parts[1].data);
    job = fm_http_job_from_multipart(parts, 2, &err);
    CHECK(job && json_is_object(json_object_get(json_object_get(job, "program"), "trajectory")));
    json_decref(job);
    snprintf(parts[1].filename, sizeof parts[1].filename, "a.ngc");
    parts[1].data = "G0\0X1";
    parts[1].size = 5;
    CHECK(fm_http_job_from_multipart(parts, 2, &err) == NULL && !strcmp(err.code, "bad_program"));
    snprintf(parts[1].name, sizeof parts[1].name, "extra");
    CHECK(fm_http_job_from_multipart(parts, 2, &err) == NULL && err.status == 400);
}

/* The statuses docs/api.md lists for each reason, and for errors without
 * one by their fm_status. */
static void test_error_mapping(void)
{
    static const struct {
        fm_status code;
        const char *reason;
        int status;
        const char *out;
    } cases[] = {
        {FM_ERR_INPUT, "not_found", 404, "not_found"},
        {FM_ERR_INPUT, "no_snapshot", 404, "no_snapshot"},
        {FM_ERR_INPUT, "not_finished", 409, "not_finished"},
        {FM_ERR_INPUT, "bad_state", 409, "bad_state"},
        {FM_ERR_LIMIT, "job_limit", 429, "job_limit"},
        {FM_ERR_LIMIT, "shutting_down", 503, "shutting_down"},
        {FM_ERR_LIMIT, "busy", 503, "busy"},
        {FM_ERR_IO, "storage", 507, "storage"},
        {FM_ERR_LIMIT, "memory_budget", 413, "memory_budget"},
        {FM_ERR_LIMIT, "check_too_large", 413, "check_too_large"},
        {FM_ERR_LIMIT, "too_large", 413, "too_large"},
        {FM_ERR_INPUT, "unknown_key", 400, "unknown_key"},
        {FM_ERR_INPUT, "bad_tools", 400, "bad_tools"},
        {FM_ERR_INPUT, "", 400, "bad_job"},
        {FM_ERR_LIMIT, "", 413, "limit"},
        {FM_ERR_IO, "", 507, "storage"},
        {FM_ERR_INTERNAL, "", 500, "internal"},
    };
    for (size_t i = 0; i < sizeof cases / sizeof cases[0]; i++) {
        fm_error e;
        fm_error_set_reason(&e, cases[i].code, cases[i].reason, "message %zu", i);
        e.line = 3;
        e.column = 7;
        fm_http_error h;
        fm_http_error_from(&e, &h);
        CHECK(h.status == cases[i].status && !strcmp(h.code, cases[i].out));
        CHECK(h.line == 3 && h.column == 7 && !strcmp(h.message, e.message));
    }
}

int main(void)
{
    test_error_mapping();
    test_multipart();
    test_multipart_job();
    return test_summary("http_parse");
}
