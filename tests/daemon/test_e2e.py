"""test_e2e.py: end-to-end test of frepmilld over HTTP with curl: submit the
bundled demo job, follow its server-sent events to the end, fetch the final
mesh and compare with the CLI's result for the same inputs (frepmill
simulate --report --out): removed volume, and the enclosed volume of the
STL meshes, each within a voxel-based tolerance; the Draco (decoded by
draco_decoder), PLY and OBJ downloads read back: the same triangles,
bounding box and volume; a multipart upload of the same job runs to the
same result. Also checks the JSON
errors of bad requests. Usage: test_e2e.py FREPMILLD FREPMILL"""
import json
import os
import shutil
import struct
import subprocess
import sys
import tempfile
import time

from daemon_util import (Daemon, check, cli_reference, curl, curl_json, decode_draco, demo_job,
                         mesh_measures, read_obj, read_ply, skip, stl_volume, submit, wait_state)

VOXEL = 0.25
STOCK_BOX = (0, 0, -30, 100, 60, 0)  # daemon_util.DEMO_STOCK


def follow_events(url, job_id, timeout):
    """Read the SSE stream with curl until the end event; returns events."""
    proc = subprocess.Popen(["curl", "-s", "-N", "-m", str(timeout), url + "/v1/jobs/%s/events" % job_id],
                            stdout=subprocess.PIPE)
    events, kind = [], None
    try:
        for raw in proc.stdout:
            line = raw.decode().rstrip("\n")
            if line.startswith("event: "):
                kind = line[7:]
            elif line.startswith("data: ") and kind:
                events.append((kind, json.loads(line[6:])))
                if kind == "end":
                    break
    finally:
        proc.kill()
        proc.wait(timeout=10)
    return events


def main():
    frepmilld, frepmill = sys.argv[1], sys.argv[2]
    if not shutil.which("draco_decoder"):
        skip("draco_decoder is not installed (Debian package draco)")
    with tempfile.TemporaryDirectory(prefix="fm-e2e-") as tmp:
        ref = cli_reference(frepmill, VOXEL, tmp)
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1")
        try:
            code, body = curl_json(d.url + "/healthz")
            check(code == 200 and body["status"] == "ok", "GET /healthz is 200")
            job_id = submit(d.url, demo_job(VOXEL), tmp)
            check(os.path.exists(os.path.join(tmp, "state", "jobs", job_id, "spec.json")),
                  "the spec is on disk when the job is acknowledged")
            events = follow_events(d.url, job_id, 300)
            kinds = [k for k, _ in events]
            check(kinds and kinds[-1] == "end" and events[-1][1]["state"] == "done",
                  "the event stream ends with end/done (%d events)" % len(events))
            check("progress" in kinds and "chunks" in kinds and "block" in kinds,
                  "progress, block and chunks events were sent")
            code, status = curl_json(d.url + "/v1/jobs/" + job_id)
            check(code == 200 and status["state"] == "done" and status["progress"] == 1.0,
                  "status is done")
            tol_removed = 1e-3 * ref["removed_volume_mm3"]
            check(abs(status["removed_volume_mm3"] - ref["removed_volume_mm3"]) <= tol_removed,
                  "removed volume %.2f vs CLI %.2f mm3" % (status["removed_volume_mm3"],
                                                           ref["removed_volume_mm3"]))
            # the budget warning (issue 19): the demo's cuts are all proven
            check(status.get("voxels_uncertain") == 0 and status.get("uncertain_line", 0) is None,
                  "status: voxels_uncertain %s (the demo must show 0)" % status.get("voxels_uncertain"))
            code, stl = curl(d.url + "/v1/jobs/%s/mesh?format=stl" % job_id)
            check(code == 200, "GET mesh?format=stl is 200 (%d bytes)" % len(stl))
            vol = stl_volume(stl)
            # The daemon's mesh is welded from chunk meshes, the CLI's made
            # from the whole grid: the same surface up to vertex rounding, so
            # a hundredth of a voxel layer over the surface bounds the gap.
            tol_mesh = 0.01 * VOXEL * ref["surface_area_mm2"]
            check(abs(vol - ref["mesh_volume_mm3"]) <= tol_mesh,
                  "mesh volume %.2f vs CLI mesh %.2f mm3 (tolerance %.2f)" %
                  (vol, ref["mesh_volume_mm3"], tol_mesh))
            tol_grid = 0.5 * VOXEL * ref["surface_area_mm2"]
            check(abs(vol - ref["final_volume_mm3"]) <= tol_grid,
                  "mesh volume %.2f vs CLI stock volume %.2f mm3 (half a voxel of surface)" %
                  (vol, ref["final_volume_mm3"]))
            code, rep = curl_json(d.url + "/v1/jobs/%s/report" % job_id)
            check(code == 200 and rep["motions"] == ref["motions"],
                  "report: %d motions like the CLI" % rep["motions"])
            check(rep.get("voxels_uncertain") == 0 and ref.get("voxels_uncertain") == 0,
                  "report: voxels_uncertain 0 like the CLI")
            code, chunks = curl_json(d.url + "/v1/jobs/%s/chunks?since=0" % job_id)
            check(code == 200 and len(chunks["chunks"]) > 0, "%d chunks listed" % len(chunks["chunks"]))
            full = [c for c in chunks["chunks"] if c["triangles"] > 0][0]
            code, drc = curl(d.url + "/v1/jobs/%s/chunks/%s.drc" % (job_id, full["id"]))
            check(code == 200 and len(drc) == full["bytes"] and drc[:5] == b"DRACO",
                  "chunk %s is a Draco blob of %d bytes" % (full["id"], len(drc)))
            code, later = curl_json(d.url + "/v1/jobs/%s/chunks?since=%d" % (job_id, chunks["version"]))
            check(code == 200 and later["chunks"] == [], "no chunk changed since the last version")
            # Every download format read back here (Draco by Google's
            # draco_decoder): the same closed surface as the STL, whose
            # bounding box is the stock's (the demo leaves its outer faces).
            stl_triangles = struct.unpack_from("<I", stl, 80)[0]
            for fmt in ("drc", "ply", "obj"):
                code, body = curl(d.url + "/v1/jobs/%s/mesh?format=%s" % (job_id, fmt))
                if fmt == "drc":
                    verts, faces = decode_draco(body, tmp)
                else:
                    verts, faces = (read_ply if fmt == "ply" else read_obj)(body)
                fvol, lo, hi = mesh_measures(verts, faces)
                check(code == 200 and len(faces) == stl_triangles,
                      "mesh?format=%s: %d bytes, %d triangles like the STL" % (fmt, len(body), len(faces)))
                check(all(abs(a - b) <= VOXEL / 2 for a, b in zip(lo + hi, STOCK_BOX)),
                      "mesh?format=%s: bounding box %s %s is the stock's" % (fmt, lo, hi))
                check(abs(fvol - vol) <= tol_mesh,
                      "mesh?format=%s: volume %.2f mm3 = the STL's %.2f (tolerance %.2f)" %
                      (fmt, fvol, vol, tol_mesh))
            # The viewer's whole stock (issue 37): meshed with adaptivity, so
            # fewer triangles, but the same block and, its merged polygons
            # straying both ways, the volume within half a voxel of surface;
            # made once and kept (the second answer is the job's file).
            code, whole = curl(d.url + "/v1/jobs/%s/stock.drc" % job_id)
            verts, faces = decode_draco(whole, tmp)
            fvol, lo, hi = mesh_measures(verts, faces)
            check(code == 200 and 0 < len(faces) < stl_triangles,
                  "stock.drc: %d bytes, %d triangles (the chunks: %d)" % (len(whole), len(faces), stl_triangles))
            check(all(abs(a - b) <= VOXEL / 2 for a, b in zip(lo + hi, STOCK_BOX)),
                  "stock.drc: bounding box %s %s is the stock's" % (lo, hi))
            check(abs(fvol - ref["final_volume_mm3"]) <= tol_grid,
                  "stock.drc: volume %.2f vs CLI stock volume %.2f mm3 (tolerance %.2f)" %
                  (fvol, ref["final_volume_mm3"], tol_grid))
            code2, again = curl(d.url + "/v1/jobs/%s/stock.drc" % job_id)
            with open(os.path.join(d.state_dir, "jobs", job_id, "stock.drc"), "rb") as f:
                kept = f.read()
            check(code2 == 200 and again == whole == kept, "stock.drc again: the same bytes, the job's file")
            code, err = curl_json(d.url + "/v1/jobs/nosuchjob/stock.drc")
            check(code == 404 and err["error"]["code"] == "not_found", "stock.drc of no job: 404 not_found")
            code, vdb = curl(d.url + "/v1/jobs/%s/stock.vdb" % job_id)
            check(code == 200 and len(vdb) > 1000, "stock.vdb is %d bytes" % len(vdb))
            code, lst = curl_json(d.url + "/v1/jobs")
            check(code == 200 and [j["id"] for j in lst["jobs"]] == [job_id], "GET /v1/jobs lists it")

            # Errors: JSON with the right status codes.
            code, err = curl_json("-X", "POST", "--data-binary", '{"stock": "box:0,0,0,1,1,1",\n "voxel": }',
                                  d.url + "/v1/jobs")
            check(code == 400 and err["error"]["code"] == "bad_json" and err["error"]["line"] == 2,
                  "bad JSON: 400 with line %s column %s" % (err["error"]["line"], err["error"]["column"]))
            job = demo_job(VOXEL)
            job["colour"] = "red"
            code, err = curl_json("-X", "POST", "--data-binary", json.dumps(job), d.url + "/v1/jobs")
            check(code == 400 and err["error"]["code"] == "unknown_key", "unknown key: 400")
            job = demo_job(VOXEL)
            job["stock"] = "/etc/passwd.stl"
            code, err = curl_json("-X", "POST", "--data-binary", json.dumps(job), d.url + "/v1/jobs")
            check(code == 400 and err["error"]["code"] == "bad_stock", "a server file as stock: 400")
            job = demo_job(0.001)
            code, err = curl_json("-X", "POST", "--data-binary", json.dumps(job), d.url + "/v1/jobs")
            check(code == 413 and err["error"]["code"] == "memory_budget",
                  "over the memory budget: 413 (%s)" % err["error"]["message"])
            code, err = curl_json(d.url + "/v1/jobs/nosuchjob")
            check(code == 404 and err["error"]["code"] == "not_found", "unknown job: 404")
            code, err = curl_json("-X", "PUT", d.url + "/v1/jobs")
            check(code == 405, "PUT /v1/jobs: 405")
            code, err = curl_json("-X", "POST", "--data-binary", "{}", d.url + "/v1/check")
            check(code == 400 and err and err["error"]["code"] == "missing_key"
                  and "stock" in err["error"]["message"],
                  "POST /v1/check of {}: 400 missing_key naming the stock (%d %s)" % (code, err))
            code, err = curl_json(d.url + "/v1/jobs/%s/mesh?format=xyz" % job_id)
            check(code == 400, "unknown mesh format: 400")

            # Multipart upload of the same job: the program as a file part.
            spec = demo_job(VOXEL)
            del spec["program"]
            spec_path = os.path.join(tmp, "spec.json")
            with open(spec_path, "w") as f:
                json.dump(spec, f)
            code, body = curl_json("-F", "job=<" + spec_path,
                                   "-F", "program=@" + os.path.join(os.path.dirname(__file__), "..", "..",
                                                                    "deploy", "demo", "pocket.ngc"),
                                   d.url + "/v1/jobs")
            check(code == 202, "multipart upload: 202 %s" % body)
            # The uploaded job runs and gives what the JSON job gave.
            up = wait_state(d.url, body["id"], ("done", "failed", "cancelled"), 300)
            code, up_rep = curl_json(d.url + "/v1/jobs/%s/report" % body["id"])
            check(up["state"] == "done" and code == 200 and up_rep["motions"] == rep["motions"]
                  and abs(up["removed_volume_mm3"] - status["removed_volume_mm3"]) <=
                  1e-9 * status["removed_volume_mm3"],
                  "the multipart job ran like the JSON one: %s, %d motions, removed %.3f mm3 (JSON %.3f)" %
                  (up["state"], up_rep.get("motions", -1), up["removed_volume_mm3"],
                   status["removed_volume_mm3"]))
            code, body = curl_json("-X", "DELETE", d.url + "/v1/jobs/" + body["id"])
            check(code == 200, "DELETE the uploaded job: 200")
        finally:
            rc = d.stop()
        check(rc == 0, "SIGTERM stops the daemon with status 0")
        check("SIGTERM: stopping" in d.read_log(), "the stop is logged")
    return 0


if __name__ == "__main__":
    sys.exit(main())
