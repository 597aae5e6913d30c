#!/usr/bin/env bash
# Side-by-side meshing figures: isoforge against fidget 0.5.1 on the six bench models
# (fixtures/bench), per depth: wall seconds, triangles and peak resident memory, each
# measured by /usr/bin/time -v on the whole process (start-up, script and file writing
# included on both sides).
#
# usage: FIDGET_BENCH=/path/to/fidget-bench tools/mesh-vs-fidget.sh [DEPTH ...]
#   (default depths: 8 9 10; RUNS=3 runs per cell, the median time and the largest peak;
#    ISOFORGE=path picks the isoforge binary, default target/release/isoforge;
#    MODELS="sphere heart" picks models.)
#
# FIDGET_BENCH is a small program outside this repository (fidget pulls its own toolchain
# needs: it is not a dependency of ours) that builds the same six fields with fidget's
# Tree API, meshes them with `fidget::mesh::Octree` at the given depth and writes an STL,
# printing "MODEL depth D triangles T ...". docs/meshing.md says how to make it.
set -euo pipefail
cd "$(dirname "$0")/.."
ISOFORGE=${ISOFORGE:-target/release/isoforge}
RUNS=${RUNS:-3}
MODELS=${MODELS:-"sphere gyroid_sphere heart drope_block sinus_sphere spheres_chain"}
DEPTHS=("$@")
[ ${#DEPTHS[@]} -eq 0 ] && DEPTHS=(8 9 10)
[ -x "$ISOFORGE" ] || { echo "no $ISOFORGE: cargo build --release -p isoforge-cli" >&2; exit 2; }
[ -n "${FIDGET_BENCH:-}" ] && [ -x "$FIDGET_BENCH" ] || {
    echo "set FIDGET_BENCH to the fidget-bench program (see docs/meshing.md)" >&2; exit 2; }
command -v /usr/bin/time >/dev/null || { echo "needs /usr/bin/time (GNU time)" >&2; exit 2; }

work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

# Runs a command under /usr/bin/time -v; prints "seconds peak_kib" and keeps its stdout.
measure() {
    local out=$1; shift
    /usr/bin/time -v -o "$work/time" "$@" >"$out" 2>"$work/err" || {
        cat "$work/err" >&2; echo "failed: $*" >&2; exit 1; }
    awk -F': ' '/Elapsed \(wall clock\)/ { n = split($2, t, ":"); s = 0;
                    for (i = 1; i <= n; i++) s = s * 60 + t[i]; secs = s }
                /Maximum resident set size/ { kib = $2 }
                END { printf "%.3f %d\n", secs, kib }' "$work/time"
}

median() { sort -g | awk '{ v[NR] = $1 } END { print v[int((NR + 1) / 2)] }'; }

printf '| model | depth | isoforge s | fidget s | ratio | isoforge triangles | fidget triangles | isoforge peak MiB | fidget peak MiB |\n'
printf '| --- | --- | --- | --- | --- | --- | --- | --- | --- |\n'
for depth in "${DEPTHS[@]}"; do
    for model in $MODELS; do
        : >"$work/ours"; : >"$work/theirs"
        for _ in $(seq "$RUNS"); do
            # Alternate the two so that a drift in the machine's speed hits both alike.
            measure "$work/ours.json" "$ISOFORGE" mesh "fixtures/bench/$model.rhai" \
                -o "$work/ours.stl" --depth "$depth" --json >>"$work/ours"
            measure "$work/theirs.txt" "$FIDGET_BENCH" "$model" "$depth" "$work/theirs.stl" \
                >>"$work/theirs"
        done
        ours_s=$(cut -d' ' -f1 "$work/ours" | median)
        theirs_s=$(cut -d' ' -f1 "$work/theirs" | median)
        ours_kib=$(cut -d' ' -f2 "$work/ours" | sort -n | tail -1)
        theirs_kib=$(cut -d' ' -f2 "$work/theirs" | sort -n | tail -1)
        ours_t=$(grep -o '"triangles": *[0-9]*' "$work/ours.json" | grep -o '[0-9]*$')
        theirs_t=$(grep -o 'triangles [0-9]*' "$work/theirs.txt" | grep -o '[0-9]*$')
        awk -v m="$model" -v d="$depth" -v a="$ours_s" -v b="$theirs_s" -v ta="$ours_t" \
            -v tb="$theirs_t" -v ka="$ours_kib" -v kb="$theirs_kib" 'BEGIN {
            printf "| %s | %s | %.2f | %.2f | %.2f | %d | %d | %.0f | %.0f |\n",
                m, d, a, b, (b > 0 ? a / b : 0), ta, tb, ka / 1024, kb / 1024 }'
    done
done
