#!/usr/bin/env bash
# bench/rve-periodic: the cost of a periodic cell against walls (issue #13: "a periodic RVE
# steps within 20 % of the same packing with walls") and the cost of one tangent D.
#   REPS=3 N=1500 DURATION=0.2 bench/rve-periodic/run.sh
# Two scenes from one template: N spheres (r = 4 mm, frictional viscoelastic law) placed at
# random in a 12 cm cube and compacted to 10 kPa isotropic for DURATION s of simulated time,
# (a) in a periodic cell by its stress servo, (b) between six servo walls. Prints each run's
# particle-steps/s and contacts (floe run's summary, the whole run), the medians and the
# ratio periodic / walled; then, from the compacted periodic sample, the wall time of one
# eq 29 tangent and of one perturbation tangent (python/floe RVE), medians of 5.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
REPS=${REPS:-3}; N=${N:-1500}; DURATION=${DURATION:-0.2}
build=${BUILD:-$root/build-bench}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_TESTS=OFF >/dev/null
cmake --build "$build" -j"$(nproc)" --target floe_cli floe_shared >/dev/null
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
common() {
cat <<YAML
dimension: 3
time: {duration: $DURATION, dt: 2.0e-5}
gravity: [0, 0, 0]
materials: [{name: grain, density: 2650}]
laws: [{materials: [grain, grain], model: viscoelastic, kn: 2.0e5, ks: 1.0e5, gn: 2.0, gs: 1.0, friction: 0.3}]
bodies:
  - {packing: random, shape: {sphere: {radius: 0.004}}, material: grain, count: $N, seed: 3,
     region: {min: [0, 0, 0], max: [0.12, 0.12, 0.12]}}
YAML
}
{ common; cat <<YAML
cell: {size: [0.12, 0.12, 0.12], stress: {xx: -1.0e4, yy: -1.0e4, zz: -1.0e4}, max_strain_rate: 2.0}
YAML
} > "$work/periodic.yaml"
{ common; echo "walls:"; for w in "x0 [0, 0, 0] [1, 0, 0]" "x1 [0.12, 0, 0] [-1, 0, 0]" "y0 [0, 0, 0] [0, 1, 0]" \
    "y1 [0, 0.12, 0] [0, -1, 0]" "z0 [0, 0, 0] [0, 0, 1]" "z1 [0, 0, 0.12] [0, 0, -1]"; do
  set -- $w; echo "  - {name: $1, point: $2 $3 $4, normal: $5 $6 $7, material: grain, servo: {pressure: 1.0e4, max_speed: 0.24}}"
  done; } > "$work/walled.yaml"
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
: > "$work/p.txt"; : > "$work/w.txt"
for r in $(seq "$REPS"); do
  for kind in periodic walled; do
    out=$("$build/floe" run "$work/$kind.yaml" -o "$work/out-$kind")
    pss=$(echo "$out" | sed -n 's/.*particle-steps\/s: *\([0-9.e+-]*\).*/\1/p')
    nc=$(echo "$out" | sed -n 's/.*contacts (current): *\([0-9]*\).*/\1/p')
    echo "rve-periodic $kind: N=$N particle_steps_per_s=$pss contacts=$nc"
    echo "$pss" >> "$work/$([ $kind = periodic ] && echo p || echo w).txt"
  done
done
p=$(median < "$work/p.txt"); w=$(median < "$work/w.txt")
echo "median particle-steps/s: periodic $p, walled $w, periodic/walled $(python3 -c "print(f'{$p/$w:.3f}')")"
PYTHONPATH="$root/python" FLOE_LIBRARY="$build/libfloe.so" /usr/bin/python3 - "$work/periodic.yaml" <<'PY'
import statistics, sys, time
import floe
rve = floe.RVE.from_scene(sys.argv[1])
rve.world.run(rve.world.time + 0.2)
n = rve.world.n
def timed(f, k=5):
    ts = []
    for _ in range(k):
        t0 = time.perf_counter(); f(); ts.append(time.perf_counter() - t0)
    return statistics.median(ts)
m = rve.measures()
print(f"sample: N={n} contacts={m.contacts} coordination={m.coordination:.2f} porosity={m.porosity:.3f}")
print(f"tangent eq29: {timed(lambda: rve.tangent()):.4g} s")
rve.tangent("perturbation", strain=1e-6)
print(f"tangent perturbation (6 probes + reference, 1 step + 1 relaxation each = {rve.last_probe_steps} steps): "
      f"{timed(lambda: rve.tangent('perturbation', strain=1e-6), 3):.4g} s")
PY
