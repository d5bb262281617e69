#!/bin/sh
# tests/test_mpi.sh: mpirun -np 1, 2, 3 nbt-fit mc writes output identical byte
# for byte to a one-process run with the same seed; bad input under mpirun
# (exit 2, the message, no file). Run only in builds configured --with-mpi.
. "${top_srcdir:-.}/tests/testlib.sh"
NBT_FIT=$(abspath "${NBT_FIT:-./nbt-fit}")
MPIRUN=${NBT_MPIRUN:-mpirun}
# Open MPI refuses root unless told; CI containers run as root
if [ "$(id -u)" -eq 0 ]; then
  OMPI_ALLOW_RUN_AS_ROOT=1; OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1
  export OMPI_ALLOW_RUN_AS_ROOT OMPI_ALLOW_RUN_AS_ROOT_CONFIRM
fi
# 3 ranks on a 2-core machine: oversubscribe; shared memory and self only (no network needed).
# Under ASan, Open MPI's own allocations (MCA plugins, ops) are reported as leaks at exit: leak
# checking is off for the MPI runs only (the one-process runs keep it; nbt's MPI code frees all).
mpi() { n=$1; shift; ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0 timeout 120 "$MPIRUN" --oversubscribe \
  --mca btl self,vader -x ASAN_OPTIONS -np "$n" "$@"; }

M="--albedo 0.9 --sigma-t 1.3 --phase hg:g=0.75 --photons 30011 --z-planes 0.5:3:4 --r-bins 9 --seed 2385 --threads 1"
S="--albedo 0.9 --sigma-t 1 --phase hg:g=0.75 --photons 30011 --slab 2 --seed 2385 --threads 1"
"$NBT_FIT" mc $M -o "$tmp/ref.csv" >"$tmp/ref.m" 2>/dev/null && "$NBT_FIT" mc $M -o "$tmp/ref.exr" >/dev/null 2>&1 &&
  "$NBT_FIT" mc $S >"$tmp/ref.s" 2>/dev/null && ok || bad "one-process reference runs"
for n in 1 2 3; do
  mpi "$n" "$NBT_FIT" mc $M -o "$tmp/p$n.csv" >"$tmp/p$n.m" 2>"$tmp/p$n.err" &&
    cmp -s "$tmp/ref.csv" "$tmp/p$n.csv" && cmp -s "$tmp/ref.m" "$tmp/p$n.m" && ok ||
    bad "$n ranks: planes differ from one process: $(head -c 600 "$tmp/p$n.err")"
  mpi "$n" "$NBT_FIT" mc $S >"$tmp/s$n" 2>"$tmp/s$n.err" && cmp -s "$tmp/ref.s" "$tmp/s$n" && ok ||
    bad "$n ranks: slab R/T differ from one process: $(cat "$tmp/s$n") vs $(cat "$tmp/ref.s")"
  ls "$tmp"/p$n.csv.tmp* >/dev/null 2>&1 && bad "$n ranks: a temporary file was left" || ok
done
grep -q "all ranks" "$tmp/p3.err" && ok || bad "3 ranks: rank 0 reports the whole run: $(cat "$tmp/p3.err")"
[ "$(grep -c "photons in" "$tmp/p3.err")" -eq 1 ] && ok || bad "3 ranks: one report, from rank 0 only"
mpi 2 "$NBT_FIT" mc $M --threads 2 -o "$tmp/e2.exr" >/dev/null 2>&1 && cmp -s "$tmp/ref.exr" "$tmp/e2.exr" && ok ||
  bad "2 ranks: EXR differs from one process"
"$NBT_FIT" mc $M --estimator weighted -o "$tmp/w1.csv" >"$tmp/w1.m" 2>/dev/null &&
  mpi 3 "$NBT_FIT" mc $M --estimator weighted -o "$tmp/w3.csv" >"$tmp/w3.m" 2>/dev/null &&
  cmp -s "$tmp/w1.csv" "$tmp/w3.csv" && cmp -s "$tmp/w1.m" "$tmp/w3.m" && ok || bad "weighted, 3 ranks: differs from one process"
# 4 standard errors of van de Hulst's slab (R 0.09739, T 0.66096) with 3 ranks
awk '$1 == "R" { r = ($2 - 0.09739) / $3 } $1 == "T" { t = ($2 - 0.66096) / $3 }
     END { exit !(r * r < 16 && t * t < 16 && NR == 2) }' "$tmp/s3" && ok || bad "3 ranks: slab R/T: $(cat "$tmp/s3")"

# bad input under mpirun: exit 2 from every rank, one message (rank 0's), no file
mpi 2 "$NBT_FIT" mc --albedo 1.5 --sigma-t 1 --B 0.1 --photons 1000 -o "$tmp/bad.csv" >"$tmp/out" 2>"$tmp/err"; rc=$?
[ $rc -eq 2 ] && [ "$(grep -c "albedo" "$tmp/err")" -eq 1 ] && [ ! -e "$tmp/bad.csv" ] && ok ||
  bad "2 ranks, --albedo 1.5: rc=$rc, $(cat "$tmp/err")"
# rank 0 cannot write: exit 1, nothing written anywhere
mpi 2 "$NBT_FIT" mc $M -o "$tmp/nodir/x.csv" >"$tmp/out" 2>"$tmp/err"; rc=$?
[ $rc -eq 1 ] && [ "$(grep -c "cannot write" "$tmp/err")" -eq 1 ] && [ ! -e "$tmp/nodir" ] && ok ||
  bad "2 ranks, -o into a missing directory: rc=$rc, $(cat "$tmp/err")"
finish
