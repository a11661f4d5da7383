#!/usr/bin/env bash
# bench/machine: the most a second core can give on this machine, for loops that stream
# memory (the particle loops, the contact stage) as against loops that only compute. One copy
# of bench_headroom, then two at once, at three working-set sizes (in L2, in L3, in memory);
# prints each copy's time and the two copies' speed-up over one (2.00 on two independent
# cores), then the time to move a cache line from one core to the other (bench_pingpong).
# Run it before a threads or MPI sitting: a two-thread target above this ceiling
# cannot be met on this machine, whatever the code does.
#   REPS=3 bench/machine/run.sh
set -euo pipefail
here=$(cd "$(dirname "$0")" && pwd)
root=$(cd "$here/../.." && pwd)
REPS=${REPS:-3}
build=${BUILD:-$root/build-bench}
if [[ ! -x "$build/bench/bench_headroom" || ! -x "$build/bench/bench_pingpong" ]]; then
  cmake -S "$root" -B "$build" -DCMAKE_BUILD_TYPE=Release -DFLOE_BUILD_TESTS=OFF >/dev/null
  cmake --build "$build" -j"$(nproc)" --target bench_headroom bench_pingpong >/dev/null
fi
b=$build/bench/bench_headroom
secs() { sed -n 's/.*seconds=\([0-9.]*\).*/\1/p'; }
median() { sort -g | awk '{a[NR]=$1} END {print (NR%2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}'; }
echo "cpu: $(lscpu | sed -n 's/^Model name: *//p' | head -1), $(nproc) cpus, $(lscpu | sed -n 's/^Thread(s) per core: *//p') thread(s) per core (as the VM reports it)"
for n in 20000 400000 8000000; do
  : > /tmp/headroom1.$$; : > /tmp/headroom2.$$
  for r in $(seq "$REPS"); do
    "$b" "$n" | secs >> /tmp/headroom1.$$
    # two copies at once: the slower one's time is the pair's
    t2=$( ( "$b" "$n" & "$b" "$n"; wait ) | secs | sort -g | tail -1)
    echo "$t2" >> /tmp/headroom2.$$
  done
  t1=$(median < /tmp/headroom1.$$); t2=$(median < /tmp/headroom2.$$)
  python3 -c "print(f'headroom: {16*$n/1024:>8.0f} KiB per copy: one copy {$t1:.3f} s, two at once {$t2:.3f} s each: two cores give {2*$t1/$t2:.2f}x one (medians of $REPS)')"
  rm -f /tmp/headroom1.$$ /tmp/headroom2.$$
done
# a cache line moved between the two cores (medians of REPS): the price of each line that a
# two-thread run shares between its threads
: > /tmp/pingpong.$$
for r in $(seq "$REPS"); do "$build/bench/bench_pingpong" | sed -n 's/.*ns_per_handover=\([0-9.]*\).*/\1/p' >> /tmp/pingpong.$$; done
echo "pingpong: a cache line from one core to the other: $(median < /tmp/pingpong.$$) ns per hand-over (median of $REPS)"
rm -f /tmp/pingpong.$$
