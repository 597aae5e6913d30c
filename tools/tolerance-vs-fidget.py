#!/usr/bin/env python3
"""The six bench models meshed by isoforge and by fidget 0.5.1 at one depth, each mesh
measured against the model's field by `isoforge check --against`, side by side, by hand.

    cargo build --release -p isoforge-cli
    FIDGET_BENCH=/path/to/fidget-bench python3 tools/tolerance-vs-fidget.py [--depth N]

FIDGET_BENCH is the scratch program that tools/mesh-vs-fidget.sh uses (docs/meshing.md,
"Side by side with fidget 0.5.1", says how to make it). It meshes over [-1, 1]^3 with the
model's coordinates scaled to its region, so its STL is scaled back here by half the
region's side (read from the fixture's `bounds(...)`) before it is checked.

Both meshes are checked with isoforge's default tolerance at that depth (0.1 of a cell)
and with `--depth`, so the points beyond it where the model is narrower than two cells are
counted apart. One line per model and mesher: triangles, the largest distance in
tolerances (everywhere and where wide), the mean in tolerances, the share of the area
beyond the tolerance, the share facing against the field, and whether the mesh is closed
and manifold.
"""

import argparse
import json
import os
import re
import struct
import subprocess
import sys
import tempfile

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)
MODELS = ["sphere", "gyroid_sphere", "heart", "drope_block", "sinus_sphere", "spheres_chain"]


def half_side(script):
    """Half the side of the cubic region of a bench fixture, from its `bounds(...)`."""
    text = open(script).read()
    m = re.search(r"bounds\(\[\s*(-?[\d.]+)\s*,", text)
    if not m:
        sys.exit("no bounds in %s" % script)
    return -float(m.group(1))


def scale_stl(src, dst, factor):
    """A binary STL with every coordinate multiplied by `factor` (normals kept)."""
    data = open(src, "rb").read()
    (count,) = struct.unpack("<I", data[80:84])
    out = bytearray(data[:84])
    for i in range(count):
        at = 84 + 50 * i
        values = list(struct.unpack("<12f", data[at:at + 48]))
        values[3:] = [v * factor for v in values[3:]]
        out += struct.pack("<12f", *values) + data[at + 48:at + 50]
    open(dst, "wb").write(out)


def check(binary, stl, script, tolerance, depth):
    run = subprocess.run(
        [binary, "check", stl, "--against", script, "--tolerance", str(tolerance),
         "--depth", str(depth), "--json"],
        capture_output=True, text=True)
    try:
        return json.loads(run.stdout)
    except json.JSONDecodeError:
        return {"error": run.stderr.strip()}


def row(model, who, j):
    if "error" in j:
        return "| %s | %s | could not be read: %s |" % (model, who, j["error"])
    t = j["tolerance"]
    return "| %s | %s | %d | %.2f | %.2f | %.3f | %.4f %% | %.3f %% | %s |" % (
        model, who, j["triangles"], j["max_deviation"] / t,
        j["max_deviation_where_wide"] / t, j["mean_deviation"] / t,
        100 * j["area_beyond_tolerance"], 100 * j["area_facing_against"],
        "yes" if j["closed_manifold"] else "no")


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--depth", type=int, default=8)
    ap.add_argument("--bin", default=os.path.join(ROOT, "target", "release", "isoforge"))
    args = ap.parse_args()
    fidget = os.environ.get("FIDGET_BENCH")
    if not fidget or not os.access(fidget, os.X_OK):
        sys.exit("set FIDGET_BENCH to the fidget-bench program (see docs/meshing.md)")
    print("| model | mesher | triangles | largest, tolerances | where wide | mean | "
          "area beyond | area facing against | closed, manifold |")
    print("| --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    with tempfile.TemporaryDirectory() as work:
        for model in MODELS:
            script = os.path.join(ROOT, "fixtures", "bench", model + ".rhai")
            ours = os.path.join(work, "ours.stl")
            made = subprocess.run(
                [args.bin, "mesh", script, "--depth", str(args.depth), "--json", "-o", ours],
                capture_output=True, text=True, check=True)
            tolerance = json.loads(made.stdout)["tolerance"]
            raw, theirs = os.path.join(work, "raw.stl"), os.path.join(work, "theirs.stl")
            subprocess.run([fidget, model, str(args.depth), raw], capture_output=True,
                           check=True)
            scale_stl(raw, theirs, half_side(script))
            print(row(model, "isoforge", check(args.bin, ours, script, tolerance, args.depth)))
            print(row(model, "fidget", check(args.bin, theirs, script, tolerance, args.depth)))
            sys.stdout.flush()


if __name__ == "__main__":
    main()
