#!/usr/bin/env bash
# bench/pd-impact: PMB peridynamic cylinder (R 13.5 mm, H 14 mm, h 0.5 mm: 66,381 points)
# hit by a rigid sphere (fix indent, K 1e17, 4 mm, -100 m/s), 500 steps of 1e-7 s: floe
# against LAMMPS PERI (Debian package, /usr/bin/lmp), one thread each, interleaved.
#   REPS=3 STEPS=500 bench/pd-impact/run.sh
#   PD_R=0.006 PD_H=0.006 bench/pd-impact/run.sh     # smaller cylinder (5,733 points), quick
#   ALPHA0=1 ...      also one untimed run of each with alpha = 0 (constant s0 = s00)
#   PD_ALPHA=0 ...    floe with a constant critical stretch in the timed runs (default 0.25,
#                     LAMMPS' value in in.lammps: s0 = s00 - alpha s_min per point)
#   CONTACT=0 ...     skip the one-off run of floe's contact-law indenter (it stops at step ~37)
# Prints each run, the medians of the loop times, bond-updates/s on the family-size basis
# (bonds counted from both ends, LAMMPS' "total # of bonds"), the ratio and the damage.
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
REPS=${REPS:-3}; STEPS=${STEPS:-500}
R=${PD_R:-0.0135}; H=${PD_H:-0.014}
build=${BUILD:-$root/build-bench-pd}
command -v lmp >/dev/null || apt-get install -y lammps >/dev/null
cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_TESTS=OFF -DFLOE_WERROR=ON >/dev/null
cmake --build "$build" -j"$(nproc)" --target bench_pd_impact >/dev/null
bin="$build/bench/bench_pd_impact"
work=$(mktemp -d); trap 'rm -rf "$work"' EXIT
export OMP_NUM_THREADS=1
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
kv() { sed -n "s/.* $1=\([^ ]*\).*/\1/p"; }
lammps() { # $1 = input, $2 = log, extra args
  local in=$1 log=$2; shift 2
  (cd "$work" && lmp -in "$in" -var nsteps "$STEPS" -var R "$R" -var H "$H" -log "$log" -echo none "$@" >/dev/null)
}
lammps_line() { # summary of a LAMMPS log
  local log=$1 loop natoms nb last
  loop=$(sed -n 's/^Loop time of \([0-9.e+-]*\) .*/\1/p' "$log" | tail -1)
  natoms=$(awk '/^ *Step +Atoms/{getline; print $2; exit}' "$log")
  nb=$(sed -n 's/.*total # of bonds = \([0-9]*\).*/\1/p' "$log" | head -1)
  last=$(awk '/^ *Step +Atoms/{on=1; next} /^Loop time/{on=0} on{l=$0} END{print l}' "$log")
  python3 - "$loop" "$natoms" "$nb" "$STEPS" $last <<'EOF'
import sys
loop, n, nb, steps = float(sys.argv[1]), int(sys.argv[2]), int(sys.argv[3]), int(sys.argv[4])
dsum, dmean = float(sys.argv[10]), float(sys.argv[11])
print(f"lammps pd-impact: N={n} family_sum={nb} steps={steps} loop_s={loop:.3f} "
      f"particle_steps_per_s={n*steps/loop:.4e} bond_updates_per_s={nb*steps/loop:.4e} "
      f"damage_sum={dsum:.1f} damage_mean={dmean:.4f}")
EOF
}
: > "$work/floe.txt"; : > "$work/lmp.txt"
for r in $(seq "$REPS"); do
  fl=$(PD_R=$R PD_H=$H PD_INDENT=force PD_ALPHA=${PD_ALPHA:-0.25} "$bin" "$STEPS" 2>/dev/null)
  echo "$fl"
  echo "$fl" >> "$work/floe.txt"
  lammps "$here/in.lammps" "$work/lmp$r.log"
  ll=$(lammps_line "$work/lmp$r.log")
  echo "$ll"
  echo "$ll" >> "$work/lmp.txt"
done
if [ "${CONTACT:-1}" = 1 ]; then
  echo "floe contact-law indenter (PD_INDENT=contact), one untimed attempt:"
  PD_R=$R PD_H=$H PD_INDENT=contact "$bin" "$STEPS" 2>&1 | grep -E "unstable|^floe" | sed 's/^/  /' || true
fi
if [ "${ALPHA0:-0}" = 1 ]; then
  sed 's/^pair_coeff .*/pair_coeff      * * 1.6863e22 0.0015001 0.0005 0.0/' "$here/in.lammps" > "$work/in.alpha0"
  lammps "$work/in.alpha0" "$work/a0.log"
  echo "LAMMPS with alpha = 0 (constant s0 = s00), untimed: $(lammps_line "$work/a0.log" | sed 's/.*damage_sum/damage_sum/')"
  awk '/^ *Step +Atoms/{on=1; next} /^Loop time/{on=0} on{printf "  step %s damage_sum %s\n", $1, $6}' "$work/a0.log"
  echo "floe with alpha = 0, untimed: $(PD_R=$R PD_H=$H PD_ALPHA=0 "$bin" "$STEPS" 2>/dev/null | sed 's/.*\(damage_sum=[^ ]*\).*\(damage_hist=.*\)/\1 \2/')"
fi
fl_loop=$(kv loop_s < "$work/floe.txt" | median)
lm_loop=$(kv loop_s < "$work/lmp.txt" | median)
python3 - "$fl_loop" "$lm_loop" "$REPS" "$work/floe.txt" "$work/lmp.txt" <<'EOF'
import sys
fl, lm, reps = float(sys.argv[1]), float(sys.argv[2]), sys.argv[3]
def kv(line):
    return dict(t.split("=", 1) for t in line.split() if "=" in t)
f = kv(open(sys.argv[4]).readlines()[-1]); l = kv(open(sys.argv[5]).readlines()[-1])
steps = int(f["steps"]); nf, nl = int(f["N"]), int(l["N"])
bf, bl, pairs = int(f["family_sum"]), int(l["family_sum"]), int(f["pairs"])
fb, lb = bf * steps / fl, bl * steps / lm
print(f"pd-impact medians of {reps} (loop time only), {steps} steps:")
print(f"  points          floe {nf}  LAMMPS {nl}")
print(f"  bonds           floe {pairs} stored pairs, family-size sum {bf}; LAMMPS {bl} (family-size sum)")
print(f"  loop_s          floe {fl:.3f}  LAMMPS {lm:.3f}")
print(f"  particle-steps/s floe {nf*steps/fl:.3e}  LAMMPS {nl*steps/lm:.3e}")
print(f"  bond-updates/s  floe {fb:.3e}  LAMMPS {lb:.3e}  (family-size basis; floe per stored pair {pairs*steps/fl:.3e})")
print(f"  floe/LAMMPS per bond update = {fb/lb:.2f}  (target >= 2)")
print(f"  damage at end   floe sum {float(f['damage_sum']):.1f} mean {float(f['damage_mean']):.4f}; "
      f"LAMMPS sum {float(l['damage_sum']):.1f} mean {float(l['damage_mean']):.4f}; "
      f"floe/LAMMPS {float(f['damage_sum'])/float(l['damage_sum']):.2f}")
print(f"  floe memory     {int(f['bytes'])} B: {float(f['bytes_per_family_bond']):.2f} B per family bond, "
      f"{float(f['bytes_per_pair']):.2f} B per stored pair")
print(f"  floe damage every 100 steps: {f['damage_hist']} (alpha {f['alpha']})")
EOF
echo "  LAMMPS damage every 100 steps: $(awk '/^ *Step +Atoms/{on=1; next} /^Loop time/{on=0} on && $1 > 0 {print $6}' "$work/lmp$REPS.log" | paste -sd, -)"
