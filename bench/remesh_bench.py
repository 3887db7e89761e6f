#!/usr/bin/env python3
"""Geometry-image benchmark: runs `isocharts remesh` on the shared meshes and prints one table.

For every mesh in ../shared/data/meshes: the 4-level pyramid 256,128,64,32 from its iso-chart
atlas (watertightness per level, PSNR at 256²); for the Table II models (horse, gargoyle,
feline) a level at about 47k defined samples; for the baseline atlases of ../shared/data/
baseline_atlases (UVAtlas, xatlas) a level at the same defined-sample budget; and the bunny
timing runs (256² and the pyramid, atlas and distance excluded).

Usage: bench/remesh_bench.py [--cli build/apps/isocharts] [--data ../shared/data]
                              [--out bench_out] [--threads 2] [--psnr-samples 1000000]
                              [--only NAME ...] [--skip-pyramid] [--skip-baselines]
The JSON of every run is kept in --out; the table goes to stdout (and --out/summary.txt).
Python 3 standard library only.
"""

import argparse
import json
import os
import subprocess
import sys
import time

PAPER_TABLE_II = {"horse": 88.7, "gargoyle": 85.6, "feline": 82.9}
STAGES = ["charts", "packing", "sampling", "zippering", "reconstruction", "optimization"]


def run(cli, args, report, threads):
    cmd = [cli] + args + ["--json", "--report", report, "--threads", str(threads), "-q"]
    t0 = time.time()
    proc = subprocess.run(cmd, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    wall = time.time() - t0
    if proc.returncode != 0:
        return None, wall, proc.stderr.strip().splitlines()[-1:] or ["exit %d" % proc.returncode]
    return json.loads(proc.stdout), wall, []


def remesh_seconds(level):
    return sum(level["seconds"].get(s, 0.0) for s in STAGES)


def topo(level):
    ok = level["manifold"] and level["euler_preserved"]
    closed = level["closed"] if level["input_boundary_loops"] == 0 else (
        level["boundary_loops"] == level["input_boundary_loops"])
    return "ok" if ok and closed else "FAIL(closed=%s manifold=%s euler %d/%d loops %d/%d)" % (
        level["closed"], level["manifold"], level["euler_characteristic"],
        level["input_euler_characteristic"], level["boundary_loops"], level["input_boundary_loops"])


def fmt_psnr(level):
    p = level.get("psnr")
    return "   n/a" if p is None else "%6.2f" % p


def main():
    here = os.path.dirname(os.path.abspath(__file__))
    root = os.path.dirname(here)
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--cli", default=os.path.join(root, "build", "apps", "isocharts"))
    ap.add_argument("--data", default=os.path.join(root, "..", "shared", "data"))
    ap.add_argument("--out", default="bench_out")
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--psnr-samples", type=int, default=1000000)
    ap.add_argument("--samples", type=int, default=47000, help="defined-sample budget for Table II runs")
    ap.add_argument("--only", nargs="*", help="mesh base names to run (default: all)")
    ap.add_argument("--skip-pyramid", action="store_true")
    ap.add_argument("--skip-baselines", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    meshes_dir = os.path.join(a.data, "meshes")
    meshes = sorted(f for f in os.listdir(meshes_dir) if f.rsplit(".", 1)[-1] in ("obj", "off", "ply"))
    if a.only:
        meshes = [m for m in meshes if m.rsplit(".", 1)[0] in a.only]
    lines = []

    def out(s=""):
        print(s, flush=True)
        lines.append(s)

    common = ["--psnr-samples", str(a.psnr_samples)]
    if not a.skip_pyramid:
        out("== Pyramid 256,128,64,32 from the iso-chart atlas (topology per level; PSNR per level)")
        out("%-18s %-6s %8s %8s %6s %7s %8s  %s" % ("mesh", "level", "defined", "unique", "zero", "PSNR", "remesh s", "topology"))
        for m in meshes:
            name = m.rsplit(".", 1)[0]
            rep = os.path.join(a.out, name + "_pyramid.json")
            res, wall, err = run(a.cli, ["remesh", os.path.join(meshes_dir, m), "-o",
                                         os.path.join(a.out, name + "_pyr.ply"), "--levels", "256,128,64,32"] + common,
                                 rep, a.threads)
            if res is None:
                out("%-18s ERROR %s" % (name, " ".join(err)))
                continue
            for lv in res["levels"]:
                out("%-18s %-6s %8d %8d %6d %7s %8.2f  %s" % (
                    name, "%d" % lv["resolution"][0], lv["defined_samples"], lv["unique_vertices"],
                    lv["degenerate_triangles"], fmt_psnr(lv), remesh_seconds(lv), topo(lv)))
            corr = sum(lv["seconds"]["correspondence"] for lv in res["levels"])
            total = sum(remesh_seconds(lv) for lv in res["levels"]) + corr
            out("%-18s pyramid: atlas %.1f s, remesh+correspondence %.2f s (correspondence %.2f s), wall %.1f s" % (
                name, res["atlas"]["seconds"], total, corr, wall))

    out()
    out("== About %d defined samples (iso-chart atlas vs the paper's Table II)" % a.samples)
    out("%-18s %-15s %-9s %8s %8s %7s %7s %7s  %s" % ("mesh", "atlas", "res", "defined", "unique", "PSNR", "mean",
                                                    "paper", "topology"))
    # The geometric iso-chart atlas, then the same charts parameterized and sized for the
    # normal signal (`--signal normals`: samples follow the curvature).
    variants = (("geometric", []), ("signal normals", ["--signal", "normals"]))
    for name in ("horse", "gargoyle", "feline"):
        files = [m for m in meshes if m.rsplit(".", 1)[0] == name]
        if not files:
            continue
        for label, extra in variants:
            tag = name + ("_samples" if not extra else "_samples_signal")
            rep = os.path.join(a.out, tag + ".json")
            res, wall, err = run(a.cli, ["remesh", os.path.join(meshes_dir, files[0]), "-o",
                                         os.path.join(a.out, tag + ".ply"), "--samples", str(a.samples)]
                                 + extra + common, rep, a.threads)
            if res is None:
                out("%-18s %-15s ERROR %s" % (name, label, " ".join(err)))
                continue
            lv = res["levels"][0]
            out("%-18s %-15s %-9s %8d %8d %7s %7s %7.1f  %s" % (
                name, label, "%dx%d" % tuple(lv["resolution"]), lv["defined_samples"], lv["unique_vertices"],
                fmt_psnr(lv), "%.2f" % lv["psnr_mean"] if lv.get("psnr_mean") is not None else "n/a",
                PAPER_TABLE_II[name], topo(lv)))

    if not a.skip_baselines:
        out()
        out("== Baseline atlases at about %d defined samples (same packer, same pipeline)" % a.samples)
        out("%-24s %-9s %8s %8s %7s %6s  %s" % ("atlas", "res", "defined", "unique", "PSNR", "empty", "topology"))
        base_dir = os.path.join(a.data, "baseline_atlases")
        for f in sorted(os.listdir(base_dir)):
            name = f.rsplit(".", 1)[0]
            model = name.split("_")[0]
            if a.only and model not in a.only:
                continue
            src = [m for m in os.listdir(meshes_dir) if m.rsplit(".", 1)[0] == model]
            if not src:
                continue
            rep = os.path.join(a.out, name + ".json")
            res, wall, err = run(a.cli, ["remesh", os.path.join(meshes_dir, src[0]), "-o",
                                         os.path.join(a.out, name + ".ply"), "--samples", str(a.samples),
                                         "--atlas", os.path.join(base_dir, f)] + common, rep, a.threads)
            if res is None:
                out("%-24s ERROR %s" % (name, " ".join(err)))
                continue
            lv = res["levels"][0]
            out("%-24s %-9s %8d %8d %7s %6d  %s" % (
                name, "%dx%d" % tuple(lv["resolution"]), lv["defined_samples"], lv["unique_vertices"], fmt_psnr(lv),
                lv["empty_charts"], topo(lv)))

    bunny = [m for m in meshes if m.rsplit(".", 1)[0] == "bunny"]
    if bunny:
        out()
        out("== Bunny timing (%d threads; atlas and distance excluded)" % a.threads)
        path = os.path.join(meshes_dir, bunny[0])
        for label, extra in (("256x256", ["--res", "256"]), ("pyramid", ["--levels", "256,128,64,32"])):
            rep = os.path.join(a.out, "bunny_timing_%s.json" % label)
            res, wall, err = run(a.cli, ["remesh", path, "-o", os.path.join(a.out, "bunny_timing.ply"), "--no-psnr"] + extra,
                                 rep, a.threads)
            if res is None:
                out("bunny %s ERROR %s" % (label, " ".join(err)))
                continue
            per = " ".join("%s %.2f" % (s, sum(lv["seconds"][s] for lv in res["levels"])) for s in STAGES + ["correspondence"])
            total = sum(remesh_seconds(lv) + lv["seconds"]["correspondence"] for lv in res["levels"])
            out("bunny %-8s remesh %.2f s (%s); atlas %.1f s; wall %.1f s" % (label, total, per, res["atlas"]["seconds"], wall))

    with open(os.path.join(a.out, "summary.txt"), "w") as f:
        f.write("\n".join(lines) + "\n")


if __name__ == "__main__":
    sys.exit(main())
