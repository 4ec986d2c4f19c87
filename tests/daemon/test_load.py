"""test_load.py: 200 status requests per second (open loop: request i is
sent at start + i/200 s, each on its own connection) for FM_LOAD_SECONDS
(default 10 in CI; docs/daemon.md records a 30 s run) while jobs run, with
no error; meanwhile a client sending one byte per second and a client
sending a header line every 2 s must not delay the others and must be cut
off by the total request deadline. Usage: test_load.py FREPMILLD FREPMILL"""
import http.client
import os
import select
import socket
import sys
import tempfile
import threading
import time

from daemon_util import Daemon, check, curl_json, demo_job, submit

RATE = 200
DEADLINE_MS = 4000


def slow_client(port, chunk_fn, result):
    """Dribble a request; record how long until the server closed it (the
    pauses wait for the socket to become readable, so the close is seen at
    once)."""
    s = socket.create_connection(("127.0.0.1", port), timeout=30)
    start = time.time()
    try:
        for piece in chunk_fn():
            s.sendall(piece)
            readable, _, _ = select.select([s], [], [], 1 if len(piece) == 1 else 2)
            if readable:
                while s.recv(4096):
                    pass
                break
            if time.time() - start > 25:
                break
    except OSError:
        pass
    result["closed_after"] = time.time() - start
    s.close()


def bytes_of(text):
    return lambda: (bytes([b]) for b in text.encode())


def header_lines():
    yield b"GET /healthz HTTP/1.1\r\nHost: x\r\n"
    for i in range(100):
        yield b"X-Slow-%d: y\r\n" % i


def main():
    frepmilld = sys.argv[1]
    seconds = float(os.environ.get("FM_LOAD_SECONDS", "10"))
    with tempfile.TemporaryDirectory(prefix="fm-load-") as tmp:
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1",
                   "--request-deadline-ms", str(DEADLINE_MS))
        try:
            port = int(d.url.rsplit(":", 1)[1])
            jobs = [submit(d.url, demo_job(0.25, "load%d" % i), tmp)
                    for i in range(int(seconds // 10) + 2)]
            time.sleep(0.5)
            byte_result, line_result = {}, {}
            slow = [threading.Thread(target=slow_client, args=(port, bytes_of(
                        "GET /healthz HTTP/1.1\r\nHost: x\r\n" + "X-Pad: " + "y" * 100 + "\r\n\r\n"),
                        byte_result)),
                    threading.Thread(target=slow_client, args=(port, header_lines, line_result))]
            for t in slow:
                t.start()
            total = int(RATE * seconds)
            latencies, errors = [], []
            lock = threading.Lock()
            start = time.time() + 0.2
            counter = iter(range(total))
            counter_lock = threading.Lock()

            def worker():
                while True:
                    with counter_lock:
                        i = next(counter, None)
                    if i is None:
                        return
                    delay = start + i / RATE - time.time()
                    if delay > 0:
                        time.sleep(delay)
                    t0 = time.time()
                    try:
                        c = http.client.HTTPConnection("127.0.0.1", port, timeout=10)
                        c.request("GET", "/v1/jobs/" + jobs[i % len(jobs)])
                        r = c.getresponse()
                        body = r.read()
                        c.close()
                        ok = r.status == 200 and body.startswith(b"{")
                        with lock:
                            latencies.append(time.time() - t0)
                            if not ok:
                                errors.append("status %d" % r.status)
                    except Exception as e:  # noqa: BLE001 - every failure counts
                        with lock:
                            errors.append(repr(e))

            threads = [threading.Thread(target=worker) for _ in range(32)]
            for t in threads:
                t.start()
            code, first = curl_json(d.url + "/v1/jobs/" + jobs[0])
            for t in threads:
                t.join(timeout=seconds + 60)
            elapsed = time.time() - start
            for t in slow:
                t.join(timeout=60)
            latencies.sort()
            p50 = latencies[len(latencies) // 2]
            p99 = latencies[int(len(latencies) * 0.99)]
            print("load: %d requests in %.1f s (%.0f/s), p50 %.1f ms, p99 %.1f ms, max %.1f ms, "
                  "%d errors" % (len(latencies), elapsed, len(latencies) / elapsed, p50 * 1e3,
                                 p99 * 1e3, latencies[-1] * 1e3, len(errors)))
            check(not errors, "no errors (%s)" % errors[:3])
            check(len(latencies) == total and elapsed < seconds * 1.2 + 2,
                  "%d requests held the rate of %d/s" % (total, RATE))
            check(p99 < 0.5, "p99 latency %.1f ms under 500 ms despite the slow clients" % (p99 * 1e3))
            states = [curl_json(d.url + "/v1/jobs/" + j)[1]["state"] for j in jobs]
            check(first["state"] == "running" or "running" in states,
                  "a job was running during the load (%s)" % states)
            for name, res in (("one byte per second", byte_result), ("a header line every 2 s", line_result)):
                after = res.get("closed_after", 1e9)
                check(DEADLINE_MS / 1000 - 0.5 <= after <= DEADLINE_MS / 1000 + 3,
                      "the client sending %s was closed after %.1f s (deadline %.1f s)" %
                      (name, after, DEADLINE_MS / 1000))
        finally:
            d.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
