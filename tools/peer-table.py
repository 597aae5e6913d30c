#!/usr/bin/env python3
"""Slices the calibration models with isoforge, PrusaSlicer and CuraEngine and prints the
side-by-side table of docs/slicing.md (markdown): slicing time, layers, retractions, the
shortest layer time and the extruded volume of the part. Every G-code file is read by the
same judge, `isoforge check FILE.gcode --json`, so the three are counted alike.

    python3 tools/peer-table.py [--isoforge target/release/isoforge] [--runs 3]

Needs prusa-slicer and CuraEngine on PATH; CuraEngine's printer definitions are looked up
in CURA_DEFS (default: fdmprinter.def.json under /usr/share/cura/resources/definitions).
Times are the least wall and CPU (user + system) seconds of --runs runs, each the whole
process (start-up included); on a busy machine the CPU figure is the steadier one.
"""

import argparse
import json
import os
import resource
import subprocess
import sys
import tempfile
import time

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.dirname(HERE)

# The shared basic settings: 0.2 mm layers, two perimeters, 20% infill, 0.4 mm nozzle,
# 1.75 mm filament, a 220 mm Marlin bed. Each slicer keeps its own defaults otherwise
# (cooling, speeds, retraction), as a user would get them.
PRUSA = ["prusa-slicer", "--export-gcode", "--layer-height", "0.2", "--first-layer-height",
         "0.2", "--perimeters", "2", "--fill-density", "20%", "--nozzle-diameter", "0.4",
         "--filament-diameter", "1.75", "--gcode-flavor", "marlin2", "--center", "110,110"]
CURA_SETTINGS = ["layer_height=0.2", "layer_height_0=0.2", "wall_line_count=2",
                 "infill_sparse_density=20", "machine_gcode_flavor=RepRap (Marlin/Sprinter)",
                 "machine_width=220", "machine_depth=220", "center_object=true"]

WALL = """// One free-standing wall 20 mm long, 10 mm tall, t mm thick.
let t = param("t", 0.4, 0.1, 5.0);
bounds([-11, -2, -1], [11, 2, 11]);
max(max(abs(x) - 10, abs(y) - t / 2), abs(z - 5) - 5)
"""


def best_time(cmd, runs):
    """The least wall and CPU (user + system) seconds of `runs` runs, whole processes."""
    best = None
    for _ in range(runs):
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        t0 = time.monotonic()
        subprocess.run(cmd, check=True, stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
        wall = time.monotonic() - t0
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
        cpu = (after.ru_utime - before.ru_utime) + (after.ru_stime - before.ru_stime)
        best = (wall, cpu) if best is None else (min(best[0], wall), min(best[1], cpu))
    return best


def judge(isoforge, gcode):
    out = subprocess.run([isoforge, "check", gcode, "--json"], check=True,
                         capture_output=True, text=True).stdout
    j = json.loads(out)
    part = sum(v for k, v in j["volume_mm3"].items()
               if "skirt" not in k.lower() and "brim" not in k.lower())
    return j, part


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--isoforge", default=os.path.join(ROOT, "target/release/isoforge"))
    ap.add_argument("--runs", type=int, default=3)
    args = ap.parse_args()
    defs = os.environ.get("CURA_DEFS", "/usr/share/cura/resources/definitions")
    cura_def = os.path.join(defs, "fdmprinter.def.json")
    work = tempfile.mkdtemp()
    wall_script = os.path.join(work, "wall.rhai")
    with open(wall_script, "w") as f:
        f.write(WALL)
    models = [("20 mm cube", os.path.join(ROOT, "fixtures/slice/cube.rhai"), [], None),
              ("torus R15 r5", os.path.join(ROOT, "fixtures/slice/torus.rhai"), [], None),
              ("3 mm pin, 40 mm", os.path.join(ROOT, "fixtures/slice/pin_tall.rhai"), [], None)]
    for t in (0.4, 0.6, 0.8, 1.2):
        models.append((f"{t} mm wall", wall_script, ["--param", f"t={t}"], t * 20 * 10))
    print("| model | slicer | time (s): wall / CPU | layers | retractions | shortest layer (s) "
          "| part volume (mm³) |")
    print("|---|---|---:|---:|---:|---:|---:|")
    for label, script, params, exact in models:
        stem = os.path.join(work, label.replace(" ", "_"))
        stl = stem + ".stl"
        subprocess.run([args.isoforge, "mesh", script, *params, "-o", stl, "-q",
                        "--resolution", "0.05"], check=True)
        runs = {
            "isoforge": [args.isoforge, "slice", script, *params, "-o", stem + ".ours.gcode",
                         "-q"],
            "PrusaSlicer 2.5": PRUSA + [stl, "-o", stem + ".prusa.gcode"],
            "CuraEngine 4.13": ["CuraEngine", "slice", "-j", cura_def]
            + [a for s in CURA_SETTINGS for a in ("-s", s)]
            + ["-e0", "-s", "material_diameter=1.75", "-l", stl, "-o", stem + ".cura.gcode"],
        }
        for name, cmd in runs.items():
            wall, cpu = best_time(cmd, args.runs)
            gcode = cmd[cmd.index("-o") + 1]
            j, part = judge(args.isoforge, gcode)
            vol = f"{part:.0f}"
            if exact:
                vol += f" ({100 * part / exact:.0f}%)"
            shortest = j["layer_seconds_min"]
            shortest = "-" if shortest is None else f"{shortest:.1f}"
            print(f"| {label} | {name} | {wall:.2f} / {cpu:.2f} | {j['layers']} "
                  f"| {j['retractions']} | {shortest} | {vol} |")
        sys.stdout.flush()


if __name__ == "__main__":
    main()
