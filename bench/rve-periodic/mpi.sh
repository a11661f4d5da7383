#!/usr/bin/env bash
# bench/rve-periodic/mpi.sh: the periodic ParticLS 5.3 RVE (examples/rve-compression/
# periodic.yaml: 17,160 spheres on the HCP lattice that tiles the cell, about 85,000
# contacts) cut to DURATION s of simulated time, through `floe run` with its outputs (stress
# and energy every 100 steps, vtk every 2,000), on one rank, on two ranks under mpirun (one
# thread a rank) and on one rank of two threads, interleaved; prints each run's wall time,
# the medians and the ratios over one rank (docs/parallel.md, "Periodic cells across ranks").
#   REPS=3 DURATION=0.1 bench/rve-periodic/mpi.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
REPS=${REPS:-3}; DURATION=${DURATION:-0.1}
MPIRUN=${MPIRUN:-mpirun}
MPIFLAGS=${MPIFLAGS:-"--allow-run-as-root --oversubscribe --bind-to none"}
. "$root/bench/lib.sh"
floe_mpi_cli
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
sed "s/^  duration: .*/  duration: $DURATION/" "$root/examples/rve-compression/periodic.yaml" > "$work/scene.yaml"
now() { date +%s.%N; }
for r in $(seq "$REPS"); do
  for c in np1 np2 t2; do
    rm -rf "$work/o_$c"
    s=$(now)
    case $c in
      np1) OMP_NUM_THREADS=1 "$FLOE" run "$work/scene.yaml" -o "$work/o_$c" -q ;;
      np2) OMP_NUM_THREADS=1 $MPIRUN $MPIFLAGS -np 2 "$FLOE" run "$work/scene.yaml" -o "$work/o_$c" -q ;;
      t2) OMP_NUM_THREADS=2 "$FLOE" run "$work/scene.yaml" -o "$work/o_$c" -q ;;
    esac
    e=$(now)
    t=$(python3 -c "print(f'{$e - $s:.2f}')")
    echo "round $r $c $t s"
    echo "$c $t" >> "$work/times"
  done
done
python3 - "$work/times" <<'PY'
import statistics, sys
t = {}
for line in open(sys.argv[1]):
    c, v = line.split()
    t.setdefault(c, []).append(float(v))
m = {c: statistics.median(v) for c, v in t.items()}
print("medians: one rank %.2f s, two ranks %.2f s (%.2fx), one rank of two threads %.2f s (%.2fx)"
      % (m["np1"], m["np2"], m["np1"] / m["np2"], m["t2"], m["np1"] / m["t2"]))
PY
