#!/usr/bin/env bash
# bench/sea-ice-field: N polygon floes (default 10,000) stepped three ways (move only; with
# ocean/wind drag and Coriolis, every step and every 10th; with Hopkins' ridging contacts, forcing every
# step and every 10th), floe only, one thread:
# floe-steps/s, the breakdown in ns per floe-step, contacts, heap bytes per floe. REPS runs,
# medians printed by the program's lines (grep the last REPS blocks).
#   REPS=3 N=10000 STEPS=500 WARM=200 bench/sea-ice-field/run.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
REPS=${REPS:-3}; N=${N:-10000}; STEPS=${STEPS:-500}; WARM=${WARM:-200}
build=${BUILD:-$root/build-bench-ice}
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_TESTS=OFF -DFLOE_BUILD_EXAMPLES=OFF \
  -DFLOE_WITH_CGAL=OFF -DFLOE_WITH_ASSIMP=OFF >/dev/null
cmake --build "$build" -j"$(nproc)" --target bench_sea_ice_field >/dev/null
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
for r in $(seq "$REPS"); do "$build/bench/bench_sea_ice_field" "$N" "$STEPS" "$WARM" | tee -a "$work/all.txt"; done
python3 - "$work/all.txt" "$N" <<'PY'
import re, statistics, sys
rows = {}
for line in open(sys.argv[1]):
    m = re.match(r"(move|forcing10|forcing|contacts10|contacts)\s", line)
    if m:
        rows.setdefault(m.group(1), []).append({k: float(v) for k, v in re.findall(r"(\w+)=([-0-9.e+]+)", line)})
med = {k: {f: statistics.median(r[f] for r in v) for f in v[0]} for k, v in rows.items()}
for k in ("move", "forcing", "forcing10", "contacts", "contacts10"):
    print("median %-10s %.3e floe-steps/s, %.0f contacts, %.0f bytes/floe" % (k, med[k]["floe_steps_per_s"],
          med[k]["contacts"], med[k]["bytes_per_floe"]))
t = {k: 1e9 / med[k]["floe_steps_per_s"] for k in med}
print("median breakdown per floe-step: move %.1f ns, forcing %.1f ns (every 10th step %.1f ns), contacts %.1f ns "
      "(%.0f ns per contact)" % (t["move"], t["forcing"] - t["move"], t["forcing10"] - t["move"],
      t["contacts"] - t["forcing"], (t["contacts"] - t["forcing"]) * float(sys.argv[2]) / med["contacts"]["contacts"]))
PY
