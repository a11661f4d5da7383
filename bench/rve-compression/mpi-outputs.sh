#!/usr/bin/env bash
# bench/rve-compression/mpi-outputs.sh: the walled and the periodic ParticLS 5.3 RVE
# (examples/rve-compression/scene.yaml cut to DURATION s, periodic.yaml to PDURATION s) through
# `floe run` with their outputs (stress, top-wall tracker and energy every 100 steps, vtk every
# 2,000), on one process and under `mpirun -np 2` (one thread a rank), interleaved; with BASE
# set to another floe binary (an older build), the same runs of it in the same rounds, for an
# A/B of the outputs' cost under MPI (bench/RESULTS.md, "Issue 14, session 21"). Prints each
# run's wall time (the whole command, startup included), the medians and two ranks over one.
#   REPS=3 bench/rve-compression/mpi-outputs.sh
#   BASE=/tmp/old/build-rel/floe REPS=3 bench/rve-compression/mpi-outputs.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
REPS=${REPS:-3}; DURATION=${DURATION:-0.25}; PDURATION=${PDURATION:-0.1}
MPIRUN=${MPIRUN:-mpirun}
MPIFLAGS=${MPIFLAGS:-"--allow-run-as-root --oversubscribe --bind-to none"}
. "$root/bench/lib.sh"
floe_mpi_cli
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
sed "s/^  duration: .*/  duration: $DURATION/" "$root/examples/rve-compression/scene.yaml" > "$work/walled.yaml"
sed "s/^  duration: .*/  duration: $PDURATION/" "$root/examples/rve-compression/periodic.yaml" > "$work/periodic.yaml"
builds="B"; [[ -n "${BASE:-}" ]] && builds="A B"
now() { date +%s.%N; }
export OMP_NUM_THREADS=1
for r in $(seq "$REPS"); do
  for sc in walled periodic; do
    for np in 1 2; do
      for v in $builds; do
        F=$FLOE; [[ $v == A ]] && F=$BASE
        rm -rf "$work/o"
        s=$(now)
        if [[ $np == 1 ]]; then "$F" run "$work/$sc.yaml" -o "$work/o" -q
        else $MPIRUN $MPIFLAGS -x OMP_NUM_THREADS=1 -np 2 "$F" run "$work/$sc.yaml" -o "$work/o" -q; fi
        e=$(now)
        t=$(python3 -c "print(f'{$e - $s:.2f}')")
        echo "round $r $sc np$np $v $t s"
        echo "$sc np$np $v $t" >> "$work/times"
      done
    done
  done
done
python3 - "$work/times" <<'PY'
import statistics, sys
t = {}
for line in open(sys.argv[1]):
    sc, np_, v, s = line.split()
    t.setdefault((sc, v), {}).setdefault(np_, []).append(float(s))
for (sc, v), d in sorted(t.items()):
    m1, m2 = statistics.median(d["np1"]), statistics.median(d["np2"])
    print(f"{sc} {'(BASE)' if v == 'A' else ''}: one rank {m1:.2f} s, two ranks {m2:.2f} s: {m1 / m2:.2f}x (medians)")
PY
