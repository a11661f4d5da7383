#!/usr/bin/env bash
# bench/random-packing: the cost of the particles' order. N Hertz-Mindlin spheres of lognormal
# radii (median 2 mm) placed by `packing: random` at 22 % solid in a periodic cell, compacted
# by the cell's stress servo to 10 kPa (docs/granular.md: how a granular RVE is made) through
# the CLI (floe run, one thread, pinned to CORE). Since issue 14 session 31 the loader numbers
# a random packing in Morton order of the centres; before, in placement order (a random
# order). Give BASE, a floe CLI built before that change (or any other), to run both
# interleaved.
#   REPS=3 N=20000 DURATION=0.06 bench/random-packing/run.sh
#   BASE=/tmp/base/floe REPS=3 bench/random-packing/run.sh
# Prints each run's particle-steps/s (floe run's summary: the steps, not the scene's loading
# and placement), the medians, the ratio new / BASE and the last stress rows of both (the same
# physics in another order of the sums: a chaotic packing's rows agree statistically, and to
# many digits only over a short run).
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
REPS=${REPS:-3}; N=${N:-20000}; DURATION=${DURATION:-0.06}; CORE=${CORE:-0}
build=${BUILD:-$root/build-bench}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j"$(nproc)" --target floe_cli >/dev/null
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
# the cell holds the spheres at about 22 % solid (random placement's easy range)
side=$(python3 -c "print(f'{(${N} * 4 / 3 * 3.141592653589793 * 0.002**3 / 0.22) ** (1 / 3):.4f}')")
cat > "$work/scene.yaml" <<YAML
dimension: 3
time: {duration: $DURATION, dt: 5.0e-6}
gravity: [0, 0, 0]
materials: [{name: grain, density: 2500, young: 5.0e7, poisson: 0.3}]
laws: [{materials: [grain, grain], model: hertz_mindlin, restitution: 0.5, friction: 0.3}]
cell: {size: [$side, $side, $side], stress: {xx: -1.0e4, yy: -1.0e4, zz: -1.0e4}, max_strain_rate: 10.0}
bodies:
  - packing: random
    material: grain
    region: {min: [0, 0, 0], max: [$side, $side, $side]}
    count: $N
    seed: 5
    max_tries: 10000000
    radius_distribution: {lognormal: {median: 0.002, sigma: 0.1, min: 0.0015, max: 0.0021}, seed: 6}
outputs:
  - {type: stress, every: 1000, file: stress.csv}
YAML
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
run() { # $1 label, $2 CLI
  local out
  if ! out=$(OMP_NUM_THREADS=1 taskset -c "$CORE" "$2" run "$work/scene.yaml" -o "$work/out-$1" 2>&1); then
    echo "$out" >&2; exit 1
  fi
  local pss; pss=$(echo "$out" | sed -n 's/.*particle-steps\/s: *\([0-9.e+-]*\).*/\1/p' | tail -1)
  [[ -n "$pss" ]] || { echo "$out" >&2; echo "no particle-steps/s in $2's summary" >&2; exit 1; }
  echo "$1: N=$N duration=$DURATION particle_steps_per_s=$pss $(echo "$out" | grep -o 'contacts (current): *[0-9]*')"
  echo "$pss" >> "$work/$1.txt"
}
: > "$work/new.txt"; : > "$work/base.txt"
for r in $(seq "$REPS"); do
  [[ -n "${BASE:-}" ]] && run base "$BASE"
  run new "$build/floe"
done
new=$(median < "$work/new.txt")
echo "median new: $new particle-steps/s"
if [[ -n "${BASE:-}" ]]; then
  base=$(median < "$work/base.txt")
  echo "median base: $base particle-steps/s"
  python3 -c "print(f'new / base: {$new / $base:.3f}')"
  echo "last stress rows (base, new):"; tail -1 "$work/out-base/stress.csv"; tail -1 "$work/out-new/stress.csv"
fi
