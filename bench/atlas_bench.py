#!/usr/bin/env python3
"""Atlas benchmark: `isocharts atlas` with default options on every shared mesh.

Every figure is measured on the written OBJ by `isocharts stats` (not taken from the atlas
run's own report), wall time and peak memory come from the atlas process itself. Prints a
Markdown table (the one kept in bench/README.md) and writes CSV + JSON under bench/results/.

usage: bench/atlas_bench.py [--bin build/apps/isocharts] [--threads 2] [MESH ...]
"""
import argparse
import csv
import json
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SHARED = os.path.normpath(os.path.join(ROOT, "..", "shared", "data", "meshes"))

# Reference figures from the issue text: Microsoft UVAtlas at its default settings, measured on
# this machine on the same files, and the Iso-charts paper's Table I (different files).
UVATLAS = {"bunny": (13, 1.095, 12.6, 0.60, 8.3), "horse": (15, 1.08, 14.2, 0.73, 10.1),
           "gargoyle": (20, None, None, None, 13.5), "feline": (36, None, None, None, 13.0),
           "armadillo": (44, None, None, None, 14.2)}
PAPER = {"bunny": 15, "horse": 19, "feline": 38, "dino": 20}


def run(cmd):
    """Runs cmd, returns (stdout, wall seconds, peak resident memory of that process in MB)."""
    import tempfile
    with tempfile.TemporaryFile("w+") as out, tempfile.TemporaryFile("w+") as err:
        t0 = time.monotonic()
        p = subprocess.Popen(cmd, stdout=out, stderr=err, text=True)
        # wait4 gives this child's own resource usage (ru_maxrss in KiB on Linux).
        _, status, usage = os.wait4(p.pid, 0)
        seconds = time.monotonic() - t0
        p.returncode = os.waitstatus_to_exitcode(status)
        out.seek(0)
        err.seek(0)
        if p.returncode != 0:
            sys.exit(f"atlas_bench: {' '.join(cmd)} failed ({p.returncode}): {err.read().strip()}")
        return out.read(), seconds, usage.ru_maxrss / 1024.0


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "apps", "isocharts"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--out", default=os.path.join(HERE, "results", "atlas"))
    ap.add_argument("meshes", nargs="*")
    a = ap.parse_args()
    meshes = a.meshes or sorted(os.path.join(SHARED, f) for f in os.listdir(SHARED))
    os.makedirs(a.out, exist_ok=True)
    rows = []
    for path in meshes:
        name = os.path.splitext(os.path.basename(path))[0]
        obj = os.path.join(a.out, name + ".obj")
        out, seconds, peak = run([a.bin, "atlas", path, "-o", obj, "--png", os.path.join(a.out, name + ".png"),
                                  "--threads", str(a.threads), "--json", "-q"])
        atlas = json.loads(out)
        stats = json.loads(run([a.bin, "stats", obj, "--json", "-q"])[0])
        row = {"mesh": name, "faces": atlas["faces"], "charts": stats["charts"],
               "charts_before_merge": atlas["charts_before_merge"], "l2": stats["l2_stretch"],
               "linf": stats["linf_stretch"], "packing": stats["packing_ratio"],
               # A zero-area or mirrored triangle breaks a texture as a flipped one does.
               "flipped": stats["flipped"] + stats["zero_area_uv"] + (stats["faces"] if stats["mirrored_charts"] else 0),
               "overlaps": stats["overlapping_pairs"], "seconds": round(seconds, 2), "peak_mb": round(peak),
               "stages": atlas["seconds"]}
        rows.append(row)
        print(f"{name:12s} {row['charts']:3d} charts  L2 {row['l2']:.4f}  Linf {row['linf']:.3f}  "
              f"packing {row['packing']:.3f}  flips {row['flipped']}  overlaps {row['overlaps']}  "
              f"{row['seconds']:.2f} s  {row['peak_mb']} MB", file=sys.stderr, flush=True)
    with open(os.path.join(a.out, "atlas.json"), "w") as f:
        json.dump(rows, f, indent=2)
    with open(os.path.join(a.out, "atlas.csv"), "w", newline="") as f:
        w = csv.writer(f)
        w.writerow(["mesh", "faces", "charts", "charts_before_merge", "l2", "linf", "packing", "flipped",
                    "overlaps", "seconds", "peak_mb"])
        for r in rows:
            w.writerow([r[k] for k in ["mesh", "faces", "charts", "charts_before_merge", "l2", "linf", "packing",
                                       "flipped", "overlaps", "seconds", "peak_mb"]])
    print("| mesh | faces | charts (before merge) | L2 | Linf | packing | flipped | overlapping pairs | "
          "seconds | peak MB | UVAtlas charts / s | paper charts |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        u = UVATLAS.get(r["mesh"])
        uv = f"{u[0]} / {u[4]}" if u else "–"
        print(f"| {r['mesh']} | {r['faces']} | {r['charts']} ({r['charts_before_merge']}) | {r['l2']:.4f} | "
              f"{r['linf']:.3f} | {r['packing']:.3f} | {r['flipped']} | {r['overlaps']} | {r['seconds']:.2f} | "
              f"{r['peak_mb']} | {uv} | {PAPER.get(r['mesh'], '–')} |")


if __name__ == "__main__":
    main()
