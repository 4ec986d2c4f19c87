"""daemon_util.py: shared helpers of the frepmilld tests: start the daemon on
a free loopback port (port 0; the daemon writes the address it bound to
STATE_DIR/http.addr), stop it, run curl, read STL volumes. Every wait is
bounded."""
import json
import os
import signal
import socket
import struct
import subprocess
import sys
import time

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tests", "support"))
from fm_skip import skip  # noqa: E402  (re-exported: the tests' skip rule)
DEMO = os.path.join(ROOT, "deploy", "demo")
DEMO_STOCK = "box:0,0,-30,100,60,0"
# Set by ctest in sanitizer builds (fm_tool_test): frepmilld and frepmill are
# instrumented there, several times slower, and waits are doubled. A test
# whose cost is its grid or its number of jobs takes a coarser grid or fewer
# jobs when COARSE; it asserts the same things. The optimized build runs the
# full size in CI (deploy/test.sh's release step), and FM_TEST_FULL_SIZE=1
# (deploy/test.sh full) keeps the full size in the sanitizer build too.
INSTRUMENTED = os.environ.get("FM_TEST_INSTRUMENTED") == "1"
COARSE = INSTRUMENTED and os.environ.get("FM_TEST_FULL_SIZE") != "1"


class Daemon:
    def __init__(self, binary, state_dir, *extra):
        self.state_dir = state_dir
        os.makedirs(state_dir, exist_ok=True)
        addr_file = os.path.join(state_dir, "http.addr")
        # A killed daemon leaves its address files: a restart must not be
        # mistaken for the old one (modbus_port reads modbus.addr).
        for name in ("http.addr", "modbus.addr"):
            if os.path.exists(os.path.join(state_dir, name)):
                os.unlink(os.path.join(state_dir, name))
        self.log_path = os.path.join(state_dir, "daemon.log")
        self.log = open(self.log_path, "ab")
        self.proc = subprocess.Popen(
            [binary, "--listen", "127.0.0.1:0", "--state-dir", state_dir,
             "--modbus-listen", "off", *extra],
            stdout=self.log, stderr=self.log)
        deadline = time.time() + 30
        while time.time() < deadline:
            if self.proc.poll() is not None:
                raise RuntimeError("frepmilld exited with %d; log:\n%s" %
                                   (self.proc.returncode, self.read_log()))
            if os.path.exists(addr_file):
                self.url = open(addr_file).read().strip()
                if self.url:
                    return
            time.sleep(0.05)
        raise RuntimeError("frepmilld did not start within 30 s")

    def read_log(self):
        with open(self.log_path, "rb") as f:
            return f.read().decode(errors="replace")

    def stop(self, sig=signal.SIGTERM, timeout=60):
        if self.proc.poll() is None:
            self.proc.send_signal(sig)
            try:
                self.proc.wait(timeout=timeout)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=10)
                raise RuntimeError("frepmilld did not stop within %d s" % timeout)
        self.log.close()
        return self.proc.returncode


def curl(*args, timeout=60):
    """Run curl; returns (http status, body bytes)."""
    out = subprocess.run(["curl", "-s", "-S", "-m", str(timeout), "-w", "\n%{http_code}", *args],
                         stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout + 10)
    if out.returncode != 0:
        raise RuntimeError("curl %s failed: %s" % (args, out.stderr.decode()))
    body, _, code = out.stdout.rpartition(b"\n")
    return int(code), body


def curl_json(*args, timeout=60):
    code, body = curl(*args, timeout=timeout)
    return code, json.loads(body) if body.strip() else None


def demo_job(voxel, name="demo"):
    with open(os.path.join(DEMO, "pocket.ngc")) as f:
        program = f.read()
    with open(os.path.join(DEMO, "tools.json")) as f:
        tools = json.load(f)
    return {"stock": DEMO_STOCK, "voxel": voxel, "tools": tools,
            "program": {"gcode": program}, "options": {"name": name}}


def submit(url, job, tmpdir):
    path = os.path.join(tmpdir, "job.json")
    with open(path, "w") as f:
        json.dump(job, f)
    code, body = curl_json("-X", "POST", "-H", "Content-Type: application/json",
                           "--data-binary", "@" + path, url + "/v1/jobs")
    if code != 202:
        raise RuntimeError("submit: %d %s" % (code, body))
    return body["id"]


def wait_state(url, job_id, states, timeout):
    """Wait for the job to reach one of states. timeout is a bound for the
    optimized build; instrumented (sanitizer build, several tests at once)
    it is doubled: only how long a test may wait changes, not what it
    asserts."""
    deadline = time.time() + (2 * timeout if INSTRUMENTED else timeout)
    while time.time() < deadline:
        code, status = curl_json(url + "/v1/jobs/" + job_id)
        if code == 200 and status["state"] in states:
            return status
        time.sleep(0.2)
    raise RuntimeError("job %s not in %s within %d s" % (job_id, states, timeout))


def cli_reference(frepmill, voxel, tmpdir):
    """The CLI's result for the demo job: its report and its mesh volume."""
    report = os.path.join(tmpdir, "cli_report.json")
    stl = os.path.join(tmpdir, "cli.stl")
    subprocess.run([frepmill, "simulate", os.path.join(DEMO, "pocket.ngc"), "--stock", DEMO_STOCK,
                    "--tools", os.path.join(DEMO, "tools.json"), "--voxel", str(voxel),
                    "--report", report, "--out", stl], check=True, timeout=600,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(report) as f:
        rep = json.load(f)
    with open(stl, "rb") as f:
        rep["mesh_volume_mm3"] = stl_volume(f.read())
    return rep


def stl_volume(data):
    """Signed volume of a binary STL (divergence theorem, sum of tetrahedra
    against the origin): computed here independently of lib/mesh."""
    count = struct.unpack_from("<I", data, 80)[0]
    if len(data) != 84 + 50 * count:
        raise ValueError("STL size %d does not match %d triangles" % (len(data), count))
    total = 0.0
    for i in range(count):
        v = struct.unpack_from("<9f", data, 84 + 50 * i + 12)
        ax, ay, az, bx, by, bz, cx, cy, cz = v
        total += (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx))
    return total / 6.0


def check(cond, message):
    if not cond:
        raise AssertionError(message)
    print("ok:", message)


def modbus_port(daemon, timeout=30):
    """The Modbus port the daemon bound (it writes STATE_DIR/modbus.addr
    after http.addr, once the Modbus server listens)."""
    path = os.path.join(daemon.state_dir, "modbus.addr")
    deadline = time.time() + timeout
    while time.time() < deadline:
        if os.path.exists(path):
            text = open(path).read().strip()
            if text:
                return int(text.rsplit(":", 1)[1])
        time.sleep(0.05)
    raise RuntimeError("no %s within %d s" % (path, timeout))


def modbus_read(port, start, count, fc=4):
    """One FC03/FC04 read over a raw socket (register values)."""
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(struct.pack(">HHHBBHH", 1, 0, 6, 1, fc, start, count))
        head = b""
        while len(head) < 9:
            head += s.recv(9 - len(head))
        n = head[8]
        data = b""
        while len(data) < n:
            data += s.recv(n - len(data))
    return list(struct.unpack(">%dH" % count, data))


def modbus_write(port, start, values):
    """One FC06 (a single value) or FC16 write over a raw socket; returns
    the exception code of the answer, 0 when the write was accepted."""
    if len(values) == 1:
        pdu = struct.pack(">BHH", 6, start, values[0])
    else:
        pdu = struct.pack(">BHHB%dH" % len(values), 16, start, len(values), 2 * len(values), *values)
    with socket.create_connection(("127.0.0.1", port), timeout=5) as s:
        s.sendall(struct.pack(">HHHB", 1, 0, len(pdu) + 1, 1) + pdu)
        head = b""
        while len(head) < 8:
            data = s.recv(8 - len(head))
            if not data:
                raise RuntimeError("Modbus server closed the connection")
            head += data
        length = struct.unpack_from(">H", head, 4)[0]
        rest = b""
        while len(rest) < length - 2:
            data = s.recv(length - 2 - len(rest))
            if not data:
                raise RuntimeError("Modbus server closed the connection")
            rest += data
    return rest[0] if head[7] & 0x80 else 0


def mesh_measures(vertices, faces):
    """(enclosed volume, bounding box low corner, high corner) of a
    triangle mesh: the volume by the divergence theorem as stl_volume,
    independent of lib/mesh."""
    total = 0.0
    for a, b, c in faces:
        ax, ay, az = vertices[a]
        bx, by, bz = vertices[b]
        cx, cy, cz = vertices[c]
        total += (ax * (by * cz - bz * cy) - ay * (bx * cz - bz * cx) + az * (bx * cy - by * cx))
    lo = [min(v[k] for v in vertices) for k in range(3)]
    hi = [max(v[k] for v in vertices) for k in range(3)]
    return total / 6.0, lo, hi


def read_obj(data):
    """Vertices and triangles of a Wavefront OBJ ("v x y z ...", "f a/.. b c")."""
    vertices, faces = [], []
    for line in data.decode().splitlines():
        if line.startswith("v "):
            vertices.append(tuple(float(t) for t in line.split()[1:4]))
        elif line.startswith("f "):
            idx = [int(t.split("/")[0]) - 1 for t in line.split()[1:]]
            faces.extend((idx[0], idx[i], idx[i + 1]) for i in range(1, len(idx) - 1))
    return vertices, faces


def read_ply(data):
    """Vertices and triangles of a binary little-endian PLY whose vertex
    properties are scalars and whose faces are one list property."""
    head, _, body = data.partition(b"end_header\n")
    sizes = {"float": ("f", 4), "double": ("d", 8), "uchar": ("B", 1), "char": ("b", 1),
             "int": ("i", 4), "uint": ("I", 4), "short": ("h", 2), "ushort": ("H", 2)}
    elements, current = [], None
    for line in head.decode().splitlines():
        words = line.split()
        if words[:1] == ["format"] and words[1] != "binary_little_endian":
            raise ValueError("PLY format %s" % words[1])
        if words[:1] == ["element"]:
            current = [words[1], int(words[2]), []]
            elements.append(current)
        elif words[:1] == ["property"]:
            current[2].append(words[1:])
    offset, vertices, faces = 0, [], []
    for name, count, props in elements:
        if name == "vertex":
            fmt = "<" + "".join(sizes[p[0]][0] for p in props)
            names = [p[-1] for p in props]
            ix, iy, iz = names.index("x"), names.index("y"), names.index("z")
            step = struct.calcsize(fmt)
            for i in range(count):
                v = struct.unpack_from(fmt, body, offset + i * step)
                vertices.append((v[ix], v[iy], v[iz]))
            offset += count * step
        elif name == "face":
            (_, count_type, index_type, _) = props[0]
            cf, cs = sizes[count_type]
            inf, ins = sizes[index_type]
            for i in range(count):
                n = struct.unpack_from("<" + cf, body, offset)[0]
                idx = struct.unpack_from("<%d%s" % (n, inf), body, offset + cs)
                offset += cs + n * ins
                faces.extend((idx[0], idx[j], idx[j + 1]) for j in range(1, n - 1))
        else:
            raise ValueError("PLY element %s" % name)
    return vertices, faces


def decode_draco(data, tmpdir):
    """A Draco blob decoded by Google's draco_decoder (Debian's draco),
    independent of the daemon's encoder: vertices and triangles."""
    drc = os.path.join(tmpdir, "decode.drc")
    obj = os.path.join(tmpdir, "decode.obj")
    with open(drc, "wb") as f:
        f.write(data)
    subprocess.run(["draco_decoder", "-i", drc, "-o", obj], check=True, timeout=120,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    with open(obj, "rb") as f:
        return read_obj(f.read())
