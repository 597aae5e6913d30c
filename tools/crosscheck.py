#!/usr/bin/env python3
"""Cross-check isoforge's mesh checker with trimesh, by hand.

    pip install trimesh
    python3 tools/crosscheck.py fixtures/meshes/*.stl out.3mf ...

For each mesh it prints trimesh's verdicts (is_watertight, is_winding_consistent), its
volume and triangle count, and, if an `isoforge` binary is on PATH (or in target/), what
`isoforge check --json` says, flagging disagreements. Exit status 1 if any disagree.
"""

import json
import os
import shutil
import subprocess
import sys


def find_isoforge():
    here = os.path.dirname(os.path.abspath(__file__))
    for cand in ("target/release/isoforge", "target/debug/isoforge"):
        path = os.path.join(here, "..", cand)
        if os.path.exists(path):
            return path
    return shutil.which("isoforge")


def ours(binary, path):
    if binary is None:
        return None
    out = subprocess.run([binary, "check", "--json", path], capture_output=True, text=True)
    if out.returncode == 2:
        return {"error": out.stderr.strip()}
    return json.loads(out.stdout)


def main(paths):
    import trimesh

    binary = find_isoforge()
    disagree = 0
    for path in paths:
        try:
            # process=True merges duplicate vertices, as an STL reader must.
            mesh = trimesh.load(path, force="mesh", process=True)
            theirs = {
                "watertight": bool(mesh.is_watertight),
                "winding_consistent": bool(mesh.is_winding_consistent),
                "volume": float(mesh.volume),
                "triangles": int(len(mesh.faces)),
            }
        except Exception as e:  # trimesh raises many kinds on bad files
            theirs = {"error": str(e)}
        mine = ours(binary, path)
        line = f"{path}: trimesh {theirs}"
        if mine is not None:
            if "error" in mine:
                line += f" | isoforge: unreadable ({mine['error']})"
                same = "error" in theirs
            else:
                line += (
                    f" | isoforge watertight={mine['watertight']} manifold={mine['manifold']} "
                    f"inconsistent_edges={mine['inconsistent_edges']} volume={mine['volume']:.6g}"
                )
                # trimesh's is_watertight means every edge is used exactly twice; ours means no
                # boundary edges, with 3+ uses counted as non-manifold edges instead.
                same = "error" not in theirs and (
                    theirs["watertight"]
                    == (mine["watertight"] and mine["non_manifold_edges"] == 0)
                    and theirs["winding_consistent"] == (mine["inconsistent_edges"] == 0)
                    and (
                        not (theirs["watertight"] and theirs["winding_consistent"])
                        or abs(theirs["volume"] - mine["volume"]) <= 1e-6 * max(1.0, abs(theirs["volume"]))
                    )
                )
            if not same:
                disagree += 1
                line += "  <-- DISAGREE"
        print(line)
    return 1 if disagree else 0


if __name__ == "__main__":
    if len(sys.argv) < 2:
        print(__doc__)
        sys.exit(2)
    sys.exit(main(sys.argv[1:]))
