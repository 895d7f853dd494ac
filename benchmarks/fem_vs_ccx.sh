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
# Each linear solver in $SOLVERS (default "cholesky amg") runs in its own
# process, so each peak RSS is its own.
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
first=1
for solver in ${SOLVERS:-cholesky amg}; do
  sed "s/\"nonlinear\": false/\"nonlinear\": false, \"linear_solver\": \"$solver\"/" "$out/cantilever.json" > "$out/$solver.json"
  /usr/bin/time -f "%e %M" -o "$out/$solver.time" \
    "$spec2fab" simulate fem "$out/$solver.json" --out "$out/$solver" --repeat "$repeats" -q
  if [ $first = 1 ]; then
    # ccx right after the first solver, on the deck it wrote.
    cp "$out/$solver/calculix.inp" "$out/ccx/job.inp"
    (cd "$out/ccx" && /usr/bin/time -f "%e %M" -o ../ccx.time ccx -i job > ccx.log 2>&1)
    read -r ccx_wall ccx_kb < "$out/ccx.time"
    flat=$(tr -d ' \n' < "$out/$solver/simulation.json")
    field() { grep -o "\"$1\":[0-9.eE+-]*" <<< "$flat" | head -1 | sed 's/.*://'; }
    printf "mesh: %d tets, %d free DOFs (TetGen %.1f s)\n" "$(field tets)" "$(field free_dofs)" "$(field mesh_seconds)"
    awk -v w="$ccx_wall" -v kb="$ccx_kb" 'BEGIN { printf "ccx (SPOOLES), whole linear job: %8.2f s, peak RSS %6.0f MB\n", w, kb / 1024 }'
    first=0
  fi
  read -r our_wall our_kb < "$out/$solver.time"
  flat=$(tr -d ' \n' < "$out/$solver/simulation.json")
  field() { grep -o "\"$1\":[0-9.eE+-]*" <<< "$flat" | head -1 | sed 's/.*://'; }
  tip=$(grep -o '"displacement_mm":\[[^]]*\]' <<< "$flat" | head -1 || true)
  awk -v solver="$solver" -v setup_s="$(field pattern_and_analysis_seconds)" -v eval_s="$(field simulate_seconds)" \
      -v cg="$(field cg_iterations)" -v our_wall="$our_wall" -v our_kb="$our_kb" -v ccx_wall="$ccx_wall" \
      -v ccx_kb="$ccx_kb" -v reps="$repeats" -v tip="$tip" 'BEGIN {
    solve = setup_s + eval_s;
    printf "spec2fab %-8s linear static solve: %8.2f s (setup %.2f s + evaluation %.2f s, mean of %d; CG iterations %d)\n", solver, solve, setup_s, eval_s, reps, cg;
    printf "spec2fab %-8s whole process: %8.2f s (TetGen and %d evaluations included), peak RSS %6.0f MB\n", solver, our_wall, reps, our_kb / 1024;
    printf "spec2fab %-8s vs ccx: %.2fx faster (solve), memory %.2f x ccx; tip %s\n", solver, ccx_wall / solve, our_kb / ccx_kb, tip;
  }'
done
echo "ccx: $out/ccx/job.dat (node displacements); deck: $out/ccx/job.inp"
