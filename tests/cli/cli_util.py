"""cli_util.py: what the Python CLI tests share: run frepmill, collect
failed checks (every check runs; the test fails at the end if any did),
write a closed box as binary STL."""
import os
import struct
import subprocess

ROOT = os.path.abspath(os.path.join(os.path.dirname(__file__), "..", ".."))
failures = []


def check(cond, message):
    print(("ok: " if cond else "FAIL: ") + message)
    if not cond:
        failures.append(message)
    return cond


def summary(name):
    if failures:
        print("%s: %d failed" % (name, len(failures)))
        return 1
    print("%s: all passed" % name)
    return 0


def run(*args, timeout=600):
    """Run a command; returns (exit status, stdout text, stderr text)."""
    out = subprocess.run(list(args), stdout=subprocess.PIPE, stderr=subprocess.PIPE, timeout=timeout)
    return out.returncode, out.stdout.decode(errors="replace"), out.stderr.decode(errors="replace")


def write_box_stl(path, lo, hi):
    """A closed, outward-facing box [lo, hi] as binary STL (12 triangles)."""
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    v = [(x0, y0, z0), (x1, y0, z0), (x1, y1, z0), (x0, y1, z0),
         (x0, y0, z1), (x1, y0, z1), (x1, y1, z1), (x0, y1, z1)]
    faces = [(0, 2, 1), (0, 3, 2), (4, 5, 6), (4, 6, 7), (0, 1, 5), (0, 5, 4),
             (1, 2, 6), (1, 6, 5), (2, 3, 7), (2, 7, 6), (3, 0, 4), (3, 4, 7)]
    with open(path, "wb") as f:
        f.write(b"\0" * 80 + struct.pack("<I", len(faces)))
        for face in faces:
            f.write(struct.pack("<3f", 0, 0, 0))
            for i in face:
                f.write(struct.pack("<3f", *v[i]))
            f.write(b"\0\0")
