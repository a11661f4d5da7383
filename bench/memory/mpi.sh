#!/usr/bin/env bash
# bench/memory/mpi.sh: resident memory of each rank of `floe run` under mpirun, against one
# process, on a lattice of SIDE^3 spheres (d = 2 mm, 0.1 mm apart, Hertz-Mindlin with
# friction, a floor; energy output only). Each run is sampled AFTER seconds in (the split
# done, the run going: VmRSS) and its peak so far (VmHWM: the start, where every rank still
# holds the whole scene), per rank in rank order; rank 0 also holds the unsplit mirror of the
# whole world that the gathered outputs and checkpoints use (docs/parallel.md, "Memory per
# rank"). Prints one line per rank count, then the same tiny scene's footprint (libraries).
#   SIDE=60 RANKS="1 2 4" AFTER=24 bench/memory/mpi.sh       (216,000 spheres: a minute a count)
#   FLOE=path/to/floe ... (an MPI build; default: bench/lib.sh floe_mpi_cli)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
. "$root/bench/lib.sh"
SIDE=${SIDE:-60}; RANKS=${RANKS:-"1 2 4"}; AFTER=${AFTER:-24}
floe_mpi_cli
work=$(mktemp -d); trap 'pkill -x floe 2>/dev/null || true; rm -rf "$work"' EXIT
scene() {  # scene SIDE DURATION
  cat <<YAML
name: memory-mpi
dimension: 3
time: {duration: $2, dt: 2.0e-6}
gravity: [0, 0, -9.81]
materials:
  - {name: glass, density: 2500, young: 1.0e7, poisson: 0.3}
laws:
  - {materials: [glass, glass], model: hertz_mindlin, restitution: 0.5, friction: 0.5}
walls:
  - {point: [0, 0, 0], normal: [0, 0, 1], material: glass}
bodies:
  - {packing: lattice, shape: {sphere: {radius: 0.001}}, material: glass,
     origin: [0.0012, 0.0012, 0.0012], counts: [$1, $1, $1], spacing: 0.0021}
outputs:
  - {type: energy, every: 100, file: energy.csv}
YAML
}
sample() {  # sample NP SCENE: "rss/peak" MB per rank after AFTER seconds
  local np=$1
  if (( np == 1 )); then "$FLOE" run "$2" -o "$work/out" -q -t 1 >/dev/null 2>&1 &
  else mpirun --allow-run-as-root --oversubscribe -np "$np" "$FLOE" run "$2" -o "$work/out" -q -t 1 >/dev/null 2>&1 & fi
  sleep "$AFTER"
  local line=""
  for p in $(pgrep -x floe | sort -n); do
    line="$line $(awk '/VmRSS/{r=$2}/VmHWM/{h=$2}END{printf "%.0f/%.0f", r/1024, h/1024}' "/proc/$p/status")"
  done
  pkill -x floe || true; wait || true
  echo "$line"
}
scene "$SIDE" 1.0 > "$work/big.yaml"
scene 2 100.0 > "$work/tiny.yaml"
echo "memory per rank, RSS/peak MB in rank order, $((SIDE * SIDE * SIDE)) spheres, sampled ${AFTER} s in:"
for np in $RANKS; do echo "  np $np:$(sample "$np" "$work/big.yaml")"; done
echo "the same with 8 spheres (the libraries' footprint):"
for np in $RANKS; do echo "  np $np:$(sample "$np" "$work/tiny.yaml")"; done
