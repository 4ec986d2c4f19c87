"""test_fleet.py: several frepmilld on one Redis Streams job queue
(docs/fleet.md). redis-server runs on a free loopback port; two daemons
consume the queue; 8 jobs whose removed volumes have closed forms and two
bad entries are queued; one daemon is killed with SIGKILL while it runs
a job and another is started on its state folder; redis-server is stopped
and started again mid-run. Then: exactly one result per entry (9 in the
results hash, 9 distinct entries on the done stream, nothing pending),
every job's volume right, a malformed and an oversized entry one `failed`
result each.
Usage: test_fleet.py FREPMILLD FREPMILL"""
import json
import math
import os
import signal
import sys
import tempfile
import time

from daemon_util import COARSE, INSTRUMENTED, Daemon, check, curl_json
from redis_util import RedisServer, need_redis_server

# 0.1 mm: a job then cuts for over a second on an idle machine, long enough
# to be caught running with a snapshot (at 0.2 mm the cuts took 0.3 s, under
# the snapshot interval, and the victim was never found). Instrumented
# (sanitizer build, several times slower): 0.2 mm and 4 jobs, which still
# run long enough; longer waits (bounds only), the same checks.
VOXEL = 0.2 if COARSE else 0.1
RADIUS = 3.0      # 6 mm flat end mill
LENGTH = 80.0     # each slot's straight length
SLOTS = 4
JOBS = 4 if COARSE else 8
WAIT_S = 600 if INSTRUMENTED else 300
TOOLS = {"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 2 * RADIUS,
                                    "flute_length": 20, "length": 40}]}


def slot_job(k):
    """SLOTS parallel slots 15 mm apart, depth 1 + k/4 mm: each the stadium
    2 r L + pi r^2 (plunge at one end, straight move, retract) times the
    depth; the slots do not touch."""
    depth = 1.0 + 0.25 * k
    lines = ["G21 G90 G17", "T1 M6", "S10000 M3", "G0 Z5"]
    for i in range(SLOTS):
        y = 10 + 15 * i
        lines += ["G0 X10 Y%g" % y, "G1 Z%g F300" % -depth, "G1 X%g F1000" % (10 + LENGTH),
                  "G0 Z5"]
    lines.append("M30")
    job = {"stock": "box:0,0,-20,100,80,0", "voxel": VOXEL, "tools": TOOLS,
           "program": {"gcode": "\n".join(lines) + "\n"},
           "options": {"name": "slots-%d" % k, "check": False, "color": "none"}}
    volume = SLOTS * depth * (2 * RADIUS * LENGTH + math.pi * RADIUS ** 2)
    return job, volume


def queue_args(port, consumer):
    return ("--queue", "redis://127.0.0.1:%d" % port, "--queue-consumer", consumer,
            "--queue-claim-s", "2", "--workers", "1", "--snapshot-interval-s", "0.3",
            "--publish-interval-s", "2", "--max-request-mb", "0.004")


def main():
    frepmilld = sys.argv[1]
    server_bin = need_redis_server()
    with tempfile.TemporaryDirectory(prefix="fm-fleet-") as tmp:
        redis = RedisServer(server_bin, os.path.join(tmp, "redis"))
        daemons = []
        try:
            r = redis.client()
            expected = {}
            for k in range(JOBS):
                job, volume = slot_job(k)
                entry = r("XADD", "frepmill:jobs", "*", "job", json.dumps(job)).decode()
                expected[entry] = volume
            bad = r("XADD", "frepmill:jobs", "*", "job", "{not json").decode()
            # Over the daemons' request budget (--max-request-mb 0.004: 4194
            # bytes): refused from its size, before its text is read.
            big_job, _ = slot_job(0)
            big_job["program"]["gcode"] += "(%s)\n" % ("x" * 8000)
            big = r("XADD", "frepmill:jobs", "*", "job", json.dumps(big_job)).decode()
            r.close()

            a = Daemon(frepmilld, os.path.join(tmp, "a"), *queue_args(redis.port, "a"))
            b = Daemon(frepmilld, os.path.join(tmp, "b"), *queue_args(redis.port, "b"))
            daemons += [a, b]

            # Kill daemon a while it runs a job, once that job has a snapshot.
            victim = None
            deadline = time.time() + WAIT_S * 4 / 5
            while time.time() < deadline and not victim:
                code, body = curl_json(a.url + "/v1/jobs")
                for st in body["jobs"] if code == 200 else []:
                    snap = os.path.join(a.state_dir, "jobs", st["id"], "stock.vdb")
                    if st["state"] == "running" and st["progress"] > 0.1 and os.path.exists(snap):
                        victim = st["id"]
                        break
                time.sleep(0.05)
            check(victim is not None, "daemon a runs a queue job with a snapshot (%s)" % victim)
            a.proc.send_signal(signal.SIGKILL)
            a.proc.wait(timeout=10)
            a.log.close()
            daemons.remove(a)
            # Another daemon on a's state folder: it may resume a's job from
            # its snapshot once the entry is idle past queue_claim_s.
            c = Daemon(frepmilld, a.state_dir, *queue_args(redis.port, "c"))
            daemons.append(c)

            # Redis goes away and comes back mid-run.
            time.sleep(1.0)
            redis.stop()
            time.sleep(1.5)
            redis.start()

            r = redis.client()
            deadline = time.time() + WAIT_S
            while time.time() < deadline and r("XLEN", "frepmill:done") < JOBS + 2:
                time.sleep(0.2)
            done = r("XRANGE", "frepmill:done", "-", "+")
            entries = [dict(zip(f[0::2], f[1::2]))[b"entry"].decode() for _, f in done]
            check(len(entries) == JOBS + 2, "%d entries on frepmill:done (expected %d)" %
                  (len(entries), JOBS + 2))
            check(len(set(entries)) == len(entries), "no entry finished twice")
            check(r("HLEN", "frepmill:results") == JOBS + 2, "%d results" % (JOBS + 2))
            pending = r("XPENDING", "frepmill:jobs", "frepmilld")
            check(pending[0] == 0, "nothing left pending (XPENDING %s)" % pending[0])

            for entry, volume in expected.items():
                res = json.loads(r("HGET", "frepmill:results", entry))
                check(res["state"] == "done", "entry %s done (%s)" % (entry, res.get("error")))
                got = res["removed_volume_mm3"]
                rel = abs(got - volume) / volume
                check(rel < 2e-4, "entry %s removed %.3f mm3, closed form %.3f (%.2e)" %
                      (entry, got, volume, rel))
                check(res["entry"] == entry and res["name"].startswith("slots-"),
                      "entry %s's result names it" % entry)
            res = json.loads(r("HGET", "frepmill:results", bad))
            check(res["state"] == "failed" and res["error"]["code"] == "bad_json",
                  "the malformed entry has one failed result (%s)" % res["error"])
            res = json.loads(r("HGET", "frepmill:results", big))
            check(res["state"] == "failed" and res["error"]["code"] == "too_large",
                  "the oversized entry has one failed result (%s)" % res["error"])
            r.close()
            logs = "".join(d.read_log() for d in daemons)
            print("c resumed a's job from its snapshot:" if "resuming from its snapshot" in
                  c.read_log() else "a's job was claimed and rerun from its start:", victim)
            check("reconnecting" in logs, "the daemons saw Redis go and reconnected")
        except BaseException:
            for d in daemons:
                print("---- last lines of %s" % d.log_path)
                print("\n".join(d.read_log().splitlines()[-40:]))
            raise
        finally:
            for d in daemons:
                try:
                    d.stop()
                except Exception as e:  # report, then go on stopping the rest
                    print("stop:", e)
            redis.stop()


if __name__ == "__main__":
    main()
