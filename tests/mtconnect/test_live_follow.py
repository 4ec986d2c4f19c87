"""test_live_follow.py: one daemon following another through MTConnect.
Daemon A follows the recorded Okuma adapter (the first 1,370 lines of
../shared/mtconnect/recordings/okuma_multus_imts2022.shdr, its assets and
the whole Z pecking stretch of test_live_shdr.py, played at a machine's
pace) in live mode; daemon B follows A's agent with live_source =
mtconnect://A/mtconnect/frepmill (the agent's root, then the device: its current
document, then its sample stream) and live_map = X=Xpos,Y=Ypos,Z=Zpos (A's device's
tool tip). B's live job must cut the volume A's live job cut, which is the
hole pi * 3^2 * 50 mm^3 of test_live_shdr.py's closed form.
Usage: test_live_follow.py FREPMILLD MTCONNECT_DATA"""
import json
import math
import os
import sys
import tempfile
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "daemon"))
from daemon_util import INSTRUMENTED, Daemon, check, skip  # noqa: E402
from test_live_shdr import BOX, RADIUS, TOOLS, Replay, recorded_positions, wait_volume  # noqa: E402

LINES = 1370


def main():
    frepmilld, data = sys.argv[1], sys.argv[2]
    recording = os.path.join(data, "recordings", "okuma_multus_imts2022.shdr")
    if not os.path.exists(recording):
        skip("the SHDR recording is missing (%s; cmake -DFM_MTCONNECT_DATA=...)" % recording)
    with open(recording, "rb") as f:
        head = b"".join(f.readlines()[:LINES])
    with tempfile.TemporaryDirectory(prefix="fm-live-follow-") as tmp:
        path = os.path.join(tmp, "head.shdr")
        with open(path, "wb") as f:
            f.write(head)
        near = [p for p in recorded_positions(path) if BOX[0] < p[1] < BOX[3]]
        deepest = min(z for _, _, z in near)
        expect = math.pi * RADIUS ** 2 * (BOX[5] - deepest)
        tools = os.path.join(tmp, "tools.json")
        with open(tools, "w") as f:
            json.dump(TOOLS, f)
        live = ["--live-stock", "box:%g,%g,%g,%g,%g,%g" % BOX, "--live-tools", tools,
                "--live-voxel", "0.1", "--live-feed", "20000", "--live-reconnect-max-s", "2"]
        # Instrumented daemons cut slower: a slower machine, so that A still
        # publishes each peck's end (B sees what A publishes).
        replay = Replay(head, pace_s=0.1 if INSTRUMENTED else 0.03)
        a = Daemon(frepmilld, os.path.join(tmp, "a"), "--live-source", "shdr://127.0.0.1:%d" % replay.port,
                   "--live-map", "X=X1actw,Z=Z1actw", "--mtconnect-sample-ms", "5", *live)
        b = None
        try:
            b = Daemon(frepmilld, os.path.join(tmp, "b"), "--live-source",
                       "mtconnect://%s/mtconnect/frepmill" % a.url[len("http://"):],
                       "--live-map", "X=Xpos,Y=Ypos,Z=Zpos", *live)
            deadline = time.time() + (900 if INSTRUMENTED else 400)
            while not replay.sent and time.time() < deadline:
                time.sleep(0.5)
            sa = wait_volume(a.url, expect, 0.005, deadline)
            check(sa is not None, "A has a live job")
            sb = wait_volume(b.url, sa["removed_volume_mm3"], 0.001, deadline)
            check(sb is not None, "B has a live job")
            ra, rb = sa["removed_volume_mm3"], sb["removed_volume_mm3"]
            print("A removed %.3f, B removed %.3f, the closed form %.3f" % (ra, rb, expect))
            check(abs(ra - expect) <= 0.005 * expect, "A cut the hole (%.3f of %.3f)" % (ra, expect))
            check(abs(rb - ra) <= 0.001 * ra, "B cut what A cut (%.3f vs %.3f)" % (rb, ra))
            check(sb.get("live_source", "").startswith("following mtconnect://"),
                  "B's status says it follows A's agent (%s)" % sb.get("live_source"))
            log = b.read_log()
            check("does not stream" not in log and "trying again" not in log,
                  "B read A's sample stream from start to end (no polling, no reconnection)")
        finally:
            replay.drop.set()
            replay.stop = True
            if b:
                b.stop()
            a.stop()


if __name__ == "__main__":
    main()
