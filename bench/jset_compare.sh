#!/bin/sh
# bench/jset_compare.sh: CPU and wall time of the planner's J^1 + J^20
# g-sliced set at 1e-3 (bench/bench_jset) with two builds of libnbt,
# alternating in one script (the machine is shared: CPU time is the
# comparable number), and the two builds' tables compared byte for byte
# (every float value and every recorded bound).
#   bench/jset_compare.sh BASE_LIBDIR [RUNS] [THREADS]
# BASE_LIBDIR holds the baseline's libnbt.so.0, e.g. from
#   git worktree add /tmp/nbt-base COMMIT && cd /tmp/nbt-base && autoreconf -fi &&
#   ./configure -q && make libnbt/libnbt.la      (then /tmp/nbt-base/libnbt/.libs)
# Run from the build tree after `make bench/bench_jset`.
set -e
base=$1
runs=${2:-3}
threads=${3:-1}
[ -n "$base" ] && [ -e "$base/libnbt.so.0" ] || { echo "usage: $0 BASE_LIBDIR [RUNS] [THREADS] (no libnbt.so.0 in '$base')" >&2; exit 2; }
bin=bench/.libs/bench_jset
[ -x "$bin" ] || { echo "$0: $bin not built (make bench/bench_jset)" >&2; exit 2; }
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
i=0
while [ "$i" -lt "$runs" ]; do
    LD_LIBRARY_PATH=$base "$bin" "$threads" 1 "$tmp/base.bin" | sed 's/^/base: /'
    LD_LIBRARY_PATH=libnbt/.libs "$bin" "$threads" 1 "$tmp/new.bin" | sed 's/^/new:  /'
    i=$((i + 1))
done | tee "$tmp/log"
for w in base new; do
    grep "^$w" "$tmp/log" | sed 's/.*cpu \([0-9.]*\) s.*/\1/' | sort -n | awk -v w="$w" '{a[NR]=$1} END {printf "%s: cpu median %.3f s (min %.3f, max %.3f) over %d runs\n", w, a[int((NR+1)/2)], a[1], a[NR], NR}'
done
if cmp -s "$tmp/base.bin" "$tmp/new.bin"; then
    echo "tables: identical to the byte (values and recorded bounds)"
else
    echo "tables: DIFFER"
    exit 1
fi
