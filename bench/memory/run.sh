#!/usr/bin/env bash
# bench/memory: resident bytes per sphere at 10^6, floe against LIGGGHTS (Debian package),
# the same lattice (side^3 spheres of d = 2 mm at 1 % overlap, 6 touching neighbours each,
# Hertz(-Mindlin) with tangential history), one thread each. Both by the same measure: the
# peak resident size (GNU time's maximum RSS) of a run at SIDE^3 spheres less that of a run
# at 46^3 = 97,336, over the difference in count (the programs' fixed footprint cancels).
#   SIDE=100 bench/memory/run.sh      (10^6 spheres; about a minute, 1 GB at most)
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
SIDE=${SIDE:-100}; SMALL=46
build=${BUILD:-$root/build-bench}
bash "$root/scripts/install-deps.sh" --bench
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j"$(nproc)" --target bench_memory >/dev/null
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
export OMP_NUM_THREADS=1
peak() { /usr/bin/time -f "%M" "$@" 2>"$work/time" >"$work/out"; tail -1 "$work/time"; }
declare -A kb
for s in $SMALL $SIDE; do
  n=$((s * s * s))
  kb[floe$s]=$(peak "$build/bench/bench_memory" "$n" 0)
  grep '^memory' "$work/out"
  kb[lig$s]=$(cd "$work" && peak liggghts -in "$here/in.liggghts" -var side "$s" -log "$work/lig.log" -echo none)
  echo "liggghts memory: N=$n $(grep -o 'Memory usage per processor = .*' "$work/lig.log" | head -1), peak RSS ${kb[lig$s]} kB"
done
python3 - "$SMALL" "$SIDE" "${kb[floe$SMALL]}" "${kb[floe$SIDE]}" "${kb[lig$SMALL]}" "${kb[lig$SIDE]}" <<'PY'
import sys
s, S = int(sys.argv[1]), int(sys.argv[2])
f0, f1, l0, l1 = (int(v) * 1024 for v in sys.argv[3:7])
dn = S**3 - s**3
f, l = (f1 - f0) / dn, (l1 - l0) / dn
print(f"memory at {S**3} spheres (peak RSS difference, {s**3} -> {S**3}): floe {f:.0f} B/sphere, "
      f"LIGGGHTS {l:.0f} B/sphere, floe/LIGGGHTS = {f / l:.2f}")
PY
