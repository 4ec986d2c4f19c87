"""test_modbus_watchdog.py: the Modbus HMI watchdog (docs/modbus.md,
"Commands": register 103) against the real daemon and a running job, with
raw Modbus/TCP frames (FC06, FC16, FC04):

- an HMI that never writes 103 is never subject to the watchdog: the job
  runs on past the watchdog time;
- the first write arms it; while the value keeps changing the job runs;
- once the value stops changing (writes of the same value do not count),
  the running job is paused after modbus_watchdog_ms, not before, and
  register 26 shows 20 (and the status bits say paused);
- a paused job does not advance; the resume command (100 = 1) resumes it
  and sets register 26 back to 0;
- the watchdog fires once: with 103 unchanged the resumed job keeps
  running; a new value re-arms it and it pauses the job again.
Usage: test_modbus_watchdog.py FREPMILLD FREPMILL"""
import os
import sys
import tempfile
import threading
import time

from daemon_util import (INSTRUMENTED, Daemon, check, curl_json, demo_job, modbus_port, modbus_read,
                         modbus_write, submit, wait_state)

WATCHDOG_MS = 1500
# How late after the watchdog time the pause may be seen: the server's loop
# ticks at least every heartbeat (docs/modbus.md) and this test polls HTTP
# every 50 ms, each poll a curl process (up to a second on a loaded
# machine). Instrumented daemons get twice the slack.
LATE_S = 6.0 if INSTRUMENTED else 3.0
# The live HMI writes a new value this often, from its own thread, so that
# slow HTTP polls never stretch its period towards the watchdog time.
ALIVE_PERIOD_S = 0.2
# The job must still be running after all the test's phases (some 15-25 s of
# unpaused work) and advance steadily: LAYERS layers of an 81-pass zigzag
# (166 motions each) on a 0.1 mm grid with one OpenVDB thread. Ten layers
# took about 45 s at load 17, and could end before the last phase on an idle
# machine (the "after the resume ... advancing" check failed once at load
# 8); forty last well beyond it. Cancelled at the end, so their length
# costs nothing.
VOXEL = 0.1
LAYERS = 40


def zigzag_job():
    lines = ["G21 G90", "T1 M6", "S10000 M3", "G0 Z5", "G0 X0 Y0", "G1 Z0 F1000"]
    for layer in range(1, LAYERS + 1):
        lines.append("G1 Z-%d" % layer)
        for i in range(81):
            lines.append("G1 X%d Y%.1f" % (40 if i % 2 == 0 else 0, 0.5 * i))
            lines.append("G1 Y%.1f" % (0.5 * i + 0.5))
        lines += ["G0 Z5", "G0 X0 Y0", "G1 Z-%d" % layer]
    lines.append("M2")
    job = demo_job(VOXEL, name="watchdog")
    job["stock"] = "box:0,0,-%d,40,40,0" % (LAYERS + 2)
    job["program"] = {"gcode": "\n".join(lines) + "\n"}
    job["options"]["check"] = False
    return job


def status(d, job_id):
    code, st = curl_json(d.url + "/v1/jobs/" + job_id)
    if code != 200:
        raise RuntimeError("GET status: %d %s" % (code, st))
    return st


def wait_paused(d, job_id, since, timeout):
    """Poll until the job is paused; returns seconds since `since`."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        st = status(d, job_id)
        if st["paused"]:
            return time.monotonic() - since
        if st["state"] != "running":
            raise RuntimeError("the job ended (%s) before the watchdog paused it" % st["state"])
        time.sleep(0.05)
    return None


def work_done(st):
    """How far the job got: motions, program time and removed volume (a
    long motion is cut in several batches, each published)."""
    return (st["motions_done"], st["program_time_s"], st["removed_volume_mm3"])


def work_settled(d, job_id, still_s=3.0 if INSTRUMENTED else 1.5, timeout=60):
    """work_done once it has not changed for still_s (a paused worker
    publishes once more when it reaches its next progress report)."""
    last = work_done(status(d, job_id))
    since = time.monotonic()
    deadline = since + timeout
    while time.monotonic() < deadline and time.monotonic() - since < still_s:
        time.sleep(0.25)
        now = work_done(status(d, job_id))
        if now != last:
            last, since = now, time.monotonic()
    return last


def main():
    frepmilld = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="fm-watchdog-") as tmp:
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1", "--threads-per-job", "1",
                   "--modbus-listen", "127.0.0.1:0", "--modbus-commands", "yes",
                   "--modbus-watchdog-ms", str(WATCHDOG_MS), "--publish-interval-s", "0.5")
        try:
            port = modbus_port(d)
            job_id = submit(d.url, zigzag_job(), tmp)
            wait_state(d.url, job_id, ("running",), 60)

            # Never written: twice the watchdog time passes, nothing happens.
            time.sleep(2 * WATCHDOG_MS / 1000)
            st = status(d, job_id)
            check(st["state"] == "running" and not st["paused"],
                  "103 never written: the job still runs after 2 watchdog periods")
            check(modbus_read(port, 26, 1)[0] == 0, "register 26 is 0 (no watchdog event)")

            # Armed and alive: a new value every 0.2 s for 3 s, from a thread.
            refused, done = [], threading.Event()

            def alive():
                value = 1
                while not done.is_set():
                    if modbus_write(port, 103, [value]) != 0:
                        refused.append(value)
                    value += 1
                    done.wait(ALIVE_PERIOD_S)

            writer = threading.Thread(target=alive)
            writer.start()
            paused_while_alive = False
            until = time.monotonic() + 2 * WATCHDOG_MS / 1000
            try:
                while time.monotonic() < until:
                    st = status(d, job_id)
                    paused_while_alive |= bool(st["paused"])
                    time.sleep(0.1)
            finally:
                done.set()
                writer.join()
            check(not refused, "FC06 writes of 103 accepted")
            check(not paused_while_alive and st["state"] == "running",
                  "103 changing every %.1f s for %.1f s: the job is not paused" % (
                      ALIVE_PERIOD_S, 2 * WATCHDOG_MS / 1000))

            # Silent HMI: the same value written again does not count.
            last_change = time.monotonic()
            check(modbus_write(port, 103, [60000]) == 0, "103 = 60000 (the last new value)")
            time.sleep(0.3)
            check(modbus_write(port, 103, [60000]) == 0, "103 = 60000 again")
            waited = wait_paused(d, job_id, last_change, WATCHDOG_MS / 1000 + LATE_S + 5)
            check(waited is not None and WATCHDOG_MS / 1000 - 0.05 <= waited <= WATCHDOG_MS / 1000 + LATE_S,
                  "the job paused %s s after 103 last changed (watchdog %d ms)" % (
                      "%.2f" % waited if waited else "never", WATCHDOG_MS))
            regs = modbus_read(port, 0, 29)
            check(regs[1] & 0x04 and regs[26] == 20,
                  "registers: paused bit set (status 0x%x), last error 20 (%d)" % (regs[1], regs[26]))
            check("HMI watchdog expired" in d.read_log(), "the expiry is logged")
            w1 = work_settled(d, job_id)
            time.sleep(1.0)
            st = status(d, job_id)
            check(st["paused"] and work_done(st) == w1,
                  "the paused job does not advance (motions, program time, removed: %s)" % (w1,))

            # Resume by command 1 (sequence 1): runs again, register 26 back to 0.
            check(modbus_write(port, 100, [1, 1, 0]) == 0, "FC16 100-102 = resume, sequence 1")
            deadline = time.monotonic() + 10
            while time.monotonic() < deadline and status(d, job_id)["paused"]:
                time.sleep(0.05)
            regs = modbus_read(port, 0, 29)
            check(regs[28] == 1 and regs[26] == 0,
                  "resume acknowledged (sequence %d), last error back to 0 (%d)" % (regs[28], regs[26]))

            # Fires once: 103 unchanged, the job keeps running (twice the
            # watchdog time at least) and advances.
            start = time.monotonic()
            while True:
                st = status(d, job_id)
                if st["paused"] or st["state"] != "running":
                    break
                if time.monotonic() - start >= 2 * WATCHDOG_MS / 1000 + 0.5 and work_done(st) > w1:
                    break
                if time.monotonic() - start > 20:
                    break
                time.sleep(0.1)
            check(st["state"] == "running" and not st["paused"] and work_done(st) > w1,
                  "after the resume, 103 unchanged: not paused again and advancing (%s -> %s)" % (
                      w1, work_done(st)))

            # A new value re-arms it.
            last_change = time.monotonic()
            check(modbus_write(port, 103, [60001]) == 0, "103 = 60001 re-arms the watchdog")
            waited = wait_paused(d, job_id, last_change, WATCHDOG_MS / 1000 + LATE_S + 5)
            check(waited is not None and WATCHDOG_MS / 1000 - 0.05 <= waited <= WATCHDOG_MS / 1000 + LATE_S,
                  "re-armed: the job paused again %s s after the new value" % (
                      "%.2f" % waited if waited else "never"))
            check(modbus_read(port, 26, 1)[0] == 20, "register 26 is 20 again")

            # Cancel (command 3, sequence 2): the test needs no more of the job.
            check(modbus_write(port, 100, [3, 2, 0]) == 0, "FC16 cancel, sequence 2")
            st = wait_state(d.url, job_id, ("cancelled", "done", "failed"), 60)
            check(st["state"] == "cancelled", "the job was cancelled")
        finally:
            rc = d.stop()
            if rc != 0:
                print(d.read_log()[-6000:])
        check(rc == 0, "the daemon stopped cleanly")
    return 0


if __name__ == "__main__":
    sys.exit(main())
