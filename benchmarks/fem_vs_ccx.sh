#!/usr/bin/env bash
# The fem simulator against CalculiX (ccx) on the same mesh, side by side in
# one session, small-strain linear, meshed by TetGen (max tet volume $1).
#   PART=cantilever (default): a 100 x 10 x 10 mm VeroWhitePlus beam,
#     clamped at x = 0, 100 N down on the end face (0.0625 mm^3: ~321,000 tets).
#   PART=voxel: a 40 x 30 x 20 mm block of 10 mm cells, a checkerboard of
#     VeroWhitePlus and DM9840 (E 2500 : 1.69 MPa, a 1.48e3 contrast, the
#     rubber at nu 0.49), clamped at z = 0, its top pressed and sheared by
#     (20, 0, -100) N (0.045 mm^3: ~1.1 M tets).
#
#   benchmarks/fem_vs_ccx.sh [MAX_TET_VOLUME_MM3] [REPEATS]
#
# spec2fab runs `simulate fem` with write_calculix_deck, so ccx gets exactly
# the mesh, materials, constraints and nodal loads the simulator solved.
# Each linear solver in $SOLVERS (default "cholesky amg gamg block_amg") runs in its own
# process, so each peak RSS is its own. CCX=0 skips ccx (its figures are
# then missing). RANKS=N (N > 1) also runs gamg under `mpirun -np N` and
# compares its displacements with the one-process gamg run.
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
case "${PART:-cantilever}" in
  cantilever)
    mesh=beam_100x10x10.stl
    subtree='{"type": "layered", "material": "VeroWhitePlus"}'
    boxes='"fixed": [{"min": [0, 0, 0], "max": [0, 10, 10]}],
    "loads": [{"min": [100, 0, 0], "max": [100, 10, 10], "force_n": [0, 0, -100]}],
    "probes": [[100, 5, 5]]' ;;
  voxel)
    mesh=box_40x30x20.stl
    cells=""
    for k in 0 1; do for j in 0 1 2; do for i in 0 1 2 3; do
      if [ $(((i + j + k) % 2)) = 0 ]; then m=VeroWhitePlus; else m=DM9840; fi
      cells="$cells${cells:+, }{\"type\": \"layered\", \"material\": \"$m\"}"
    done; done; done
    subtree="{\"type\": \"voxel\", \"size_mm\": 10, \"children\": [$cells]}"
    boxes='"fixed": [{"min": [0, 0, 0], "max": [40, 30, 0]}],
    "loads": [{"min": [0, 0, 20], "max": [40, 30, 20], "force_n": [20, 0, -100]}],
    "probes": [[40, 30, 20], [20, 15, 20], [20, 15, 10]]' ;;
  *) echo "fem_vs_ccx: PART is cantilever or voxel" >&2; exit 2 ;;
esac
cat > "$out/part.json" <<JSON
{
  "materials": "$datasets/materials/polyjet.json",
  "printer": "$datasets/printers/objet500_connex_flex.json",
  "mesh": "$datasets/meshes/$mesh",
  "subtree": $subtree,
  "simulator": {
    "max_tet_volume_mm3": $volume,
    $boxes,
    "nonlinear": false,
    "write_calculix_deck": true
  }
}
JSON
export OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1
first=1
for solver in ${SOLVERS:-cholesky amg gamg block_amg}; do
  sed "s/\"nonlinear\": false/\"nonlinear\": false, \"linear_solver\": \"$solver\"/" "$out/part.json" > "$out/$solver.json"
  /usr/bin/time -f "%e %M" -o "$out/$solver.time" \
    "$spec2fab" simulate fem "$out/$solver.json" --out "$out/$solver" --repeat "$repeats" -q
  if [ $first = 1 ]; then
    # ccx right after the first solver, on the deck it wrote.
    ccx_wall=0 ccx_kb=0
    if [ "${CCX:-1}" != 0 ]; then
      cp "$out/$solver/calculix.inp" "$out/ccx/job.inp"
      (cd "$out/ccx" && /usr/bin/time -f "%e %M" -o ../ccx.time ccx -i job > ccx.log 2>&1)
      read -r ccx_wall ccx_kb < "$out/ccx.time"
    fi
    flat=$(tr -d ' \n' < "$out/$solver/simulation.json")
    field() { grep -o "\"$1\":[0-9.eE+-]*" <<< "$flat" | head -1 | sed 's/.*://'; }
    printf "mesh: %d tets, %d free DOFs (TetGen %.1f s)\n" "$(field tets)" "$(field free_dofs)" "$(field mesh_seconds)"
    [ "${CCX:-1}" = 0 ] || awk -v w="$ccx_wall" -v kb="$ccx_kb" 'BEGIN { printf "ccx (SPOOLES), whole linear job: %8.2f s, peak RSS %6.0f MB\n", w, kb / 1024 }'
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
    if (ccx_kb > 0) printf "spec2fab %-8s vs ccx: %.2fx faster (solve), memory %.2f x ccx; tip %s\n", solver, ccx_wall / solve, our_kb / ccx_kb, tip;
    else printf "spec2fab %-8s probe %s\n", solver, tip;
  }'
done
ranks=${RANKS:-1}
if [ "$ranks" -gt 1 ]; then
  sed "s/\"nonlinear\": false/\"nonlinear\": false, \"linear_solver\": \"gamg\"/" "$out/part.json" > "$out/gamg.json"
  [ -d "$out/gamg" ] || "$spec2fab" simulate fem "$out/gamg.json" --out "$out/gamg" --repeat "$repeats" -q
  /usr/bin/time -f "%e %M" -o "$out/ranks.time" mpirun --allow-run-as-root --oversubscribe --mca btl self,vader -np "$ranks" \
    "$spec2fab" simulate fem "$out/gamg.json" --out "$out/gamg_ranks" --repeat "$repeats" -q
  flat=$(tr -d ' \n' < "$out/gamg_ranks/simulation.json")
  field() { grep -o "\"$1\":[0-9.eE+-]*" <<< "$flat" | head -1 | sed 's/.*://'; }
  read -r ranks_wall ranks_kb < "$out/ranks.time"
  difference=$(paste -d, "$out/gamg/displacements.csv" "$out/gamg_ranks/displacements.csv" | awk -F, 'NR > 1 {
      for (k = 5; k <= 7; ++k) { d = $k - $(k + 7); if (d < 0) d = -d; if (d > worst) worst = d; a = $k; if (a < 0) a = -a; if (a > big) big = a }
    } END { printf "%.2e", worst / big }')
  awk -v ranks="$ranks" -v setup_s="$(field pattern_and_analysis_seconds)" -v eval_s="$(field simulate_seconds)" \
      -v cg="$(field cg_iterations)" -v wall="$ranks_wall" -v kb="$ranks_kb" -v diff="$difference" 'BEGIN {
    printf "spec2fab gamg x %d ranks linear static solve: %8.2f s (setup %.2f s + evaluation %.2f s; CG iterations %d)\n", ranks, setup_s + eval_s, setup_s, eval_s, cg;
    printf "spec2fab gamg x %d ranks whole run: %8.2f s, peak RSS of one rank %6.0f MB; displacements within %s of one process (largest difference / largest displacement)\n", ranks, wall, kb / 1024, diff;
  }'
fi
[ "${CCX:-1}" = 0 ] || echo "ccx: $out/ccx/job.dat (node displacements); deck: $out/ccx/job.inp"
