#!/usr/bin/env bash
# bench/polyhedra-settle: 5,000 random convex polyhedra settling in a walled box against the
# same scene with volume-equivalent spheres (same sites, masses, law, dt and steps), floe
# only, one thread. Prints each run and the medians of particle-steps/s, ns per candidate
# pair evaluation and ns per contact, and the polyhedra/spheres ratios.
#   REPS=3 STEPS=2000 N=5000 bench/polyhedra-settle/run.sh
#   REPS=1 STEPS=2000 WARMUP=40000 bench/polyhedra-settle/run.sh    # the settled bed (~30 min)
#   FLOE_BENCH_CKPT=/tmp/poly.ckpt REPS=3 STEPS=2000 WARMUP=40000 bench/polyhedra-settle/run.sh
#     # the first run saves both warmed-up beds (/tmp/poly.ckpt.N.WARMUP.spheres, .polyhedra),
#     # the others load them: the settled bed in about a minute a run
# The library is built without CGAL/assimp (not needed: the grains are built from planes),
# in its own build folder (BUILD, default build-bench-poly), Release -O3 -march=native.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
REPS=${REPS:-3}; STEPS=${STEPS:-2000}; N=${N:-5000}; WARMUP=${WARMUP:-0}
build=${BUILD:-$root/build-bench-poly}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_TESTS=OFF -DFLOE_BUILD_EXAMPLES=OFF \
  -DFLOE_WITH_CGAL=OFF -DFLOE_WITH_ASSIMP=OFF >/dev/null
cmake --build "$build" -j"$(nproc)" --target bench_polyhedra_settle >/dev/null
export OMP_NUM_THREADS=1
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
for r in $(seq "$REPS"); do
  "$build/bench/bench_polyhedra_settle" "$STEPS" "$N" "$WARMUP" | tee -a "$work/all.txt"
done
python3 - "$work/all.txt" "$REPS" <<'PY'
import re, statistics, sys
rows = {"spheres": [], "polyhedra": []}
for line in open(sys.argv[1]):
    m = re.match(r"(spheres|polyhedra)\s", line)
    if m:
        kv = dict(re.findall(r"(\w+)=([-0-9.e+]+)", line))
        rows[m.group(1)].append({k: float(v) for k, v in kv.items()})
med = {k: {f: statistics.median(r[f] for r in v) for f in v[0]} for k, v in rows.items()}
for k in ("spheres", "polyhedra"):
    m = med[k]
    print("%s medians of %s: %.3e particle-steps/s, %.1f ns per pair evaluation, %.1f ns per contact, "
          "%.0f contacts at the end" % (k, sys.argv[2], m["particle_steps_per_s"], m["ns_per_pair_eval"],
                                       m["ns_per_contact"], m["contacts_end"]))
s, p = med["spheres"], med["polyhedra"]
print("polyhedra/spheres: throughput %.3f (time per step %.1fx), ns per pair evaluation %.1fx, ns per contact %.1fx"
      % (p["particle_steps_per_s"] / s["particle_steps_per_s"], s["particle_steps_per_s"] / p["particle_steps_per_s"],
         p["ns_per_pair_eval"] / s["ns_per_pair_eval"], p["ns_per_contact"] / s["ns_per_contact"]))
PY
