"""test_agent_daemon.py: frepmilld's MTConnect agent under /mtconnect. The
daemon's device takes its rotary axes from a machine file (an AC trunnion);
a job cuts a rapid at Z-5 straight through the block box:0,0,-10,50,50,0
with a 6 mm flat end mill from X-10 to X60 (tests/check/rapid_through.ngc):
the tool's ends stay outside the block, so the cut is a 50 x 6 x 5 mm slot,
1500 mm^3, and the check reports the rapid into the stock at line 6.
Every document served (probe, current, sample, a streamed part, assets,
errors) is validated with xmllint against the MTConnect 2.7 schemas; the
values are compared with that closed form, the job's JSON status and report,
and the tool table. A second job on the trunnion (its machine file in the
job) turns the table to A-20 C135 with the spindle at S12000 and ends on
line 7: the agent's angles, spindle speed and line are the program's.
Usage: test_agent_daemon.py FREPMILLD MTCONNECT_DATA"""
import json
import os
import re
import subprocess
import sys
import tempfile
import xml.etree.ElementTree as ET

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "daemon"))
from daemon_util import ROOT, Daemon, check, curl, curl_json, skip, submit, wait_state  # noqa: E402

CHECK_DIR = os.path.join(ROOT, "tests", "check")
NS = {"s": "urn:mtconnect.org:MTConnectStreams:2.7", "d": "urn:mtconnect.org:MTConnectDevices:2.7",
      "a": "urn:mtconnect.org:MTConnectAssets:2.7", "e": "urn:mtconnect.org:MTConnectError:2.7"}
SCHEMA = {"s": "MTConnectStreams_2.7_1.0.xsd", "d": "MTConnectDevices_2.7_1.0.xsd",
          "a": "MTConnectAssets_2.7_1.0.xsd", "e": "MTConnectError_2.7_1.0.xsd"}
validated = 0
# Turns the AC trunnion's table with the tool above the block (TCP: the tip
# stays at X25 Y25 Z30 of the workpiece).
TURN_PROGRAM = """(the trunnion's table turned above the block)
G21 G90 G17
T1 M6
S12000 M3
G0 X25 Y25 Z30
G1 A-20 C135 F2000
G1 X20 F500
M2
"""


def validate(body, kind, data, tmp):
    global validated
    path = os.path.join(tmp, "doc%d.xml" % validated)
    with open(path, "wb") as f:
        f.write(body)
    out = subprocess.run(["xmllint", "--noout", "--schema", os.path.join(data, "schemas", SCHEMA[kind]),
                          path], stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=120)
    validated += 1
    if out.returncode != 0:
        print(body[:3000].decode(errors="replace"))
        print(out.stderr.decode(errors="replace"))
    check(out.returncode == 0, "document %d validates against %s" % (validated, SCHEMA[kind]))
    return ET.fromstring(body)


def get(url, kind, data, tmp, status=200):
    code, body = curl(url)
    check(code == status, "%s answers %d (got %d)" % (url, status, code))
    return validate(body, kind, data, tmp)


def main():
    frepmilld, data = sys.argv[1], sys.argv[2]
    if not os.path.exists(os.path.join(data, "schemas", SCHEMA["s"])):
        skip("the MTConnect schemas are missing (%s; cmake -DFM_MTCONNECT_DATA=...)" % data)
    with tempfile.TemporaryDirectory(prefix="fm-mtconnect-") as tmp:
        machine = os.path.join(CHECK_DIR, "corpus_machine", "trunnion.json")
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--mtconnect-machine", machine,
                   "--mtconnect-device", "mill1")
        try:
            base = d.url + "/mtconnect"
            probe = get(base + "/probe", "d", data, tmp)
            names = sorted(c.get("name") for c in probe.iter("{%s}Linear" % NS["d"]))
            check(names == ["X", "Y", "Z"], "Linear X, Y, Z (%s)" % names)
            rotary = sorted(c.get("name") for c in probe.iter("{%s}Rotary" % NS["d"]))
            check(rotary == ["A", "C", "S"], "the trunnion's A and C and the spindle S (%s)" % rotary)
            device = probe.find(".//d:Device", NS)
            check(device.get("name") == "mill1", "the device's name is the setting's")
            units = {i.get("name"): i.get("units") for i in probe.iter("{%s}DataItem" % NS["d"])}
            check(units.get("removed_volume") == "CUBIC_MILLIMETER" and units.get("stock_volume") ==
                  "CUBIC_MILLIMETER" and units.get("progress") == "PERCENT" and
                  units.get("Xpos") == "MILLIMETER" and units.get("Apos") == "DEGREE",
                  "frepmill's data items carry their units (%s)" % units)
            # The same document at the agent's root and under the device's name.
            code, root = curl(base + "/")
            code2, named = curl(base + "/mill1/probe")
            check(code == 200 and code2 == 200 and b"<Linear" in root and b"<Linear" in named,
                  "probe at /mtconnect/ and /mtconnect/mill1/probe")

            with open(os.path.join(CHECK_DIR, "rapid_through.ngc")) as f:
                program = f.read()
            with open(os.path.join(CHECK_DIR, "tools.json")) as f:
                tools = json.load(f)
            job = {"stock": "box:0,0,-10,50,50,0", "voxel": 0.1, "tools": tools,
                   "program": {"gcode": program}, "options": {"name": "rapid-through"}}
            job_id = submit(d.url, job, tmp)
            status = wait_state(d.url, job_id, ("done", "failed"), 300)
            check(status["state"] == "done", "the job is done (%s)" % status["state"])
            code, report = curl_json(d.url + "/v1/jobs/" + job_id + "/report")
            check(code == 200, "the report")
            # The agent samples every 50 ms: wait for the end to show.
            for _ in range(100):
                cur = get(base + "/current", "s", data, tmp)
                if cur.find(".//s:Execution", NS).text == "PROGRAM_COMPLETED":
                    break
            check(cur.find(".//s:Execution", NS).text == "PROGRAM_COMPLETED",
                  "execution PROGRAM_COMPLETED once the job is done")
            check(cur.find(".//s:Program", NS).text == "rapid-through", "the program is the job's name")
            removed = float(cur.find(".//s:VolumeSpatial[@name='removed_volume']", NS).text)
            check(abs(removed - 1500.0) <= 0.005 * 1500.0,
                  "removed volume %.3f mm^3 within 0.5%% of the slot's 1500" % removed)
            check(abs(removed - status["removed_volume_mm3"]) <= 0.0005 + 1e-9 * removed,
                  "removed volume %.3f is the job's %.4f" % (removed, status["removed_volume_mm3"]))
            stock = float(cur.find(".//s:VolumeSpatial[@name='stock_volume']", NS).text)
            check(abs(stock - (50 * 50 * 10 - removed)) <= 0.005 * 1500.0,
                  "stock volume %.3f is the block's 25000 less the cut" % stock)
            check(float(cur.find(".//s:Variable[@name='progress']", NS).text) == 100.0, "progress 100%")
            # Every error finding of the report is a FAULT of the path's
            # MOTION_PROGRAM condition with its line as the native code.
            findings = status["findings"]
            errors = sorted({f["line"] for f in findings if f["severity"] == "error"})
            check(6 in errors, "the report's collision is at line 6 (%s)" % errors)
            faults = sorted({int(f.get("nativeCode")) for f in cur.findall(".//s:Fault", NS)
                             if f.get("type") == "MOTION_PROGRAM"})
            check(faults == errors, "faults at lines %s = the report's errors %s" % (faults, errors))
            x = float(cur.find(".//s:Position[@dataItemId='Xpos']", NS).text)
            check(abs(x - status["position"][0]) <= 1e-4, "X is the job's last position")
            check(cur.find(".//s:Angle[@dataItemId='Apos']", NS).text == "UNAVAILABLE",
                  "the rotary axes are UNAVAILABLE (the job's machine has none)")
            check(float(cur.find(".//s:RotaryVelocity[@dataItemId='Srpm']", NS).text) == 0.0,
                  "the spindle speed is 0 (the program turns no spindle on)")

            # sample: from the first sequence, in order, within the buffer.
            header = cur.find("s:Header", NS)
            first, nxt = int(header.get("firstSequence")), int(header.get("nextSequence"))
            sample = get(base + "/sample?from=%d&count=1000" % first, "s", data, tmp)
            seqs = [int(e.get("sequence")) for e in sample.iter() if e.get("sequence")]
            check(len(seqs) == min(1000, nxt - first) and sorted(seqs) == list(range(first, first + len(seqs))),
                  "sample gives the sequences %d.. in one run (%d)" % (first, len(seqs)))
            removed_seen = [float(e.text) for e in sample.iter("{%s}VolumeSpatial" % NS["s"])
                            if e.get("name") == "removed_volume" and e.text != "UNAVAILABLE"]
            check(removed_seen and abs(removed_seen[-1] - removed) < 1e-9 and
                  all(a <= b + 1e-9 for a, b in zip(removed_seen, removed_seen[1:])),
                  "the removed volume only grows, to the job's figure (%d values)" % len(removed_seen))
            path = get(base + "/current?path=//Linear%5B@name=%22Z%22%5D", "s", data, tmp)
            got = [e.get("dataItemId") for e in path.iter() if e.get("dataItemId")]
            check(got == ["Zpos"], "path=//Linear[@name=\"Z\"] gives Zpos alone (%s)" % got)

            # A streamed sample: multipart/x-mixed-replace parts, each a document.
            out = subprocess.run(["curl", "-s", "-i", "-m", "2", base + "/sample?interval=100&heartbeat=200"],
                                 stdout=subprocess.PIPE, timeout=30)
            raw = out.stdout
            m = re.search(rb"Content-Type: multipart/x-mixed-replace;boundary=(\S+)", raw)
            check(m is not None, "the stream's Content-Type is multipart/x-mixed-replace")
            parts = raw.split(b"--" + m.group(1) + b"\r\n")[1:] if m else []
            check(len(parts) >= 2, "heartbeats every 200 ms: %d parts in 2 s" % len(parts))
            for part in parts[:2]:
                head, _, rest = part.partition(b"\r\n\r\n")
                n = int(re.search(rb"Content-length: (\d+)", head).group(1))
                validate(rest[:n], "s", data, tmp)

            assets = get(base + "/assets", "a", data, tmp)
            tools_seen = {t.get("assetId"): t for t in assets.findall(".//a:CuttingTool", NS)}
            check(sorted(tools_seen) == ["T%d" % t["number"] for t in tools["tools"]],
                  "a CuttingTool per tool (%s)" % sorted(tools_seen))
            for t in tools["tools"]:
                ct = tools_seen.get("T%d" % t["number"])
                dc = float(ct.find(".//a:CuttingDiameterMax", NS).text)
                oal = float(ct.find(".//a:OverallToolLength", NS).text)
                check(dc == t["diameter"] and oal == t["length"],
                      "T%d: diameter %g and length %g from the table" % (t["number"], dc, oal))
            get(base + "/asset/T1", "a", data, tmp)

            for url, status_code, element in (
                    ("/sample?from=abc", 400, "QueryError"),
                    ("/sample?count=0", 400, "QueryError"),
                    ("/current?path=//Linear%5B", 400, "InvalidXPath"),
                    ("/sample?from=1", 400, "OutOfRange") if first > 1 else ("/sample?from=999999999", 400, "OutOfRange"),
                    ("/other/current", 404, "NoDevice"),
                    ("/asset/T42", 404, "AssetNotFound"),
                    ("/nothing", 400, "InvalidURI")):
                doc = get(base + url, "e", data, tmp, status_code)
                check(doc.find(".//e:" + element, NS) is not None, "%s: %s" % (url, element))
            code, _ = curl("-X", "POST", base + "/current")
            check(code == 405, "POST under /mtconnect is refused (%d)" % code)

            # A job on the trunnion: the table turned above the block.
            turn = TURN_PROGRAM.splitlines()
            last_line = max(n for n, text in enumerate(turn, 1) if text.startswith(("G0", "G1")))
            with open(machine) as f:
                job = {"stock": "box:0,0,-10,50,50,0", "voxel": 0.5, "tools": tools,
                       "machine": json.load(f), "program": {"gcode": TURN_PROGRAM},
                       "options": {"name": "turn"}}
            job_id = submit(d.url, job, tmp)
            status = wait_state(d.url, job_id, ("done", "failed"), 300)
            check(status["state"] == "done", "the trunnion's job is done (%s)" % status["state"])
            check(status.get("rotary") == {"A": -20.0, "C": 135.0} and status.get("spindle_rpm") == 12000.0,
                  "the job's status has the program's joints and speed (%s, %s)" %
                  (status.get("rotary"), status.get("spindle_rpm")))
            for _ in range(100):
                cur = get(base + "/current", "s", data, tmp)
                if cur.find(".//s:Program", NS).text == "turn" and \
                        cur.find(".//s:Execution", NS).text == "PROGRAM_COMPLETED":
                    break
            angles = {i: cur.find(".//s:Angle[@dataItemId='%s']" % i, NS).text for i in ("Apos", "Cpos")}
            check(angles == {"Apos": "-20.0000", "Cpos": "135.0000"},
                  "the agent's A and C are the program's last A-20 C135 (%s)" % angles)
            rpm = cur.find(".//s:RotaryVelocity[@dataItemId='Srpm']", NS).text
            check(float(rpm) == 12000.0, "the agent's spindle speed is the program's S12000 (%s)" % rpm)
            line = cur.find(".//s:LineNumber[@dataItemId='line']", NS).text
            check(int(line) == last_line, "the agent's line is the program's last motion's, %d (%s)" %
                  (last_line, line))
        finally:
            d.stop()
    print("daemon_mtconnect: %d documents validated" % validated)


if __name__ == "__main__":
    main()
