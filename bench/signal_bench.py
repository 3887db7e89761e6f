#!/usr/bin/env python3
"""Signal-specialized atlas benchmark (Iso-charts §7, §9.3): SAE of three atlases per mesh.

For every mesh and signal, `isocharts atlas --signal S --signal-use U` is run with U in
  none  - the geometric atlas (signal only measured),
  param - geometric charts, signal-specialized parameterization and signal-weighted packing,
  full  - signal charts (signal-metric splitting, eq. 6 distances) and signal parameterization,
packed for a RES x RES texture, and the SAE at RES x RES is read from its JSON report.
The colour case bakes a procedural pattern into the vertex colours of a mesh (written as an
ASCII PLY under --out, never into the repository).

Prints a Markdown table and writes JSON under bench/results/signal/; with --renders DIR also
writes small renders of the reconstructed signal (the baked texture on the atlas).

usage: bench/signal_bench.py [--bin build/apps/isocharts] [--threads 2] [--res 256] [--renders DIR]
"""
import argparse
import json
import math
import os
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
SHARED = os.path.normpath(os.path.join(ROOT, "..", "shared", "data", "meshes"))
USES = ["none", "param", "full"]


def run(cmd):
    t0 = time.monotonic()
    p = subprocess.run(cmd, capture_output=True, text=True)
    if p.returncode != 0:
        sys.exit(f"signal_bench: {' '.join(cmd)} failed ({p.returncode}): {p.stderr.strip()}")
    return p.stdout, time.monotonic() - t0


def read_off_or_obj(path):
    """Positions and triangles of an OFF or OBJ file (the shared meshes: triangles only)."""
    verts, faces = [], []
    with open(path) as f:
        if path.endswith(".off"):
            tokens = f.read().split()
            nv, nf = int(tokens[1]), int(tokens[2])
            i = 4
            for _ in range(nv):
                verts.append(tuple(float(t) for t in tokens[i:i + 3]))
                i += 3
            for _ in range(nf):
                n = int(tokens[i])
                faces.append(tuple(int(t) for t in tokens[i + 1:i + 1 + n]))
                i += 1 + n
        else:
            for line in f:
                p = line.split()
                if not p:
                    continue
                if p[0] == "v":
                    verts.append(tuple(float(t) for t in p[1:4]))
                elif p[0] == "f":
                    faces.append(tuple(int(t.split("/")[0]) - 1 for t in p[1:4]))
    return verts, faces


def write_coloured_ply(src, dst):
    """Bakes a procedural pattern into vertex colours: stripes whose frequency rises along the
    model's longest axis, so the signal is dense on one side and smooth on the other."""
    verts, faces = read_off_or_obj(src)
    lo = [min(v[i] for v in verts) for i in range(3)]
    hi = [max(v[i] for v in verts) for i in range(3)]
    axis = max(range(3), key=lambda i: hi[i] - lo[i])
    other = (axis + 1) % 3
    with open(dst, "w") as f:
        f.write("ply\nformat ascii 1.0\n")
        f.write(f"element vertex {len(verts)}\nproperty float x\nproperty float y\nproperty float z\n")
        f.write("property uchar red\nproperty uchar green\nproperty uchar blue\n")
        f.write(f"element face {len(faces)}\nproperty list uchar int vertex_indices\nend_header\n")
        for v in verts:
            t = (v[axis] - lo[axis]) / (hi[axis] - lo[axis])
            s = (v[other] - lo[other]) / (hi[other] - lo[other])
            w = 0.5 + 0.5 * math.sin(2 * math.pi * (2 + 10 * t * t) * s) if t > 0.4 else 0.5
            r, g, b = (int(round(255 * c)) for c in (w, 0.3 + 0.4 * t, 1 - w))
            f.write(f"{v[0]} {v[1]} {v[2]} {r} {g} {b}\n")
        for t in faces:
            f.write(f"3 {t[0]} {t[1]} {t[2]}\n")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bin", default=os.path.join(ROOT, "build", "apps", "isocharts"))
    ap.add_argument("--threads", type=int, default=2)
    ap.add_argument("--res", type=int, default=256)
    ap.add_argument("--out", default=os.path.join(HERE, "results", "signal"))
    ap.add_argument("--renders", default="", help="directory for renders of the reconstructed signal")
    ap.add_argument("--render-mesh", default="bunny", help="mesh whose atlases are rendered")
    ap.add_argument("--meshes", nargs="*", default=["bunny.obj", "horse.ply", "gargoyle.off"])
    ap.add_argument("--color-mesh", default="bunny_lowres.off")
    ap.add_argument("--uses", nargs="*", default=USES, choices=USES, help="atlases to build (default: all three)")
    ap.add_argument("--beta", type=float, default=None, help="eq. 6 beta for the full atlases (default: the CLI's)")
    a = ap.parse_args()
    os.makedirs(a.out, exist_ok=True)
    cases = [(os.path.join(SHARED, m), "normals") for m in a.meshes]
    if a.color_mesh:
        ply = os.path.join(a.out, os.path.splitext(a.color_mesh)[0] + "_colored.ply")
        write_coloured_ply(os.path.join(SHARED, a.color_mesh), ply)
        cases.append((ply, "colors"))
    rows = []
    for path, signal in cases:
        name = os.path.splitext(os.path.basename(path))[0]
        row = {"mesh": name, "signal": signal}
        for use in a.uses:
            obj = os.path.join(a.out, f"{name}_{signal}_{use}.obj")
            tex = os.path.join(a.out, f"{name}_{signal}_{use}.png")
            out, seconds = run([a.bin, "--threads", str(a.threads), "--json", "-q", "atlas", path, "-o", obj,
                                "--width", str(a.res), "--height", str(a.res), "--signal", signal,
                                "--signal-use", use, "--sae-res", str(a.res), "--signal-texture-out", tex] +
                               (["--beta", str(a.beta)] if a.beta is not None and use == "full" else []))
            j = json.loads(out)
            row[use] = {"sae": j["sae"], "signal_stretch": j["signal"]["signal_stretch"], "charts": j["charts"],
                        "l2": j["l2_stretch"], "linf": j["linf_stretch"], "flipped": j["flipped"],
                        "overlapping_pairs": j["overlapping_pairs"], "seconds": seconds,
                        "chart_linf": max(c["linf"] if c["linf"] is not None else float("inf")
                                          for c in j["chart_list"]),
                        "signal_seconds": j["seconds"].get("signal", 0.0), "obj": obj, "texture": tex}
            print(f"{name} {signal} {use}: SAE {j['sae']:.5f} charts {j['charts']} {seconds:.1f} s", file=sys.stderr)
            if a.renders and name == a.render_mesh:
                os.makedirs(a.renders, exist_ok=True)
                run([a.bin, "-q", "render", obj, "--texture", tex, "--views", "2", "--width", "480", "--height",
                     "240", "-o", os.path.join(a.renders, f"signal_{name}_{signal}_{use}.png")])
        rows.append(row)
    with open(os.path.join(a.out, "signal_bench.json"), "w") as f:
        json.dump(rows, f, indent=1)

    if a.uses != USES:
        for r in rows:
            print(r["mesh"], r["signal"], " ".join(f"{u}: SAE {r[u]['sae']:.5f} charts {r[u]['charts']} "
                                                  f"chart Linf {r[u]['chart_linf']:.2f} flipped+overlap "
                                                  f"{r[u]['flipped'] + r[u]['overlapping_pairs']}" for u in a.uses))
        return
    print(f"| mesh | signal | SAE geometric atlas | SAE geometric charts + signal param | "
          f"SAE signal charts + signal param | signal stretch (none / param / full) | charts (none / param / full) | "
          f"atlas Linf (none / param / full) | max chart Linf | flipped + overlapping pairs | "
          f"seconds (none / param / full) |")
    print("|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        def cell(k, fmt):
            return " / ".join(fmt.format(r[u][k]) if r[u][k] is not None else "–" for u in USES)
        bad = sum(r[u]["flipped"] + r[u]["overlapping_pairs"] for u in USES)
        print(f"| {r['mesh']} | {r['signal']} | {r['none']['sae']:.5f} | {r['param']['sae']:.5f} | "
              f"{r['full']['sae']:.5f} | {cell('signal_stretch', '{:.3f}')} | {cell('charts', '{}')} | "
              f"{cell('linf', '{:.2f}')} | {cell('chart_linf', '{:.2f}')} | {bad} | {cell('seconds', '{:.1f}')} |")


if __name__ == "__main__":
    main()
