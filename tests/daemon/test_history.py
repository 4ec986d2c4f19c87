"""test_history.py: the daemon's mesh history (issue 18): GET
/v1/jobs/ID/chunks?at=T lists each chunk's mesh as it was at program time T,
and the history stays within mesh_history_mb, dropping the oldest versions
and saying from when it is complete (history_from_s; earlier times are 410
history_dropped). Usage: test_history.py FREPMILLD FREPMILL"""
import os
import sys
import tempfile

from daemon_util import Daemon, check, curl, curl_json, demo_job, submit, wait_state

VOXEL = 0.25


def chunks(url, job_id, query):
    code, body = curl_json(url + "/v1/jobs/%s/chunks?%s" % (job_id, query))
    return code, body


def triangles(listing):
    return sum(c["triangles"] for c in listing["chunks"])


def main():
    frepmilld = sys.argv[1]
    with tempfile.TemporaryDirectory(prefix="fm-history-") as tmp:
        # The default bound (64 MB): the whole history of a small job.
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1",
                   "--publish-interval-s", "0.05")
        try:
            job_id = submit(d.url, demo_job(VOXEL), tmp)
            uncut = demo_job(VOXEL, name="uncut")
            uncut["program"] = {"gcode": "G21 G90\nM2\n"}
            uncut_id = submit(d.url, uncut, tmp)
            status = wait_state(d.url, job_id, ("done", "failed"), 300)
            check(status["state"] == "done", "the demo job is done")
            wait_state(d.url, uncut_id, ("done",), 300)
            code, now = chunks(d.url, job_id, "since=0")
            check(code == 200 and now["history_from_s"] == 0,
                  "the history is complete from program time 0 (%s s, %d bytes)"
                  % (now["history_from_s"], now["history_bytes"]))
            check(now["history_bytes"] <= 64 * 1048576, "within the default 64 MB bound")
            times = sorted({c["time_s"] for c in now["chunks"]})
            end_t = status["program_time_s"]
            code, at0 = chunks(d.url, job_id, "at=0")
            code_u, u = chunks(d.url, uncut_id, "since=0")
            check(code == 200 and code_u == 200 and triangles(at0) == triangles(u),
                  "at t=0 the chunks are the uncut stock's: %d triangles = a job that cuts "
                  "nothing (%d)" % (triangles(at0), triangles(u)))
            check(triangles(at0) != triangles(now), "... not the final stock's (%d)" % triangles(now))
            code, at_end = chunks(d.url, job_id, "at=%r" % (end_t + 1))
            same = {c["id"]: c["version"] for c in at_end["chunks"]} == \
                {c["id"]: c["version"] for c in now["chunks"]}
            check(code == 200 and same, "after the end (t=%.3f s) the chunks are the current ones" % (end_t + 1))
            # Each chunk's version never goes back as the time goes on, and
            # each listed version is downloadable with its listed size.
            samples = [end_t * k / 8 for k in range(9)]
            prev, versions_seen = {}, set()
            for t in samples:
                code, at = chunks(d.url, job_id, "at=%r" % t)
                check(code == 200, "GET chunks?at=%.3f: %d chunks, %d triangles"
                      % (t, len(at["chunks"]), triangles(at)))
                for c in at["chunks"]:
                    if c["time_s"] > t + 1e-6:
                        check(False, "chunk %s's version %d is from t=%.3f, after %.3f"
                              % (c["id"], c["version"], c["time_s"], t))
                    if c["id"] in prev and c["version"] < prev[c["id"]]:
                        check(False, "chunk %s went back from version %d to %d at t=%.3f"
                              % (c["id"], prev[c["id"]], c["version"], t))
                    prev[c["id"]] = c["version"]
                    versions_seen.add(c["version"])
            check(len(versions_seen) >= 3, "the samples show %d distinct mesh versions" % len(versions_seen))
            code, mid = chunks(d.url, job_id, "at=%r" % samples[4])
            for c in mid["chunks"]:
                if not c["triangles"]:
                    continue
                code, body = curl(d.url + "/v1/jobs/%s/chunks/%s.drc?v=%d" % (job_id, c["id"], c["version"]))
                if code != 200 or len(body) != c["bytes"]:
                    check(False, "chunk %s version %d: HTTP %d, %d bytes (listed %d)"
                          % (c["id"], c["version"], code, len(body), c["bytes"]))
            check(True, "every chunk of t=%.3f downloads at its version with its listed size" % samples[4])
            check(len(times) >= 1, "%d publication times in the current list" % len(times))
        finally:
            d.stop()

        # A bound of half a megabyte (about half of this job's history): the
        # oldest versions go, the API says from when.
        limit = int(0.5 * 1048576)
        d = Daemon(frepmilld, os.path.join(tmp, "state2"), "--workers", "1",
                   "--publish-interval-s", "0.05", "--mesh-history-mb", "0.5")
        try:
            job_id = submit(d.url, demo_job(VOXEL), tmp)
            status = wait_state(d.url, job_id, ("done", "failed"), 300)
            check(status["state"] == "done", "the demo job is done (0.5 MB history)")
            code, now = chunks(d.url, job_id, "since=0")
            frm = now["history_from_s"]
            check(now["history_bytes"] <= limit,
                  "the history holds %d bytes <= the bound %d" % (now["history_bytes"], limit))
            check(0 < frm <= status["program_time_s"],
                  "it is complete from t=%.3f s (of %.3f s)" % (frm, status["program_time_s"]))
            code, body = curl_json(d.url + "/v1/jobs/%s/chunks?at=%r" % (job_id, frm / 2))
            check(code == 410 and body["error"]["code"] == "history_dropped",
                  "earlier (t=%.3f s): 410 history_dropped: %s" % (frm / 2, body["error"]["message"]))
            code, at = chunks(d.url, job_id, "at=%r" % frm)
            check(code == 200 and at["chunks"], "at t=%.3f s: 200, %d chunks" % (frm, len(at["chunks"])))
            code, zero = chunks(d.url, job_id, "at=0")
            check(code == 410, "t=0 is gone too (%d)" % code)
            # The t=0 meshes (the first daemon's version numbers: the same
            # job makes the same stock versions) are dropped for some chunk.
            answers = {}
            for c in at0["chunks"]:
                code, _ = curl(d.url + "/v1/jobs/%s/chunks/%s.drc?v=%d" % (job_id, c["id"], c["version"]))
                answers[code] = answers.get(code, 0) + 1
            check(answers.get(410, 0) >= 1 and set(answers) <= {200, 410},
                  "the t=0 versions: %s (410: dropped, 200: kept)" % answers)
        finally:
            d.stop()
    print("history test passed")


if __name__ == "__main__":
    main()
