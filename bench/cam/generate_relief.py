#!/usr/bin/python3
# Writes two of bench/cam's programs with LinuxCNC's image-to-gcode (the CAM program that LinuxCNC ships: a
# depth image in, a raster of the surface the tool can reach out), headless:
#   /usr/bin/python3 bench/cam/generate_relief.py      (from the repository root; Debian's linuxcnc-uspace)
# The depth images are computed here (numpy) and written as 8-bit PNGs to a temporary folder, where
# image-to-gcode reads them. Its options dialog (Tk) is replaced by the options below, given as the dialog would
# return them; everything else is image-to-gcode's own code, loaded from /usr/bin/image-to-gcode.
import importlib.machinery
import importlib.util
import io
import os
import subprocess
import sys
import tempfile
from contextlib import redirect_stdout

import numpy
from PIL import Image

OUT = os.environ.get("FM_CAM_OUT", os.path.join(os.getcwd(), "bench", "cam"))
I2G = "/usr/bin/image-to-gcode"


def linuxcnc_version():
    try:
        out = subprocess.run(["dpkg-query", "-W", "-f=${Version}", "linuxcnc-uspace"], capture_output=True,
                             text=True, check=True).stdout
        return out.strip()
    except (OSError, subprocess.CalledProcessError):
        return "unknown"


def image_to_gcode(depth01, options):
    """Runs image-to-gcode's main() on a depth image (0 = deepest, 1 = the stock top) and returns its G-code."""
    loader = importlib.machinery.SourceFileLoader("image_to_gcode", I2G)
    spec = importlib.util.spec_from_loader("image_to_gcode", loader)
    module = importlib.util.module_from_spec(spec)
    loader.exec_module(module)
    module.ui = lambda im, nim, name: dict(options)
    with tempfile.TemporaryDirectory() as tmp:
        png = os.path.join(tmp, "depth.png")
        Image.fromarray(numpy.clip(depth01 * 255.0 + 0.5, 0, 255).astype(numpy.uint8), "L").save(png)
        argv = sys.argv
        sys.argv = [I2G, png]
        out = io.StringIO()
        try:
            with redirect_stdout(out):
                module.main()
        finally:
            sys.argv = argv
    return out.getvalue()


def options(**kw):
    base = {"units": 1, "invert": False, "normalize": False, "expand": 0, "tolerance": 0.01, "pixel_size": 0.1,
            "feed_rate": 800, "plunge_feed_rate": 200, "spindle_speed": 18000, "pattern": 0, "converter": 2,
            "depth": 3.0, "pixelstep": 2, "tool_diameter": 1.0, "safety_height": 2.0, "tool_type": 1,
            "bounded": 0, "contact_angle": 45.0, "roughing_offset": 0.0, "roughing_depth": 0.0}
    base.update(kw)
    return base


def write(name, gcode, header):
    path = os.path.join(OUT, name)
    with open(path, "w") as f:
        f.write("(Written by LinuxCNC image-to-gcode, linuxcnc-uspace %s; bench/cam/generate_relief.py)\n"
                % linuxcnc_version())
        for line in header:  # G-code comments do not nest: no parentheses inside
            f.write("(%s)\n" % line.replace("(", "[").replace(")", "]"))
        f.write(gcode)
    print("%s: %d lines" % (path, gcode.count("\n")))


def grid(width_px, height_px, pixel):
    y, x = numpy.mgrid[0:height_px, 0:width_px].astype(numpy.float64) * pixel
    return x, y


def cameo():
    """A cameo: an oval medallion with a rim, a domed face and a profile, on a flat ground; 1 mm flat, rows
    0.16 mm apart (0.08 mm pixels, every second row), 57 mm long."""
    pixel, tool = 0.08, 1.0
    ts = int(tool / pixel + 0.5)
    w, h = int(round(57.0 / pixel)) + ts, int(round(44.0 / pixel)) + ts
    x, y = grid(w, h, pixel)
    cx, cy = x.max() / 2, y.max() / 2
    r = numpy.sqrt(((x - cx) / 25.0) ** 2 + ((y - cy) / 19.0) ** 2)     # 1 on the oval
    d = numpy.full(x.shape, 0.45)                                         # the ground, 1.65 mm deep
    rim = numpy.exp(-((r - 1.0) / 0.04) ** 2)
    inside = r < 0.96
    dome = numpy.where(inside, 0.55 + 0.25 * numpy.sqrt(numpy.clip(1 - (r / 0.96) ** 2, 0, 1)), 0)
    head = 0.2 * numpy.exp(-(((x - cx + 2) / 8.0) ** 2 + ((y - cy - 2) / 10.0) ** 2))
    nose = 0.12 * numpy.exp(-(((x - cx - 7) / 2.0) ** 2 + ((y - cy + 1) / 3.0) ** 2))
    hair = 0.04 * numpy.sin((x - cx) * 1.3 + numpy.sin((y - cy) * 0.5) * 3) * numpy.exp(
        -(((x - cx + 6) / 7.0) ** 2 + ((y - cy - 6) / 6.0) ** 2))
    face = numpy.where(inside, dome + head + nose + hair, 0)
    d = numpy.maximum(d, numpy.maximum(0.85 * rim, face))
    d = numpy.clip(d, 0, 1)
    gcode = image_to_gcode(d, options(pixel_size=pixel, pixelstep=2, tool_diameter=tool, tool_type=1, depth=3.0,
                                      pattern=0, converter=2, tolerance=0.008))
    write("i2g_cameo_raster_1mm.ngc", gcode,
          ["operation: raster finish of a cameo (depth image %d x %d px of 0.08 mm, 3 mm deep), rows along X"
           % (w, h),
           "0.16 mm apart (pixel step 2), alternating, tolerance 0.008 mm; 57 mm passes; tool: 1 mm flat end mill",
           "stock: box:0,0,-4,57,44,0"])


def relief():
    """A doubly curved relief: two bumps, a saddle and a ripple over 80 x 60 mm, 8 mm deep; a 3 mm ball, rows
    then columns 0.5 mm apart, with image-to-gcode's roughing passes (2 mm layers, 0.5 mm left) first."""
    pixel, tool = 0.1, 3.0
    ts = int(tool / pixel + 0.5)
    w, h = int(round(80.0 / pixel)) + ts, int(round(60.0 / pixel)) + ts
    x, y = grid(w, h, pixel)
    u, v = x / x.max() * 2 - 1, y / y.max() * 2 - 1
    d = (0.55 + 0.25 * numpy.exp(-((u + 0.4) ** 2 + (v - 0.2) ** 2) / 0.12)
         + 0.18 * numpy.exp(-((u - 0.45) ** 2 + (v + 0.3) ** 2) / 0.08)
         - 0.12 * (u * v) + 0.05 * numpy.sin(6 * u) * numpy.cos(5 * v) - 0.25 * (u ** 2 + v ** 2) * 0.5)
    d = (d - d.min()) / (d.max() - d.min())
    gcode = image_to_gcode(d, options(pixel_size=pixel, pixelstep=5, tool_diameter=tool, tool_type=0, depth=8.0,
                                      pattern=2, converter=2, tolerance=0.01, feed_rate=1200,
                                      roughing_offset=0.5, roughing_depth=2.0))
    write("i2g_relief_ball3.ngc", gcode,
          ["operation: roughing (2 mm layers, 0.5 mm left) then raster finish of a doubly curved relief",
           "(depth image %d x %d px of 0.1 mm, 8 mm deep), rows then columns 0.5 mm apart (pixel step 5)," % (w, h),
           "alternating, tolerance 0.01 mm; tool: 3 mm ball end mill",
           "stock: box:0,0,-9,84,64,0"])


if __name__ == "__main__":
    only = os.environ.get("FM_CAM_ONLY", "")
    for fn in (cameo, relief):
        if not only or only == fn.__name__:
            fn()
