#!/usr/bin/env bash
# bench/dem-settle: 20,000 Hertz-Mindlin spheres settling in a walled box, floe versus
# LIGGGHTS (Debian package), one thread each, same initial state and physics.
#   REPS=3 STEPS=5000 bench/dem-settle/run.sh
#   FLOE_THREADS=2 ...   floe on 2 threads (OpenMP), LIGGGHTS on one process as before
# Prints each run and the medians of particle-steps/s (loop time only) and the ratio.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
REPS=${REPS:-3}; STEPS=${STEPS:-5000}; FLOE_THREADS=${FLOE_THREADS:-1}
build=${BUILD:-$root/build-bench}
bash "$root/scripts/install-deps.sh" --bench
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j"$(nproc)" --target bench_dem_settle >/dev/null
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
python3 "$here/gen_data.py" "$work/settle.data" >/dev/null
export OMP_NUM_THREADS=1
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
: > "$work/floe.txt"; : > "$work/lig.txt"
for r in $(seq "$REPS"); do
  line=$(OMP_NUM_THREADS=$FLOE_THREADS "$build/bench/bench_dem_settle" "$work/settle.data" "$STEPS")
  echo "$line"
  echo "$line" | sed -n 's/.*particle_steps_per_s=\([^ ]*\).*/\1/p' >> "$work/floe.txt"
  (cd "$work" && liggghts -in "$here/in.liggghts" -var nsteps "$STEPS" -var data "$work/settle.data" -log "$work/lig.log" -echo none >/dev/null)
  loop=$(sed -n 's/^Loop time of \([0-9.e+-]*\) .*/\1/p' "$work/lig.log" | tail -1)
  natoms=$(awk '/^ *Step +Atoms/{getline; print $2; exit}' "$work/lig.log")
  pss=$(python3 -c "print(f'{20000*$STEPS/$loop:.3e}')")
  echo "liggghts dem-settle: N=$natoms steps=$STEPS loop_s=$loop particle_steps_per_s=$pss"
  echo "$pss" >> "$work/lig.txt"
done
f=$(median < "$work/floe.txt"); l=$(median < "$work/lig.txt")
python3 -c "print(f'dem-settle medians of $REPS: floe {float(\"$f\"):.3e} particle-steps/s, LIGGGHTS {float(\"$l\"):.3e}, floe/LIGGGHTS = {float(\"$f\")/float(\"$l\"):.2f}')"
