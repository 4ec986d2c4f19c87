"""test_crash.py: kill -9 during a job, restart, and find the job resumed
from its last snapshot (not from the start) and finished with the removed
volume of an uninterrupted run (the CLI, same pipeline), within a voxel
tolerance. Also: a job acknowledged just before the kill is not lost.
Usage: test_crash.py FREPMILLD FREPMILL"""
import os
import re
import signal
import sys
import tempfile
import time

from daemon_util import COARSE, INSTRUMENTED, Daemon, check, cli_reference, curl_json, demo_job, submit, wait_state

# Instrumented (sanitizer build): a coarser grid, for a daemon several times
# slower; wait_state doubles its bound there itself (the same checks).
VOXEL = 0.4 if COARSE else 0.25
WAIT_S = 300


def main():
    frepmilld, frepmill = sys.argv[1], sys.argv[2]
    with tempfile.TemporaryDirectory(prefix="fm-crash-") as tmp:
        ref = cli_reference(frepmill, VOXEL, tmp)
        state = os.path.join(tmp, "state")
        d = Daemon(frepmilld, state, "--workers", "1", "--snapshot-interval-s", "0.5")
        try:
            job_id = submit(d.url, demo_job(VOXEL), tmp)
            snap = os.path.join(state, "jobs", job_id, "stock.vdb")
            deadline = time.time() + (300 if INSTRUMENTED else 120)
            progress = 0
            while time.time() < deadline:
                code, status = curl_json(d.url + "/v1/jobs/" + job_id)
                progress = status["progress"]
                if status["state"] == "done":
                    break
                if progress >= 0.3 and os.path.exists(snap):
                    break
                time.sleep(0.1)
            check(status["state"] == "running" and os.path.exists(snap),
                  "job running at progress %.2f with a snapshot on disk" % progress)
            second = submit(d.url, demo_job(VOXEL, "second"), tmp)  # queued behind the first
        finally:
            d.stop(signal.SIGKILL)
        check(d.proc.returncode == -signal.SIGKILL, "daemon killed with SIGKILL")

        d = Daemon(frepmilld, state, "--workers", "1", "--snapshot-interval-s", "0.5")
        try:
            status = wait_state(d.url, job_id, ("done", "failed"), WAIT_S)
            log = d.read_log()
            m = re.search(r"job %s: resuming from its snapshot at motion (\d+)" % job_id, log)
            check(m and int(m.group(1)) > 0, "resumed at motion %s, not from the start" %
                  (m.group(1) if m else None))
            check(status["state"] == "done", "the resumed job is done")
            removed = status["removed_volume_mm3"]
            # Resuming changes only where batches of motions start (job.h), so
            # the difference is a few voxels' worth along the cut surface.
            tol = 0.002 * ref["removed_volume_mm3"]
            check(abs(removed - ref["removed_volume_mm3"]) <= tol,
                  "removed %.2f mm3 vs uninterrupted %.2f mm3 (tolerance %.2f)" %
                  (removed, ref["removed_volume_mm3"], tol))
            s2 = wait_state(d.url, second, ("done", "failed"), WAIT_S)
            check(s2["state"] == "done", "the job acknowledged before the kill ran after restart")
        finally:
            d.stop()
        # A third start finds both finished, with their results.
        d = Daemon(frepmilld, state, "--workers", "1")
        try:
            code, status = curl_json(d.url + "/v1/jobs/" + job_id)
            check(code == 200 and status["state"] == "done" and
                  abs(status["removed_volume_mm3"] - removed) < 1e-6,
                  "after another restart the finished job keeps its result")
            code, lst = curl_json(d.url + "/v1/jobs")
            check(len(lst["jobs"]) == 2, "both jobs are listed")
        finally:
            d.stop()
    return 0


if __name__ == "__main__":
    sys.exit(main())
