#!/usr/bin/env python3
"""Texture-bake benchmark: `isocharts atlas --bake-texture` of a large texture.

Makes, in a temporary directory, the shared bunny with spherical texture coordinates (the
texture wraps around it) and an RGBA PNG of SIZE² texels (a pattern, written with the standard
library), then carries it onto the bunny's atlas at SIZE² and reports the wall time, the peak
memory of the atlas process and the `--report` seconds (`bake` includes writing the PNG).

usage: bench/bake_bench.py [--bin build/apps/isocharts] [--size 8192] [--threads 2] [--keep DIR]
"""
import argparse
import json
import math
import os
import struct
import subprocess
import sys
import tempfile
import time
import zlib

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
BUNNY = os.path.normpath(os.path.join(ROOT, "..", "shared", "data", "meshes", "bunny.obj"))


def write_model(directory):
    """The bunny with a texture coordinate per vertex from its direction seen from its centroid."""
    points, faces = [], []
    with open(BUNNY) as f:
        for line in f:
            if line.startswith("v "):
                points.append(tuple(map(float, line.split()[1:4])))
            elif line.startswith("f "):
                faces.append([w.split("/")[0] for w in line.split()[1:]])
    c = [sum(p[k] for p in points) / len(points) for k in range(3)]
    with open(os.path.join(directory, "model.obj"), "w") as out:
        out.write("mtllib model.mtl\nusemtl m\n")
        for p in points:
            out.write("v %r %r %r\n" % p)
        for x, y, z in points:
            u = (math.atan2(z - c[2], x - c[0]) / (2 * math.pi)) % 1.0
            v = math.atan2(y - c[1], math.hypot(x - c[0], z - c[2])) / math.pi + 0.5
            out.write("vt %.6f %.6f\n" % (u, v))
        for f in faces:
            out.write("f " + " ".join("%s/%s" % (i, i) for i in f) + "\n")
    with open(os.path.join(directory, "model.mtl"), "w") as out:
        out.write("newmtl m\nKd 1 1 1\nmap_Kd texture.png\n")


def write_texture(path, size):
    """An RGBA PNG of size² texels: stripes that differ per channel, opaque."""
    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", zlib.crc32(kind + data) & 0xFFFFFFFF)
    row = bytes([0]) + bytes(((x * 31) % 256 if x % 4 != 3 else 255) for x in range(size * 4))
    compressor = zlib.compressobj(6)
    body = b"".join(compressor.compress(row) for _ in range(size)) + compressor.flush()
    with open(path, "wb") as out:
        out.write(b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", size, size, 8, 6, 0, 0, 0)) +
                  chunk(b"IDAT", body) + chunk(b"IEND", b""))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "apps", "isocharts"))
    ap.add_argument("--size", type=int, default=8192, help="texture and atlas size in texels")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--keep", help="make the files in this directory and keep them")
    args = ap.parse_args()
    if not os.path.exists(args.bin):
        sys.exit(f"bake_bench: {args.bin} not found (build first)")
    directory = args.keep or tempfile.mkdtemp(prefix="bake_bench_")
    os.makedirs(directory, exist_ok=True)
    write_model(directory)
    write_texture(os.path.join(directory, "texture.png"), args.size)
    report = os.path.join(directory, "report.json")
    cmd = [args.bin, "-q", "--threads", str(args.threads), "--report", report, "atlas",
           os.path.join(directory, "model.obj"), "-o", os.path.join(directory, "atlas.obj"),
           "--width", str(args.size), "--height", str(args.size),
           "--bake-texture", os.path.join(directory, "baked.png")]
    t0 = time.monotonic()
    p = subprocess.Popen(cmd, stdout=subprocess.DEVNULL)
    _, status, usage = os.wait4(p.pid, 0)
    seconds = time.monotonic() - t0
    if os.waitstatus_to_exitcode(status) != 0:
        sys.exit("bake_bench: the atlas run failed: " + " ".join(cmd))
    with open(report) as f:
        stages = json.load(f)["seconds"]
    print(f"size {args.size}², threads {args.threads}: wall {seconds:.2f} s, peak {usage.ru_maxrss / 1024:.0f} MB")
    print("  " + ", ".join(f"{k} {v:.2f}" for k, v in sorted(stages.items())))
    if not args.keep:
        for name in os.listdir(directory):
            os.remove(os.path.join(directory, name))
        os.rmdir(directory)


if __name__ == "__main__":
    main()
