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
- a multipart upload of more than 16 parts is 413 too_many_parts;
- a chunked body (no Content-Length) over max_request_mb is 413
  request_too_large once it has ended, in JSON, and the daemon serves the
  next request;
- a body that trickles past request_deadline_ms is answered 408
  request_timeout (JSON) and the connection closed, within the sweeper's
  period of the deadline; headers that trickle are only closed.
Usage: test_auth.py FREPMILLD FREPMILL"""
import json
import os
import socket
import subprocess
import sys
import tempfile
import time

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


def raw_exchange(url, head, pieces, pause=0.0, timeout=20.0):
    """Send head then each of pieces (pause s apart) on a raw socket; return
    (status, headers text, body bytes, seconds from the first byte to the
    answer). A closed connection without an answer is status None."""
    host, port = url.split("//")[1].split(":")
    sock = socket.create_connection((host, int(port)), timeout=timeout)
    t0 = time.time()
    got = b""
    try:
        sock.sendall(head)
        for p in pieces:
            try:
                sock.sendall(p)
            except OSError:
                break  # the server answered and shut the connection down
            if pause:
                time.sleep(pause)
        while True:
            try:
                b = sock.recv(65536)
            except ConnectionResetError:
                break
            if not b:
                break
            got += b
    finally:
        sock.close()
    elapsed = time.time() - t0
    if b"\r\n\r\n" not in got:
        return None, "", got, elapsed
    headers, body = got.split(b"\r\n\r\n", 1)
    status = int(headers.split(b" ")[1])
    return status, headers.decode(errors="replace"), body, elapsed


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

        # 7. Answers mid-body (libmicrohttpd takes a response only before a
        # body or after it: http_server.c answers these another way).
        deadline_ms = 1500
        d = Daemon(frepmilld, os.path.join(tmp, "limits"), "--workers", "1",
                   "--max-request-mb", "0.01", "--request-deadline-ms", str(deadline_ms))
        try:
            big = tiny_job()
            big["program"]["gcode"] += "(" + "x" * 20000 + ")\n"
            data = json.dumps(big).encode()
            chunks = b""
            for i in range(0, len(data), 4096):
                part = data[i:i + 4096]
                chunks += b"%x\r\n" % len(part) + part + b"\r\n"
            chunks += b"0\r\n\r\n"
            head = (b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                    b"Transfer-Encoding: chunked\r\n\r\n")
            status, headers, body, _ = raw_exchange(d.url, head, [chunks])
            parsed = json.loads(body) if body.strip() else None
            check(status == 413 and error_code(parsed) == "request_too_large",
                  "a 20 kB chunked body over max_request_mb 0.01: 413 request_too_large (%s %r)"
                  % (status, body[:200]))
            small = json.dumps(tiny_job()).encode()
            status, _, body, _ = raw_exchange(
                d.url, head, [b"%x\r\n" % len(small) + small + b"\r\n0\r\n\r\n"])
            check(status == 202, "a small chunked body: 202 (%s %r)" % (status, body[:200]))

            # A body of 200 bytes sent a byte every 50 ms takes 10 s: past the
            # 1.5 s deadline it is answered 408 and closed.
            head = (b"POST /v1/jobs HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n"
                    b"Content-Length: 200\r\n\r\n")
            status, headers, body, took = raw_exchange(d.url, head, [b" "] * 200, pause=0.05)
            parsed = json.loads(body) if body.strip() else None
            check(status == 408 and error_code(parsed) == "request_timeout",
                  "a body trickling past request_deadline_ms: 408 request_timeout (%s %r)"
                  % (status, body[:200]))
            check("connection: close" in headers.lower(), "the 408 closes the connection")
            check(deadline_ms / 1000.0 <= took <= deadline_ms / 1000.0 + 2.0,
                  "answered %.2f s after the request began (deadline %.1f s, the sweeper's "
                  "period 0.25 s, 2 s of slack for a loaded machine)" % (took, deadline_ms / 1000.0))
            # Headers that trickle get no answer, but are closed.
            status, _, body, took = raw_exchange(d.url, b"GET /v1/jobs HTTP/1.1\r\n",
                                                 [b"X-Slow: 1\r\n"] * 100, pause=0.05)
            check(status is None and took < deadline_ms / 1000.0 + 2.5,
                  "headers trickling past the deadline: closed after %.2f s (%s)" % (took, status))
            code, body = curl_json(d.url + "/v1/jobs")
            check(code == 200, "the daemon still serves requests (%d)" % code)
        finally:
            rc = d.stop()
        check(rc == 0, "the limits daemon stops with status 0")
    return 0


if __name__ == "__main__":
    sys.exit(main())
