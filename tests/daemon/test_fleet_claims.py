"""test_fleet_claims.py: the claim promises of the Redis Streams job queue
(docs/fleet.md, "How a job moves" and "Failures"), one scenario each, each
on its own redis-server:

1. restart: a daemon killed with SIGKILL and started again under the same
   consumer name takes its pending entry back at once (queue_claim_s is 60 s:
   no idle timeout explains it) and resumes the job from its snapshot
   (resuming at motion N > 0); the resumed job's removed volume equals a
   rerun's of the same job (another entry, cut from the start) and the
   closed form.
2. lost claim: daemon a runs an entry, paused (Modbus) so that it cannot
   end first, and is stopped (SIGSTOP, a partition longer than
   queue_claim_s); daemon b claims the entry and runs it; a,
   continued, finds at its next renewal that b owns the entry, releases the
   job ("stopped by its queue") and writes no result; b's result is the
   only one, right, and nothing is left pending.
3. two daemons finish one entry: a result and a done record are already
   there (another daemon finished first, as after a partition) when this
   daemon finishes the entry: HSETNX keeps the first result, no second done
   record is added, and the entry is acknowledged.
Usage: test_fleet_claims.py FREPMILLD FREPMILL [SCENARIO...] (restart,
lost_claim, second_finish; default all)"""
import json
import math
import os
import re
import signal
import sys
import tempfile
import time

from daemon_util import COARSE, INSTRUMENTED, Daemon, check, curl_json, modbus_port, modbus_write
from redis_util import RedisServer, need_redis_server

# 0.1 mm: a job of 8 slots cuts for a few seconds in the optimized build,
# long enough to be caught running with a snapshot and to outlast a stop.
# Instrumented (sanitizer build, several times slower): 0.2 mm, the same
# checks, doubled waits.
VOXEL = 0.2 if COARSE else 0.1
SCALE = 2 if INSTRUMENTED else 1
RADIUS = 3.0      # 6 mm flat end mill
LENGTH = 80.0     # each slot's straight length
# The tolerance test_fleet states against the closed form; a resumed job
# and a rerun each meet it, and so they differ from each other by at most
# twice it.
REL_TOL = 2e-4
WAIT_S = 300     # bounds only: each job takes about a second on an idle machine
CLAIM_S = 60     # the restart scenario's queue_claim_s
TOOLS = {"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 2 * RADIUS,
                                    "flute_length": 20, "length": 40}]}


def slot_job(name, slots, depth=1.5):
    """slots parallel slots 8 mm apart (plunge, straight move, retract):
    each the stadium 2 r L + pi r^2 times the depth; they do not touch."""
    lines = ["G21 G90 G17", "T1 M6", "S10000 M3", "G0 Z5"]
    for i in range(slots):
        y = 6 + 8 * i
        lines += ["G0 X10 Y%g" % y, "G1 Z%g F300" % -depth, "G1 X%g F1000" % (10 + LENGTH),
                  "G0 Z5"]
    lines.append("M30")
    job = {"stock": "box:0,0,-10,100,%g,0" % (12 + 8 * slots), "voxel": VOXEL, "tools": TOOLS,
           "program": {"gcode": "\n".join(lines) + "\n"},
           "options": {"name": name, "check": False, "color": "none"}}
    volume = slots * depth * (2 * RADIUS * LENGTH + math.pi * RADIUS ** 2)
    return job, volume


def queue_args(port, consumer, claim_s):
    return ("--queue", "redis://127.0.0.1:%d" % port, "--queue-consumer", consumer,
            "--queue-claim-s", str(claim_s), "--workers", "1", "--snapshot-interval-s", "0.3",
            "--publish-interval-s", "2")


def wait_for(what, cond, timeout):
    deadline = time.time() + timeout * SCALE
    while time.time() < deadline:
        v = cond()
        if v:
            return v
        time.sleep(0.05)
    raise AssertionError("%s: not within %g s" % (what, timeout * SCALE))


def job_status(d, job_id):
    code, body = curl_json(d.url + "/v1/jobs/" + job_id)
    return body if code == 200 else None


def running_job(d, job_id, min_progress, snapshot=None):
    """The job's status once it runs past min_progress (with its snapshot
    on disk if given), else None; fails at once if it ended first."""
    st = job_status(d, job_id)
    if st and st["state"] in ("done", "failed", "cancelled"):
        raise AssertionError("job %s ended (%s) before the test caught it running" %
                             (job_id, st["state"]))
    if st and st["state"] == "running" and st["progress"] > min_progress and \
            (snapshot is None or os.path.exists(snapshot)):
        return st
    return None


def result(r, entry):
    raw = r("HGET", "frepmill:results", entry)
    return json.loads(raw) if raw else None


def done_entries(r):
    done = r("XRANGE", "frepmill:done", "-", "+")
    return [dict(zip(f[0::2], f[1::2]))[b"entry"].decode() for _, f in done]


def pending_of(r, entry):
    """The consumer that holds entry pending, or None."""
    p = r("XPENDING", "frepmill:jobs", "frepmilld", entry, entry, 1)
    return p[0][1].decode() if p else None


def check_volume(res, volume, what):
    check(res is not None and res["state"] == "done", "%s is done (%s)" %
          (what, res and res.get("error")))
    got = res["removed_volume_mm3"]
    rel = abs(got - volume) / volume
    check(rel < REL_TOL, "%s removed %.3f mm3, closed form %.3f (%.2e)" % (what, got, volume, rel))
    return got


def scenario_restart(frepmilld, server_bin, tmp, daemons):
    redis = RedisServer(server_bin, os.path.join(tmp, "redis1"))
    try:
        r = redis.client()
        job, volume = slot_job("resumed", 8)
        entry = r("XADD", "frepmill:jobs", "*", "job", json.dumps(job)).decode()
        job_id = "q-" + entry
        state = os.path.join(tmp, "a1")
        args = queue_args(redis.port, "a", CLAIM_S) + ("--modbus-listen", "127.0.0.1:0",
                                                     "--modbus-commands", "yes")
        a = Daemon(frepmilld, state, *args)
        daemons.append(a)
        snap = os.path.join(state, "jobs", job_id, "stock.vdb")
        st = wait_for("a runs the entry with a snapshot",
                      lambda: running_job(a, job_id, 0.15, snap), WAIT_S)
        # Paused (Modbus) so that it cannot end before the kill, however
        # loaded the machine; a pause is not kept across a restart.
        check(modbus_write(modbus_port(a), 100, [2, 1, 0]) == 0, "Modbus pause of a's job")
        st = wait_for("a's job paused", lambda: (job_status(a, job_id) or {}).get("paused") and
                      job_status(a, job_id), WAIT_S)
        check(st["state"] == "running" and st["progress"] < 1,
              "a killed mid-job (progress %.2f)" % st["progress"])
        a.stop(signal.SIGKILL)
        daemons.remove(a)
        check(pending_of(r, entry) == "a", "the entry stays pending on consumer a")

        started = time.time()
        a = Daemon(frepmilld, state, *args)
        daemons.append(a)
        # queue_claim_s is 60: an entry taken back by the idle timeout would
        # take a minute; at once is at the daemon's first connect (bounded
        # here by half the claim time, for a loaded machine).
        wait_for("the restarted a takes its entry back", lambda: "job %s: taken from the queue "
                 "again" % job_id in a.read_log(), CLAIM_S / 2 / SCALE)
        taken_s = time.time() - started
        check(taken_s < CLAIM_S / 2, "restarted under the same name, a took its entry back in "
              "%.1f s (queue_claim_s %d)" % (taken_s, CLAIM_S))
        wait_for("the job resumes", lambda: "job %s: resuming" % job_id in a.read_log(), WAIT_S)
        m = re.search(r"job %s: resuming from its snapshot at motion (\d+)" % job_id, a.read_log())
        check(m and int(m.group(1)) > 0, "the job resumed at motion %s, not from the start" %
              (m.group(1) if m else None))
        wait_for("the resumed entry's result", lambda: result(r, entry), WAIT_S)
        resumed = check_volume(result(r, entry), volume, "the resumed job")

        # The same job again, as a new entry: cut from its start.
        rerun_entry = r("XADD", "frepmill:jobs", "*", "job", json.dumps(job)).decode()
        wait_for("the rerun's result", lambda: result(r, rerun_entry), WAIT_S)
        rerun = check_volume(result(r, rerun_entry), volume, "the rerun")
        check(not re.search(r"job q-%s: resuming" % rerun_entry, a.read_log()),
              "the rerun was cut from its start")
        check(abs(resumed - rerun) <= 2 * REL_TOL * volume,
              "resumed %.3f mm3 vs rerun %.3f mm3 (%.2e of the volume)" %
              (resumed, rerun, abs(resumed - rerun) / volume))
        check(done_entries(r) == [entry, rerun_entry], "one done record each")
        check(r("XPENDING", "frepmill:jobs", "frepmilld")[0] == 0, "nothing left pending")
        r.close()
    finally:
        redis.stop()


def scenario_lost_claim(frepmilld, server_bin, tmp, daemons):
    redis = RedisServer(server_bin, os.path.join(tmp, "redis2"))
    try:
        r = redis.client()
        job, volume = slot_job("contested", 8)
        entry = r("XADD", "frepmill:jobs", "*", "job", json.dumps(job)).decode()
        job_id = "q-" + entry
        # Modbus commands: a's job is paused (held between cuts) before the
        # partition, so that it cannot finish before a notices the loss,
        # however loaded the machine; a release ends a pause (jobs.c).
        a = Daemon(frepmilld, os.path.join(tmp, "a2"), *queue_args(redis.port, "a", 2),
                   "--modbus-listen", "127.0.0.1:0", "--modbus-commands", "yes")
        daemons.append(a)
        wait_for("a runs the entry", lambda: running_job(a, job_id, 0.0), WAIT_S)
        check(modbus_write(modbus_port(a), 100, [2, 1, 0]) == 0, "Modbus pause of a's job")
        st = wait_for("a's job paused", lambda: (job_status(a, job_id) or {}).get("paused") and
                      job_status(a, job_id), WAIT_S)
        a.proc.send_signal(signal.SIGSTOP)   # a partition: a neither cuts nor renews
        try:
            check(st["state"] == "running" and st["progress"] < 1,
                  "a's job paused unfinished (progress %.2f)" % st["progress"])
            b = Daemon(frepmilld, os.path.join(tmp, "b2"), *queue_args(redis.port, "b", 2))
            daemons.append(b)
            # b claims the entry once it has been idle for queue_claim_s (2 s).
            wait_for("b claims the idle entry", lambda: pending_of(r, entry) == "b", 30)
            check(result(r, entry) is None, "b claimed the entry before any result")
        finally:
            a.proc.send_signal(signal.SIGCONT)
        pat = "job %s: stopped by its queue (another daemon has it)" % job_id
        # a renews every queue_claim_s / 3, at once after the stop.
        wait_for("a releases the entry b owns", lambda: pat in a.read_log(), 30)
        check("entry %s went to another consumer" % entry in a.read_log(),
              "a noticed at its renewal that b owns the entry")
        st = job_status(a, job_id)
        check(st["state"] == "queued", "a's job is held, not finished (%s)" % st["state"])
        wait_for("b's result", lambda: result(r, entry), WAIT_S)
        res = result(r, entry)
        check_volume(res, volume, "b's run of the entry")
        check("entry %s: result written" % entry in b.read_log(), "the result is b's")
        time.sleep(0.5)  # a's queue thread would have written a result by now
        check("entry %s: result" % entry not in a.read_log(), "a wrote no result")
        check(done_entries(r) == [entry], "one done record")
        check(r("XPENDING", "frepmill:jobs", "frepmilld")[0] == 0, "nothing left pending")
        st = job_status(a, job_id)
        check(st["state"] == "queued", "a's released job stays held (%s)" % st["state"])
        r.close()
    finally:
        redis.stop()


def scenario_second_finish(frepmilld, server_bin, tmp, daemons):
    redis = RedisServer(server_bin, os.path.join(tmp, "redis3"))
    try:
        r = redis.client()
        job, _ = slot_job("finished-twice", 1)
        entry = r("XADD", "frepmill:jobs", "*", "job", json.dumps(job)).decode()
        # Another daemon finished the entry first (its finish script's
        # writes), but had not acknowledged it: this daemon runs it too.
        first = json.dumps({"entry": entry, "state": "done", "name": "the first daemon's"})
        r("HSET", "frepmill:results", entry, first)
        r("XADD", "frepmill:done", "*", "entry", entry)
        d = Daemon(frepmilld, os.path.join(tmp, "a3"), *queue_args(redis.port, "a", 2))
        daemons.append(d)
        pat = "entry %s: result already written by another" % entry
        wait_for("the second finish", lambda: pat in d.read_log(), WAIT_S)
        st = job_status(d, "q-" + entry)
        check(st and st["state"] == "done", "this daemon ran the entry to its end")
        check(r("HGET", "frepmill:results", entry).decode() == first,
              "the first result is kept (HSETNX), not replaced")
        check(done_entries(r) == [entry], "no second done record")
        check(r("XPENDING", "frepmill:jobs", "frepmilld")[0] == 0,
              "the entry is acknowledged all the same")
        r.close()
    finally:
        redis.stop()


def main():
    frepmilld = sys.argv[1]
    server_bin = need_redis_server()
    with tempfile.TemporaryDirectory(prefix="fm-fleet-claims-") as tmp:
        daemons = []
        try:
            names = sys.argv[3:] or ["restart", "lost_claim", "second_finish"]
            for scenario in [globals()["scenario_" + n] for n in names]:
                print("==== %s" % scenario.__name__)
                scenario(frepmilld, server_bin, tmp, daemons)
                for d in list(daemons):
                    # a clean stop: under the sanitizers a leak or an error
                    # found at exit is a non-zero status
                    rc = d.stop()
                    daemons.remove(d)
                    check(rc == 0, "%s stopped cleanly (status %s)" % (d.state_dir, rc))
        except BaseException:
            for d in daemons:
                print("---- last lines of %s" % d.log_path)
                print("\n".join(d.read_log().splitlines()[-40:]))
            raise
        finally:
            for d in daemons:
                try:
                    if d.proc.poll() is None:
                        d.proc.send_signal(signal.SIGCONT)
                    d.stop()
                except Exception as e:  # report, then go on stopping the rest
                    print("stop:", e)


if __name__ == "__main__":
    main()
