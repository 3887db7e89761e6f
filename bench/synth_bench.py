#!/usr/bin/env python3
"""Texture-synthesis benchmark: runs `isocharts synth` on bunny and horse with four shared
exemplars (bricks, gravel, wicker, cells_161) over the MCGIM pyramid 256,128,64,32, renders
each result from four sides, checks byte-identical outputs for --threads 1 and 2 on one case,
and prints a markdown table (start level and direction-field symmetry the tool chose, seam
error, match error, texel-scale spread, seconds).

Usage: bench/synth_bench.py [--cli build/apps/isocharts] [--data ../shared/data]
                            [--out bench_out/synth] [--threads 2] [--pixels-per-texel 1.0]
                            [--renders DIR] [--only MESH ...] [--skip-determinism]
The JSON of every run is kept in --out; renders (1000x250 PNG, four views of the mesh on its
iso-chart atlas) go to --renders (default: --out, as MESH_EXEMPLAR_render.png). Python 3 standard library only.
"""

import argparse
import filecmp
import json
import os
import subprocess
import sys
import time

# Up axis of each model for the renders (horse.ply is z-up).
UP = {"horse": "z"}

MESHES = {"bunny": "meshes/bunny.obj", "horse": "meshes/horse.ply"}
EXEMPLARS = ["bricks.png", "gravel.png", "wicker.png", "cells_161.jpg"]
LEVELS = "256,128,64,32"


def synth(cli, mesh, exemplar, out, threads, ppt, seed=1):
    report = out[: -len(".glb")] + ".json"
    cmd = [cli, "synth", mesh, "--exemplar", exemplar, "--levels", LEVELS, "--pixels-per-texel", str(ppt),
           "-o", out, "--threads", str(threads), "--seed", str(seed), "--json", "--report", report, "-q"]
    t0 = time.time()
    p = subprocess.run(cmd, capture_output=True, text=True)
    wall = time.time() - t0
    if p.returncode != 0:
        sys.exit("failed (%d): %s\n%s" % (p.returncode, " ".join(cmd), p.stderr))
    with open(report) as f:
        return json.load(f), wall


def main():
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--cli", default="build/apps/isocharts")
    ap.add_argument("--data", default="../shared/data")
    ap.add_argument("--out", default="bench_out/synth")
    ap.add_argument("--renders", default=None)
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--pixels-per-texel", type=float, default=1.0)
    ap.add_argument("--only", nargs="*", default=None)
    ap.add_argument("--skip-determinism", action="store_true")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    renders = a.renders or a.out
    os.makedirs(renders, exist_ok=True)

    rows = []
    for mesh_name, rel in MESHES.items():
        if a.only and mesh_name not in a.only:
            continue
        for ex in EXEMPLARS:
            ex_name = os.path.splitext(ex)[0]
            out = os.path.join(a.out, "%s_%s.glb" % (mesh_name, ex_name))
            j, wall = synth(a.cli, os.path.join(a.data, rel), os.path.join(a.data, "exemplars", ex), out,
                            a.threads, a.pixels_per_texel)
            stem = out[: -len(".glb")]
            # In --out itself, the render must not take the synthesized texture's name.
            suffix = "_render" if os.path.abspath(renders) == os.path.abspath(a.out) else ""
            render = os.path.join(renders, "%s_%s%s.png" % (mesh_name, ex_name, suffix))
            subprocess.run([a.cli, "render", stem + ".obj", "--texture", stem + ".png", "--views", "4",
                            "--width", "1000", "--height", "250", "--up", UP.get(mesh_name, "y"), "-o", render, "-q"], check=True,
                           capture_output=True)
            rows.append((mesh_name, ex_name, j, wall, render))
            print("%s %s: %.1f s" % (mesh_name, ex_name, wall), file=sys.stderr)

    det = None
    if not a.skip_determinism:
        mesh = os.path.join(a.data, MESHES["bunny"])
        ex = os.path.join(a.data, "exemplars", "cells_161.jpg")
        outs = []
        for t in (1, 2):
            # Same file names in two folders: the OBJ names its MTL.
            os.makedirs(os.path.join(a.out, "threads%d" % t), exist_ok=True)
            out = os.path.join(a.out, "threads%d" % t, "det.glb")
            synth(a.cli, mesh, ex, out, t, a.pixels_per_texel, seed=5)
            outs.append(out[: -len(".glb")])
        same = all(filecmp.cmp(outs[0] + s, outs[1] + s, shallow=False)
                   for s in (".glb", ".png", "_mcgim.glb", "_mcgim.png", ".obj", "_mcgim.obj"))
        det = "bunny + cells_161, seed 5: --threads 1 vs 2 outputs (glb, obj, png; atlas and MCGIM) %s" % (
            "byte-identical" if same else "DIFFER")

    lines = ["| mesh | exemplar | charts | start level | field N | copy off scale | seam error | match error "
             "| texel-scale spread | synthesis s | total s |",
             "|---|---|---|---|---|---|---|---|---|---|---|"]
    for mesh_name, ex_name, j, wall, _ in rows:
        se = j["seam_error"]
        start = j.get("start_level")
        level = "%d²" % j["levels"][start]["resolution"][0] if start is not None else "?"
        lines.append("| %s | %s | %d | %s | %s | %.3f | %s | %.3f | %.3f | %.1f | %.1f |" % (
            mesh_name, ex_name, j["charts"], level, j.get("direction_symmetry", "?"), j.get("copy_scale_off", 0),
            "n/a" if se is None else "%.3f" % se, j["match_error"],
            j["texel_scale_spread"], j["seconds_breakdown"]["synthesis"], j["seconds"]))
    text = "\n".join(lines) + "\n"
    if det:
        text += "\n" + det + "\n"
    print(text)
    with open(os.path.join(a.out, "summary.md"), "w") as f:
        f.write(text)


if __name__ == "__main__":
    main()
