#!/usr/bin/env bash
# bench/rve-compression: ParticLS §5.3 through the CLI (examples/rve-compression/scene.yaml,
# 16,483 HCP spheres, linear spring-dashpot, a moving top wall, with its outputs: stress
# and the top-wall tracker, every 100 steps) against LIGGGHTS 3.8 on the peers' input (in.liggghts,
# gen_data.py, top.stl: the shared peer benchmark dem-compress-rve), interleaved.
#   REPS=3 FRACTION=1.0 FLOE_THREADS=1 bench/rve-compression/run.sh
#   RANKS=2 REPS=3 FRACTION=0.25 bench/rve-compression/run.sh   # both under mpirun -np 2
#   BIND=core RANKS=2 ...   # both codes' ranks pinned to cores (default: --bind-to none)
#   BALANCE=time RANKS=2 ...   # floe's shares by measured speed (floe run --balance; default
#                              # weights: equal shares of the estimated work)
# FRACTION < 1 runs the first part of the loading only (both codes the same steps). RANKS > 1:
# floe's MPI build (its stress, tracker and energy reduced over the ranks, vtk as .pvtu pieces) and LIGGGHTS, both
# under mpirun -np RANKS, one thread a rank.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
REPS=${REPS:-3}; FRACTION=${FRACTION:-1.0}; FLOE_THREADS=${FLOE_THREADS:-1}; RANKS=${RANKS:-1}
MPIRUN=(); BAL=()
if (( RANKS > 1 )); then
  FLOE_THREADS=1
  BAL=(--balance "${BALANCE:-weights}")
  # BIND=core pins each rank (of both codes) to a core (OpenMPI's own default for np <= 2);
  # the default none leaves the placement to the kernel, as the earlier sessions measured
  MPIRUN=(mpirun --allow-run-as-root --oversubscribe --bind-to "${BIND:-none}" -np "$RANKS")
fi
if [[ -z "${FLOE:-}" ]]; then
  bash "$root/scripts/install-deps.sh" --bench
  if (( RANKS > 1 )); then mpi=ON; build=${BUILD:-$root/build-mpi-bench}; else mpi=OFF; build=${BUILD:-$root/build-bench}; fi
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_TESTS=OFF -DFLOE_WITH_MPI=$mpi >/dev/null
  cmake --build "$build" -j"$(nproc)" --target floe_cli >/dev/null
  FLOE=$build/floe
fi
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
steps=$(python3 -c "print(round(20000 * $FRACTION))")
sed "s/^  duration: 1.0/  duration: $(python3 -c "print($steps * 5e-5)")/" "$root/examples/rve-compression/scene.yaml" > "$work/scene.yaml"
grep -q "duration: $(python3 -c "print($steps * 5e-5)")" "$work/scene.yaml" || { echo "scene duration not set" >&2; exit 1; }
(cd "$work" && python3 "$here/gen_data.py" rve.data >/dev/null && cp "$here/top.stl" .)
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
: > "$work/f.txt"; : > "$work/l.txt"
for r in $(seq "$REPS"); do
  OMP_NUM_THREADS=$FLOE_THREADS "${MPIRUN[@]}" "$FLOE" run "$work/scene.yaml" -o "$work/out" -t "$FLOE_THREADS" "${BAL[@]}" > "$work/floe.log" 2>&1 \
    || { cat "$work/floe.log"; exit 1; }
  n=$(sed -n 's/.*particles: *\([0-9]*\).*/\1/p' "$work/floe.log" | head -1)
  wall=$(sed -n 's/.*wall time: *\([0-9.]*\) s.*/\1/p' "$work/floe.log" | head -1)
  pss=$(python3 -c "print(f'{16483*$steps/$wall:.3e}')")
  echo "floe     rve: ranks=$RANKS threads=$FLOE_THREADS steps=$steps loop_s=$wall particle_steps_per_s=$pss (particles line: ${n:-?})"
  echo "$pss" >> "$work/f.txt"
  (cd "$work" && OMP_NUM_THREADS=1 "${MPIRUN[@]}" liggghts -in "$here/in.liggghts" -var nsteps "$steps" -log "$work/lig.log" -echo none >/dev/null)
  loop=$(sed -n 's/^Loop time of \([0-9.e+-]*\) .*/\1/p' "$work/lig.log" | tail -1)
  pss=$(python3 -c "print(f'{16483*$steps/$loop:.3e}')")
  echo "liggghts rve: ranks=$RANKS steps=$steps loop_s=$loop particle_steps_per_s=$pss"
  echo "$pss" >> "$work/l.txt"
done
f=$(median < "$work/f.txt"); l=$(median < "$work/l.txt")
python3 -c "print(f'rve-compression medians of $REPS ($steps steps): floe {float(\"$f\"):.3e} particle-steps/s ($RANKS rank(s), $FLOE_THREADS thread(s)), LIGGGHTS {float(\"$l\"):.3e}, floe/LIGGGHTS = {float(\"$f\")/float(\"$l\"):.2f}')"
