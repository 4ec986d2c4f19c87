"""test_live_meshes.py: a live job announces its meshes (the `chunks` event)
before their Draco bytes exist (issue 37: the encoding runs after the event,
docs/daemon.md); a client that fetches what an event announced, at once,
must get those meshes, not an empty or older body. Positions are written
over Modbus (raw FC16 writes, no client library); the events are read from a
raw socket and every chunk an event names is fetched at its announced version
right after the event, as the viewer does. Checked: the daemon's log says
readers did wait for bytes being encoded (the path is taken); every body is
the same when fetched again after the job is done; no chunk is announced
again with the mesh it had (a chunk marked near a seam whose mesh did not
change keeps its version); the chunks as last
announced, decoded by Google's draco_decoder and put together, enclose the
stock's volume: the box less the slot's closed form.
Usage: test_live_meshes.py FREPMILLD FREPMILL"""
import http.client
import json
import math
import os
import shutil
import socket
import struct
import sys
import tempfile
import time

from daemon_util import (Daemon, check, curl_json, decode_draco, mesh_measures, modbus_port,
                         modbus_write, skip)

STOCK_BOX = (0, 0, -10, 60, 60, 0)
VOXEL = 0.25
RADIUS, DEPTH = 3.0, 2.0
TOOLS = {"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 2 * RADIUS,
                                   "flute_length": 20, "length": 40}]}
FEED = 1000.0  # mm/min, the daemon's live_feed
# Placed above the stock and plunged; 1 mm along X at a time, each move's
# meshes announced before the next is written, across the chunk seam at
# x = 16 (chunks are 64 voxels, 16 mm; the tool also spans the seam at
# y = 32); then on to x = 30 in one go.
GROUPS = ([[(10, 30, 5), (10, 30, -DEPTH)]] + [[(x, 30, -DEPTH)] for x in range(11, 24)] +
          [[(26, 30, -DEPTH), (30, 30, -DEPTH)]])
MOVES = [m for g in GROUPS for m in g]


def program_time(moves):
    """Program time after the moves (the first only places the tool)."""
    return sum(math.dist(a, b) for a, b in zip(moves, moves[1:])) / FEED * 60.0


def position_words(x, y, z, tool):
    """Registers 110-116: X, Y, Z as float32 (high word first), the tool."""
    words = []
    for v in (x, y, z):
        bits = struct.unpack(">I", struct.pack(">f", v))[0]
        words += [bits >> 16, bits & 0xFFFF]
    return words + [tool]


class Events:
    """The job's server-sent events over a raw socket."""

    def __init__(self, port, job_id):
        self.sock = socket.create_connection(("127.0.0.1", port), timeout=30)
        self.sock.sendall(("GET /v1/jobs/%s/events HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                           "Accept: text/event-stream\r\n\r\n" % job_id).encode())
        self.buf = b""
        self.kind = None

    def next_chunks(self, timeout):
        """The next `chunks` event's data, or None after timeout seconds."""
        deadline = time.time() + timeout
        while True:
            while b"\n" in self.buf:
                line, self.buf = self.buf.split(b"\n", 1)
                line = line.decode().rstrip("\r")
                if line.startswith("event: "):
                    self.kind = line[7:]
                elif line.startswith("data: ") and self.kind == "chunks":
                    return json.loads(line[6:])
            left = deadline - time.time()
            if left <= 0:
                return None
            self.sock.settimeout(left)
            try:
                data = self.sock.recv(65536)
            except socket.timeout:
                return None
            if not data:
                return None
            self.buf += data


def get(conn, path):
    conn.request("GET", path)
    r = conn.getresponse()
    return r.status, r.read()


def main():
    frepmilld = sys.argv[1]
    if not shutil.which("draco_decoder"):
        skip("draco_decoder is not installed (Debian package draco)")
    with tempfile.TemporaryDirectory(prefix="fm-live-meshes-") as tmp:
        t0 = time.time()
        tools = os.path.join(tmp, "tools.json")
        with open(tools, "w") as f:
            json.dump(TOOLS, f)
        d = Daemon(frepmilld, os.path.join(tmp, "state"), "--workers", "1",
                   "--modbus-listen", "127.0.0.1:0", "--modbus-live", "yes",
                   "--live-stock", "box:" + ",".join(map(str, STOCK_BOX)), "--live-tools", tools,
                   "--live-voxel", str(VOXEL), "--log-level", "debug")
        try:
            port = modbus_port(d)
            http_port = int(d.url.rsplit(":", 1)[1])
            check(modbus_write(port, 117, [1]) == 0, "live mode on")
            job_id = None
            deadline = time.time() + 30
            while not job_id and time.time() < deadline:
                code, listing = curl_json(d.url + "/v1/jobs")
                live = [j for j in listing["jobs"] if j.get("name") == "live"]
                job_id = live[0]["id"] if live else None
                time.sleep(0.02)
            check(job_id is not None, "a live job is listed")
            events = Events(http_port, job_id)
            conn = http.client.HTTPConnection("127.0.0.1", http_port, timeout=60)
            # Each group written, then its events read until its program
            # time is announced; each event's chunks fetched at once, at the
            # announced version; the chunk list (bytes, triangles) too.
            fetched = {}  # (chunk, version) -> body
            repeated = []  # chunks announced again with the body they had
            last_body = {}  # chunk -> body of its last announced version
            current = {}  # chunk -> (version, triangles) as last announced
            deadline = time.time() + 120

            def read_events_until(moves_time):
                """Events until one announces moves_time; its program time."""
                while time.time() < deadline:
                    ev = events.next_chunks(60)
                    check(ev is not None, "a chunks event came")
                    version = ev["version"]
                    for name in ev["changed"]:
                        code, body = get(conn, "/v1/jobs/%s/chunks/%s.drc?v=%d" % (job_id, name, version))
                        if code != 200:
                            check(False, "chunk %s at version %d fetched at once: %d" % (name, version, code))
                        fetched[(name, version)] = body
                        if last_body.get(name) == body:
                            repeated.append((name, version))
                        last_body[name] = body
                    code, body = get(conn, "/v1/jobs/%s/chunks?since=%d" % (job_id, version - 1))
                    for c in json.loads(body)["chunks"]:
                        if c["version"] != version:
                            continue
                        current[c["id"]] = (version, c["triangles"])
                        got = fetched.get((c["id"], version))
                        if got is not None and (c["bytes"] != len(got) or (c["triangles"] > 0) != (len(got) > 0)):
                            check(False, "chunk %s at version %d: the list says %d bytes and %d triangles, "
                                  "the body fetched at once had %d bytes" %
                                  (c["id"], version, c["bytes"], c["triangles"], len(got)))
                    if ev["program_time_s"] >= moves_time - 1e-6:
                        return ev["program_time_s"]
                return None

            written = []
            for group in GROUPS:
                for m in group:
                    check(modbus_write(port, 110, position_words(*m, 1)) == 0,
                          "position %s written" % (m,))
                written += group
                moves_time = program_time(written)
                last_time = read_events_until(moves_time)
            check(last_time is not None and last_time >= moves_time - 1e-6,
                  "the last move's meshes were announced (program time %.2f s)" % moves_time)
            check(all(len(b) > 0 for (n, v), b in fetched.items() if current.get(n, (0, 1))[1] > 0
                      and current[n][0] == v),
                  "every current chunk with triangles had a non-empty body when fetched at once")
            log = d.read_log().splitlines()
            waits = [l for l in log if "waited" in l and "Draco bytes" in l]
            check(waits, "readers waited for bytes still being encoded (%d times; the path is taken)" %
                  len(waits))
            # The stock marks the chunks within two voxels of the leaves a
            # cut touched; where a move's change reaches none of a marked
            # chunk's faces (moves along the seams), the chunk keeps its
            # version instead of a copy of it.
            kept = [l for l in log if "marked chunks whose meshes did not change" in l]
            if not kept:
                print("\n".join(l for l in log if "published" in l or "encoded" in l))
            check(kept, "some marked chunks kept their meshes (%d publications)" % len(kept))
            check(not repeated, "no chunk was announced again with the body it had (%s)" % repeated[:3])

            check(modbus_write(port, 117, [0]) == 0, "live mode off")
            deadline = time.time() + 60
            while time.time() < deadline:
                code, status = curl_json(d.url + "/v1/jobs/" + job_id)
                if status["state"] == "done":
                    break
                time.sleep(0.05)
            check(status["state"] == "done", "the live job is done")
            same = all(get(conn, "/v1/jobs/%s/chunks/%s.drc?v=%d" % (job_id, n, v)) == (200, b)
                       for (n, v), b in fetched.items())
            check(same, "all %d bodies fetched at once are the ones served after the job" % len(fetched))

            # The chunks as last announced, put together: the stock's
            # closed surface. Its volume by the divergence theorem against
            # the box less the slot (a stadium of length 20 mm, DEPTH deep).
            vertices, faces = [], []
            for name, (version, triangles) in current.items():
                if triangles == 0:
                    continue
                v, f = decode_draco(fetched[(name, version)], tmp)
                if len(f) != triangles:
                    check(False, "chunk %s: %d triangles decoded, %d listed" % (name, len(f), triangles))
                base = len(vertices)
                vertices += v
                faces += [(a + base, b + base, c + base) for a, b, c in f]
            volume, lo, hi = mesh_measures(vertices, faces)
            box = (STOCK_BOX[3] - STOCK_BOX[0]) * (STOCK_BOX[4] - STOCK_BOX[1]) * (STOCK_BOX[5] - STOCK_BOX[2])
            slot = DEPTH * (2 * RADIUS * 20 + math.pi * RADIUS ** 2)
            # The mesh cuts the box's 12 edges and the slot's rim by about
            # half a voxel square per mm; the slot (297 mm3) is far above it.
            tol = 0.5 * VOXEL ** 2 * (4 * 60 + 4 * 60 + 4 * 10 + 2 * (40 + 2 * math.pi * RADIUS))
            check(abs(volume - (box - slot)) <= tol,
                  "the announced chunks enclose %.1f mm3 = box less the slot %.1f within %.1f" %
                  (volume, box - slot, tol))
            conn.close()
        finally:
            rc = d.stop()
            if rc != 0:
                print(d.read_log()[-6000:])
        check(rc == 0, "the daemon stopped cleanly")
        print("test_live_meshes: %.1f s" % (time.time() - t0))


if __name__ == "__main__":
    main()
