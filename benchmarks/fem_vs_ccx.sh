#!/usr/bin/env bash
# The fem simulator against CalculiX (ccx) on the same mesh, side by side in
# one session: a 100 x 10 x 10 mm VeroWhitePlus cantilever meshed by TetGen
# (max tet volume $1, default 0.0625 mm^3: ~320,000 tets), clamped at x = 0,
# 100 N down on the end face, small-strain linear.
#
#   benchmarks/fem_vs_ccx.sh [MAX_TET_VOLUME_MM3] [REPEATS]
#
# spec2fab runs `simulate fem` with write_calculix_deck, so ccx gets exactly
# the mesh, materials, constraints and nodal loads the simulator solved.
# Both run on one core (OPENBLAS_NUM_THREADS=1, OMP_NUM_THREADS=1, ccx's
# SPOOLES is serial). Reported: wall seconds and peak RSS (/usr/bin/time),
# and from simulation.json the setup (pattern + symbolic analysis) and the
# per-evaluation time (materials, assembly, numeric refactorisation, solve):
# what an optimizer pays per call.
set -euo pipefail
cd "$(dirname "$0")/.."
volume=${1:-0.0625}
repeats=${2:-3}
out=${BENCH_OUT:-/tmp/spec2fab_fem_vs_ccx}
spec2fab=build/spec2fab
command -v ccx > /dev/null || { echo "fem_vs_ccx: ccx not found (apt-get install calculix-ccx)" >&2; exit 2; }
[ -x "$spec2fab" ] || { echo "fem_vs_ccx: build first (scripts/build release)" >&2; exit 2; }
rm -rf "$out"
mkdir -p "$out/ccx"
datasets=$(pwd)/datasets
cat > "$out/cantilever.json" <<JSON
{
  "materials": "$datasets/materials/polyjet.json",
  "printer": "$datasets/printers/objet500_connex_flex.json",
  "mesh": "$datasets/meshes/beam_100x10x10.stl",
  "subtree": {"type": "layered", "material": "VeroWhitePlus"},
  "simulator": {
    "max_tet_volume_mm3": $volume,
    "fixed": [{"min": [0, 0, 0], "max": [0, 10, 10]}],
    "loads": [{"min": [100, 0, 0], "max": [100, 10, 10], "force_n": [0, 0, -100]}],
    "probes": [[100, 5, 5]],
    "nonlinear": false,
    "write_calculix_deck": true
  }
}
JSON
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
/usr/bin/time -f "%e %M" -o "$out/spec2fab.time" \
  "$spec2fab" simulate fem "$out/cantilever.json" --out "$out/run" --repeat "$repeats" -q
cp "$out/run/calculix.inp" "$out/ccx/job.inp"
(cd "$out/ccx" && /usr/bin/time -f "%e %M" -o ../ccx.time ccx -i job > ccx.log 2>&1)

read -r our_wall our_kb < "$out/spec2fab.time"
read -r ccx_wall ccx_kb < "$out/ccx.time"
flat=$(tr -d ' \n' < "$out/run/simulation.json")
field() { grep -o "\"$1\":[0-9.eE+-]*" <<< "$flat" | head -1 | sed 's/.*://'; }
tets=$(field tets); dofs=$(field free_dofs); mesh_s=$(field mesh_seconds)
setup_s=$(field pattern_and_analysis_seconds); eval_s=$(field simulate_seconds)
tip=$(grep -o '"displacement_mm":\[[^]]*\]' <<< "$flat" | head -1 || true)
awk -v tets="$tets" -v dofs="$dofs" -v mesh_s="$mesh_s" -v setup_s="$setup_s" -v eval_s="$eval_s" \
    -v our_wall="$our_wall" -v our_kb="$our_kb" -v ccx_wall="$ccx_wall" -v ccx_kb="$ccx_kb" -v reps="$repeats" 'BEGIN {
  solve = setup_s + eval_s;
  printf "mesh: %d tets, %d free DOFs (TetGen %.1f s)\n", tets, dofs, mesh_s;
  printf "ccx (SPOOLES), whole linear job:        %8.2f s, peak RSS %6.0f MB\n", ccx_wall, ccx_kb / 1024;
  printf "spec2fab linear static solve:           %8.2f s (pattern + analysis %.2f s, first solve %.2f s)\n", solve, setup_s, eval_s;
  printf "spec2fab evaluation (refactor + solve): %8.2f s each, mean of %d\n", eval_s, reps;
  printf "spec2fab whole process:                 %8.2f s (TetGen and %d evaluations included), peak RSS %6.0f MB\n", our_wall, reps, our_kb / 1024;
  printf "ratio ccx / spec2fab solve: %.2f x; memory spec2fab / ccx: %.2f\n", ccx_wall / solve, our_kb / ccx_kb;
}'
echo "tip probe: $tip"
echo "ccx: $out/ccx/job.dat (node displacements); deck: $out/ccx/job.inp"
