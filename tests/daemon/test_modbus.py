"""test_modbus.py: the Modbus "done when" of issue 10 against the real
daemon and a real job. Debian's mbpoll reads the status and float registers
while the job runs and sees the block number (N words of the program) advance
and the heartbeat tick; the Node client from npm (modbus-serial) writes the
pause and resume commands and the job pauses and resumes, as its HTTP status
shows. Usage: test_modbus.py FREPMILLD FREPMILL"""
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time

from daemon_util import DEMO, COARSE, INSTRUMENTED, Daemon, check, curl_json, demo_job, modbus_port, skip, submit, wait_state
from test_live import client, need_node_client


# Instrumented (sanitizer build), the daemon is several times slower and the
# job's set-up (the stock, its first meshes) comes before its first blocks:
# a coarser grid and a longer polling window there. The window only bounds
# the wait; the test reads the same registers.
VOXEL = 0.4 if COARSE else 0.1
POLL_S = 180 if INSTRUMENTED else 60


def numbered_demo():
    """The demo program with an N word on every line that moves: N10, N20...,
    and before its M5 ten layers of a zigzag over the block: the job must
    still be cutting when the test pauses it (about 1.5 s in). In the
    optimized build the demo alone at 0.2 mm took 0.56 s, and the pause
    came after its last motion once (CI, "a paused job does not advance
    (motion 284)"); with these layers, one thread and 0.1 mm it takes some
    6 s on two idle cores."""
    with open(os.path.join(DEMO, "pocket.ngc")) as f:
        lines = f.read().splitlines()
    end = max(i for i, line in enumerate(lines) if line.strip() == "M5")
    extra = ["G0 Z5", "G0 X10 Y10", "G1 Z0 F1000"]
    for layer in range(1, 11):
        extra.append("G1 Z-%d" % layer)
        for p in range(41):
            extra.append("G1 X%d Y%d" % (90 if p % 2 == 0 else 10, 10 + p))
            extra.append("G1 Y%.1f" % (10 + p + 0.5))
        extra += ["G0 Z5", "G0 X10 Y10"]
    out, n = [], 0
    for line in lines[:end] + extra + lines[end:]:
        if re.match(r"\s*G[0-3]\b", line):
            n += 10
            line = "N%d %s" % (n, line)
        out.append(line + "\n")
    return "".join(out), n


def mbpoll(port, *args):
    out = subprocess.run(["mbpoll", "-m", "tcp", "-a", "1", "-0", "-1", "-p", str(port), *args,
                          "127.0.0.1"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=20)
    if out.returncode != 0:
        raise RuntimeError("mbpoll %s: %s" % (args, out.stderr.decode() + out.stdout.decode()))
    return {int(a): float(b) for a, b in re.findall(r"^\[(\d+)\]:\s+(\S+)", out.stdout.decode(), re.M)}


def settled_status(url, job_id, still_s, timeout_s):
    """The job's status once motions_done has not changed for still_s."""
    code, last = curl_json(url + "/v1/jobs/" + job_id)
    since = time.time()
    deadline = since + timeout_s
    while time.time() < deadline and time.time() - since < still_s:
        time.sleep(0.25)
        code, now = curl_json(url + "/v1/jobs/" + job_id)
        if now["motions_done"] != last["motions_done"]:
            since = time.time()
        last = now
    return last


def main():
    frepmilld, frepmill = sys.argv[1], sys.argv[2]
    if not shutil.which("mbpoll"):
        skip("mbpoll is not installed (Debian package mbpoll)")
    need_node_client()
    with tempfile.TemporaryDirectory(prefix="fm-modbus-") as tmp:
        t0 = time.time()
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1",
                   "--threads-per-job", "1",
                   "--modbus-listen", "127.0.0.1:0", "--modbus-commands", "yes",
                   "--publish-interval-s", "0.2")
        try:
            port = modbus_port(d)
            program, last_n = numbered_demo()
            job = demo_job(VOXEL, name="numbered")
            job["program"] = {"gcode": program}
            job["options"]["check"] = False
            job_id = submit(d.url, job, tmp)
            wait_state(d.url, job_id, ("running",), 60)
            blocks, beats, floats_ok = [], [], False
            deadline = time.time() + POLL_S
            last_f = None
            while time.time() < deadline and (len(set(blocks)) < 3 or not floats_ok):
                regs = mbpoll(port, "-t", "3", "-r", "0", "-c", "3")
                beats.append(regs[2])
                blocks.append(mbpoll(port, "-t", "3:int", "-B", "-r", "3", "-c", "1")[3])
                f = mbpoll(port, "-t", "3:float", "-B", "-r", "9", "-c", "6")
                last_f = f
                floats_ok = floats_ok or (0 <= f[9] <= 100 and 0 <= f[11] <= 60 and f[17] > 0)
                time.sleep(0.3)
            check(len(set(blocks)) >= 3 and all(b2 >= b1 for b1, b2 in zip(blocks, blocks[1:])),
                  "mbpoll sees the block number advance (%s)" % sorted(set(blocks))[:6])
            check(all(0 < b <= last_n and b % 10 == 0 for b in set(blocks) if b),
                  "block numbers are the program's N words")
            check(len(set(beats)) >= 3, "mbpoll sees the heartbeat tick (%d values)" % len(set(beats)))
            check(abs(last_f[17] + last_f[19] - 100 * 60 * 30) <= 1.0,
                  "removed + remaining volume = the 100 x 60 x 30 mm box")
            check(floats_ok, "float registers: tool tip inside the stock's XY, removed volume > 0 (%s)" % last_f)

            out = client(port, "cmd:2,1,0")
            check(out == ["command 2,1,0"], "the Node client wrote pause")
            deadline = time.time() + 20
            while time.time() < deadline:
                code, status = curl_json(d.url + "/v1/jobs/" + job_id)
                if status["paused"] or status["state"] != "running":
                    break
                time.sleep(0.1)
            check(status["paused"] and status["state"] == "running", "HTTP shows the job paused")
            # The worker holds at its next progress report, after the batch
            # of cuts it is in (a second or more under the sanitizers), and
            # publishes its count once more there: wait for that, then the
            # count must hold still.
            s1 = settled_status(d.url, job_id, 2.0, 60)
            time.sleep(1.0)
            code, s2 = curl_json(d.url + "/v1/jobs/" + job_id)
            check(s1["motions_done"] == s2["motions_done"] and s2["paused"] and s2["state"] == "running",
                  "a paused job does not advance (motion %d)" % s2["motions_done"])
            regs = mbpoll(port, "-t", "3", "-r", "0", "-c", "29")
            check(int(regs[1]) & 0x04 and int(regs[28]) == 1 and int(regs[26]) == 0,
                  "registers: paused bit, sequence 1 acknowledged, no error")
            out = client(port, "cmd:1,2,0")
            status = wait_state(d.url, job_id, ("done", "failed", "cancelled"), 300)
            check(status["state"] == "done" and not status["paused"],
                  "after the resume command the job finished")
            regs = mbpoll(port, "-t", "3", "-r", "0", "-c", "29")
            check(int(regs[1]) & 0x08 and int(regs[28]) == 2 and int(regs[7]) == 1000,
                  "registers: done bit, sequence 2 acknowledged, progress 1000 per mille")
        finally:
            rc = d.stop()
            if rc != 0:
                print(d.read_log()[-6000:])
        check(rc == 0, "the daemon stopped cleanly")
        print("test_modbus: %.1f s" % (time.time() - t0))


if __name__ == "__main__":
    main()
