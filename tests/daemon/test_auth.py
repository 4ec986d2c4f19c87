"""test_auth.py: frepmilld's bearer token and request limits over real HTTP
(docs/api.md "Errors", docs/daemon.md "Settings" and "Limits"):

- a non-loopback listen without a token is refused at start (exit 2, the
  reason logged) and with one it starts;
- with a token, every write endpoint (POST /v1/jobs, DELETE, cancel,
  POST /v1/check) answers 401 unauthorized without the header, with a wrong
  token, a token that is a prefix or an extension of the right one, or
  another scheme; the right token is accepted; reads need no token;
- a non-loopback daemon with a token refuses a write without it;
- max_jobs: the job past the limit is 429 job_limit, and once one is deleted
  a new one is accepted;
- max_request_mb: a body over it is 413 request_too_large (by its
  Content-Length);
- a multipart upload of more than 16 parts is 413 too_many_parts.
Usage: test_auth.py FREPMILLD FREPMILL"""
import json
import os
import subprocess
import sys
import tempfile

from daemon_util import Daemon, check, curl_json

TOKEN = "s3cret-Token_42"
# A tiny job: one plunge into a small box on a coarse grid (it runs in well
# under a second; what is tested here is the answer to the request).
TOOLS = os.path.join(os.path.dirname(__file__), "..", "..", "deploy", "demo", "tools.json")


def tiny_job(name="tiny"):
    with open(TOOLS) as f:
        tools = json.load(f)
    return {"stock": "box:0,0,-5,10,10,0", "voxel": 0.5, "tools": tools,
            "program": {"gcode": "G21 G90\nT1 M6\nG0 X5 Y5 Z1\nG1 Z-1 F100\nG0 Z5\nM2\n"},
            "options": {"name": name}}


def post(url, path, body, token=None, auth=None):
    args = ["-X", "POST", "-H", "Content-Type: application/json", "--data-binary", body]
    if auth is not None:
        args += ["-H", "Authorization: " + auth]
    elif token is not None:
        args += ["-H", "Authorization: Bearer " + token]
    return curl_json(*args, url + path)


def error_code(body):
    return body["error"]["code"] if body and "error" in body else None


def main():
    frepmilld = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="fm-auth-") as tmp:
        # 1. Not loopback without a token: refused at start.
        state = os.path.join(tmp, "refused")
        out = subprocess.run([frepmilld, "--listen", "0.0.0.0:0", "--state-dir", state,
                              "--modbus-listen", "off"],
                             stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=60)
        text = out.stdout.decode(errors="replace")
        check(out.returncode == 2 and "not loopback" in text and "token" in text,
              "listen 0.0.0.0 without a token: exit %d, %r" % (out.returncode, text.strip()))
        check(not os.path.exists(os.path.join(state, "http.addr")), "the refused daemon never listened")

        # 2. Loopback with a token: writes need it, reads do not.
        d = Daemon(frepmilld, os.path.join(tmp, "token"), "--token", TOKEN, "--workers", "1",
                   "--max-jobs", "2")
        try:
            job = json.dumps(tiny_job())
            for what, kw in (("no Authorization header", {}),
                             ("a wrong token", {"token": "wrong"}),
                             ("a prefix of the token", {"token": TOKEN[:-1]}),
                             ("the token and one more byte", {"token": TOKEN + "x"}),
                             ("the empty token", {"token": ""}),
                             ("another scheme", {"auth": "Basic " + TOKEN}),
                             ("the token without a scheme", {"auth": TOKEN})):
                code, body = post(d.url, "/v1/jobs", job, **kw)
                check(code == 401 and error_code(body) == "unauthorized",
                      "POST /v1/jobs with %s: 401 unauthorized (%d %s)" % (what, code, body))
            code, lst = curl_json(d.url + "/v1/jobs")
            check(code == 200 and lst["jobs"] == [], "no job was stored by the refused POSTs")
            code, body = post(d.url, "/v1/jobs", job, token=TOKEN)
            check(code == 202 and body and body.get("id"), "POST /v1/jobs with the token: 202")
            first = body["id"]
            # "Bearer" is case-insensitive (RFC 7235 auth-scheme)
            code, body = post(d.url, "/v1/jobs", job, auth="bearer " + TOKEN)
            check(code == 202, "the scheme 'bearer' in lower case: 202 (%d)" % code)
            second = body["id"]
            code, st = curl_json(d.url + "/v1/jobs/" + first)
            check(code == 200 and st["id"] == first, "GET of a job needs no token: 200")
            code, body = post(d.url, "/v1/check", job)
            check(code == 401 and error_code(body) == "unauthorized", "POST /v1/check without the token: 401")
            code, body = post(d.url, "/v1/check", "{}", token=TOKEN)
            check(code == 400 and error_code(body) == "missing_key",
                  "POST /v1/check with the token reaches the check: 400 missing_key (%d)" % code)
            code, body = post(d.url, "/v1/jobs/%s/cancel" % first, "")
            check(code == 401 and error_code(body) == "unauthorized", "cancel without the token: 401")
            code, body = curl_json("-X", "DELETE", d.url + "/v1/jobs/" + first)
            check(code == 401 and error_code(body) == "unauthorized", "DELETE without the token: 401")
            code, body = curl_json("-X", "DELETE", "-H", "Authorization: Bearer wrong",
                                   d.url + "/v1/jobs/" + first)
            check(code == 401, "DELETE with a wrong token: 401")
            code, st = curl_json(d.url + "/v1/jobs/" + first)
            check(code == 200, "the job is still there after the refused DELETEs")

            # 3. max_jobs = 2: the third is 429 job_limit; after a delete, accepted.
            code, body = post(d.url, "/v1/jobs", job, token=TOKEN)
            check(code == 429 and error_code(body) == "job_limit",
                  "a third job with max_jobs 2: 429 job_limit (%d %s)" % (code, body))
            code, body = curl_json("-X", "DELETE", "-H", "Authorization: Bearer " + TOKEN,
                                   d.url + "/v1/jobs/" + first)
            check(code == 200 and body["deleted"] is True, "DELETE with the token: 200")
            code, body = post(d.url, "/v1/jobs", job, token=TOKEN)
            check(code == 202, "after a delete a job is accepted again: 202 (%d %s)" % (code, body))
            del second
        finally:
            rc = d.stop()
        check(rc == 0, "the token daemon stops with status 0")

        # 4. Not loopback with a token: starts, and writes need the token.
        d = Daemon(frepmilld, os.path.join(tmp, "open"), "--listen", "0.0.0.0:0", "--token", TOKEN,
                   "--workers", "1", "--max-request-mb", "0.01")
        d.url = d.url.replace("0.0.0.0", "127.0.0.1")
        try:
            job = json.dumps(tiny_job())
            code, body = post(d.url, "/v1/jobs", job)
            check(code == 401 and error_code(body) == "unauthorized",
                  "listen 0.0.0.0 with a token: POST without it is 401")
            code, body = post(d.url, "/v1/jobs", job, token=TOKEN)
            check(code == 202, "listen 0.0.0.0: POST with the token is 202")

            # 5. max_request_mb 0.01 (10,485 bytes): a larger body is 413.
            big = tiny_job()
            big["program"]["gcode"] += "(" + "x" * 20000 + ")\n"
            code, body = post(d.url, "/v1/jobs", json.dumps(big), token=TOKEN)
            check(code == 413 and error_code(body) == "request_too_large",
                  "a 20 kB body over max_request_mb 0.01: 413 request_too_large (%d %s)" % (code, body))
            small = tiny_job()
            small["program"]["gcode"] += "(" + "x" * 8000 + ")\n"
            code, body = post(d.url, "/v1/jobs", json.dumps(small), token=TOKEN)
            check(code == 202, "a 9 kB body under the limit: 202 (%d %s)" % (code, body))

            # 6. 17 parts: 413 too_many_parts (FM_HTTP_MAX_PARTS is 16).
            args = ["-X", "POST", "-H", "Authorization: Bearer " + TOKEN]
            for i in range(17):
                args += ["-F", "extra%d=x" % i]
            code, body = curl_json(*args, d.url + "/v1/jobs")
            check(code == 413 and error_code(body) == "too_many_parts",
                  "a multipart body of 17 parts: 413 too_many_parts (%d %s)" % (code, body))
            args = ["-X", "POST", "-H", "Authorization: Bearer " + TOKEN]
            for i in range(16):
                args += ["-F", "extra%d=x" % i]
            code, body = curl_json(*args, d.url + "/v1/jobs")
            check(code == 400 and error_code(body) != "too_many_parts",
                  "16 parts are within the limit (400 %s for the missing job part)" % error_code(body))

        finally:
            rc = d.stop()
        check(rc == 0, "the non-loopback daemon stops with status 0")
    return 0


if __name__ == "__main__":
    sys.exit(main())
