#!/usr/bin/env python3
"""bench_fleet.py: the fleet's two figures (docs/fleet.md), never a test.

1. Jobs per minute through one Redis Streams queue with 1 and with 2
   frepmilld (one worker and one OpenVDB thread each): a redis-server on a
   free loopback port, N jobs queued at once, the clock runs from the
   daemons' start to the last result. Floor: N jobs cut back to back by
   `frepmill simulate` with one thread (the bare work, no queue, no daemon).
2. One job split into k spatial tiles (k = 1, 2): the stock box is cut
   into k slabs along X and each slab is simulated by its own `frepmill
   simulate` process with the whole program, in parallel (one thread
   each). The slabs' removed volumes add up to the whole job's; the
   speed-up is the k = 1 wall time over the k = 2 one (floor: k).

Usage (from the repository root, after a release build):
  bench/fleet/bench_fleet.py [BUILD_DIR] [--jobs N] [--voxel MM]
"""
import argparse
import json
import math
import os
import shutil
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, "..", ".."))
sys.path.insert(0, os.path.join(ROOT, "tests", "daemon"))
from daemon_util import Daemon  # noqa: E402
from redis_util import RedisServer  # noqa: E402

DEMO = os.path.join(ROOT, "deploy", "demo")
DEMO_BOX = (0.0, 0.0, -30.0, 100.0, 60.0, 0.0)


def slot_program(k, slots=4, length=80.0):
    depth = 1.0 + 0.25 * (k % 8)
    lines = ["G21 G90 G17", "T1 M6", "S10000 M3", "G0 Z5"]
    for i in range(slots):
        y = 10 + 15 * i
        lines += ["G0 X10 Y%g" % y, "G1 Z%g F300" % -depth, "G1 X%g F1000" % (10 + length),
                  "G0 Z5"]
    return "\n".join(lines + ["M30"]) + "\n", slots * depth * (6 * length + math.pi * 9)


TOOLS = {"units": "mm", "tools": [{"number": 1, "shape": "flat", "diameter": 6, "flute_length": 20,
                                    "length": 40}]}
STOCK = "box:0,0,-20,100,80,0"


def cli_floor(frepmill, n, voxel, tmp):
    tools = os.path.join(tmp, "tools.json")
    with open(tools, "w") as f:
        json.dump(TOOLS, f)
    t0 = time.time()
    for k in range(n):
        prog = os.path.join(tmp, "slots%d.ngc" % k)
        with open(prog, "w") as f:
            f.write(slot_program(k)[0])
        subprocess.run([frepmill, "simulate", prog, "--stock", STOCK, "--tools", tools, "--voxel",
                        str(voxel), "--threads", "1"], check=True, stdout=subprocess.DEVNULL,
                       stderr=subprocess.DEVNULL)
    return time.time() - t0


def fleet_run(frepmilld, daemons, n, voxel, tmp):
    redis = RedisServer(shutil.which("redis-server"), os.path.join(tmp, "redis-%d" % daemons))
    r = redis.client()
    for k in range(n):
        job = {"stock": STOCK, "voxel": voxel, "tools": TOOLS,
               "program": {"gcode": slot_program(k)[0]},
               "options": {"name": "bench-%d" % k, "check": False, "color": "none", "threads": 1}}
        r("XADD", "frepmill:jobs", "*", "job", json.dumps(job))
    t0 = time.time()
    ds = [Daemon(frepmilld, os.path.join(tmp, "d%d-%d" % (daemons, i)), "--queue",
                 "redis://127.0.0.1:%d" % redis.port, "--queue-consumer", "d%d" % i,
                 "--workers", "1", "--threads-per-job", "1", "--publish-interval-s", "60",
                 "--snapshot-interval-s", "60") for i in range(daemons)]
    try:
        while r("XLEN", "frepmill:done") < n:
            time.sleep(0.05)
        wall = time.time() - t0
        bad = [k for k, v in zip(r("HKEYS", "frepmill:results"), r("HVALS", "frepmill:results"))
               if json.loads(v)["state"] != "done"]
        if bad:
            raise RuntimeError("jobs failed: %s" % bad)
    finally:
        for d in ds:
            d.stop()
        r.close()
        redis.stop()
    return wall


def tile_run(frepmill, k, voxel, tmp):
    x0, y0, z0, x1, y1, z1 = DEMO_BOX
    procs, reports = [], []
    t0 = time.time()
    for i in range(k):
        a = x0 + (x1 - x0) * i / k
        b = x0 + (x1 - x0) * (i + 1) / k
        rep = os.path.join(tmp, "tile%d-%d.json" % (k, i))
        reports.append(rep)
        procs.append(subprocess.Popen(
            [frepmill, "simulate", os.path.join(DEMO, "pocket.ngc"), "--stock",
             "box:%g,%g,%g,%g,%g,%g" % (a, y0, z0, b, y1, z1), "--tools",
             os.path.join(DEMO, "tools.json"), "--voxel", str(voxel), "--threads", "1",
             "--report", rep], stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL))
    for p in procs:
        if p.wait() != 0:
            raise RuntimeError("a tile's simulation failed")
    wall = time.time() - t0
    removed = 0.0
    for rep in reports:
        with open(rep) as f:
            removed += json.load(f)["removed_volume_mm3"]
    return wall, removed


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("build", nargs="?", default=os.path.join(ROOT, "build", "release"))
    ap.add_argument("--jobs", type=int, default=12)
    ap.add_argument("--voxel", type=float, default=0.2)
    ap.add_argument("--tile-voxel", type=float, default=0.1)
    args = ap.parse_args()
    frepmill = os.path.join(args.build, "daemon", "frepmill")
    frepmilld = os.path.join(args.build, "daemon", "frepmilld")
    if not shutil.which("redis-server"):
        sys.exit("bench_fleet: redis-server is not installed")
    print("machine: %d cores, load %s" % (os.cpu_count(), open("/proc/loadavg").read().split()[:3]))
    with tempfile.TemporaryDirectory(prefix="fm-bench-fleet-") as tmp:
        floor = cli_floor(frepmill, args.jobs, args.voxel, tmp)
        print("floor: %d jobs back to back with frepmill simulate (1 thread): %.2f s = %.1f jobs/min"
              % (args.jobs, floor, 60 * args.jobs / floor))
        one = fleet_run(frepmilld, 1, args.jobs, args.voxel, tmp)
        print("1 daemon : %d jobs in %.2f s = %.1f jobs/min (%.2fx the floor's time)"
              % (args.jobs, one, 60 * args.jobs / one, one / floor))
        two = fleet_run(frepmilld, 2, args.jobs, args.voxel, tmp)
        print("2 daemons: %d jobs in %.2f s = %.1f jobs/min (%.2fx the floor's time; speed-up %.2f"
              " over 1 daemon, ideal 2)" % (args.jobs, two, 60 * args.jobs / two, two / floor,
                                            one / two))
        w1, v1 = tile_run(frepmill, 1, args.tile_voxel, tmp)
        w2, v2 = tile_run(frepmill, 2, args.tile_voxel, tmp)
        print("tiles: demo pocket at %g mm: k=1 %.2f s, removed %.3f mm3; k=2 %.2f s, removed %.3f "
              "mm3 (difference %.2e of the whole); speed-up %.2f (ideal 2)"
              % (args.tile_voxel, w1, v1, w2, v2, abs(v2 - v1) / v1, w1 / w2))


if __name__ == "__main__":
    main()
