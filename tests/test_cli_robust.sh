#!/bin/sh
# tests/test_cli_robust.sh: what a new user ran into (issue 20): scene files
# with repeated keys or CR LF line ends, signals during a multi-file write,
# g-sliced tables that miss their tolerance, extrapolated kernel values,
# nbt-demo's options and output, --threads 0.
. "${top_srcdir:-.}/tests/testlib.sh"
NBT_GEN=$(abspath "${NBT_GEN:-./nbt-gen}")

# ---- scene files: a key given twice is refused (file:line, both lines), nothing written
printf 'kappa_t = 0.5\ndistance = 8\nphase = iso\n# a comment\ndistance = 9\n' >"$tmp/dup.scene"
expect_usage "scene: duplicate key" "dup.scene:5: distance is given twice (first at line 2)" \
  "$NBT_GEN" scene "$tmp/dup.scene" -o "$tmp/dup"
printf 'kappa_t = 0.5\ndistance = 8\nphase = iso\nphong = 20\nphong = 40\n' >"$tmp/dup.scene"
expect_usage "scene: phong twice" "dup.scene:5: phong is given twice (first at line 4)" \
  "$NBT_GEN" scene "$tmp/dup.scene" -o "$tmp/dup"
[ ! -e "$tmp/dup" ] && ok || bad "a refused scene left $tmp/dup"

# ---- scene files with CR LF line ends read as with LF: the same tables and summary
printf 'kappa_t = 0.2:0.5 # 1/m\ndistance = 8\nphase = hg:g=0.3\nairlight = yes\ndiffuse = no\nphong = 20, 40\ntol = 2e-2\nhalf = no\n' \
  >"$tmp/lf.scene"
sed 's/$/\r/' "$tmp/lf.scene" >"$tmp/crlf.scene"
[ "$(tr -cd '\r' <"$tmp/crlf.scene" | wc -c)" -eq 8 ] && ok || bad "the CR LF scene has no CRs"
mkdir "$tmp/lf" "$tmp/crlf"
(cd "$tmp/lf" && "$NBT_GEN" scene ../lf.scene -o t --quiet >out 2>err); rc1=$?
(cd "$tmp/crlf" && "$NBT_GEN" scene ../crlf.scene -o t --quiet >out 2>err); rc2=$?
[ $rc1 -eq 0 ] && [ $rc2 -eq 0 ] && [ -s "$tmp/crlf/t/J40_hg_g_0.3.exr" ] && [ ! -e "$tmp/crlf/t/J1_hg_g_0.3.exr" ] &&
  cmp -s "$tmp/lf/out" "$tmp/crlf/out" && cmp -s "$tmp/lf/t/H_hg_g_0.3.exr" "$tmp/crlf/t/H_hg_g_0.3.exr" && ok ||
  bad "CR LF scene: rc $rc1/$rc2, $(cat "$tmp/crlf/err") $(diff "$tmp/lf/out" "$tmp/crlf/out")"
# ---- --threads 0 means all CPUs (as in nbt-scatter): the same tables as one thread
NBT_FIT=$(abspath "${NBT_FIT:-./nbt-fit}")
"$NBT_GEN" airlight --phase hg:g=0.4 --size 17x9 --threads 0 --no-preview --quiet -o "$tmp/t0.exr" >"$tmp/t0.out" 2>&1 &&
  "$NBT_GEN" airlight --phase hg:g=0.4 --size 17x9 --threads 1 --no-preview --quiet -o "$tmp/t1.exr" >/dev/null 2>&1 &&
  cmp -s "$tmp/t0.exr" "$tmp/t1.exr" && ok || bad "airlight --threads 0: $(cat "$tmp/t0.out")"
"$NBT_GEN" scene "$tmp/lf.scene" -o "$tmp/sc0" --threads 0 --quiet >/dev/null 2>"$tmp/err" &&
  cmp -s "$tmp/sc0/H_hg_g_0.3.exr" "$tmp/lf/t/H_hg_g_0.3.exr" && ok || bad "scene --threads 0: $(cat "$tmp/err")"
expect_usage "--threads 65" "--threads.*65" "$NBT_GEN" airlight --phase iso --threads 65 -o "$tmp/t65.exr"
# nbt-fit mc: results are identical for any --threads, 0 included
"$NBT_FIT" mc --albedo 0.9 --sigma-t 1 --phase hg:g=0.7 --photons 20000 --slab 1.5 --seed 3 --threads 0 >"$tmp/m0" 2>"$tmp/err" &&
  "$NBT_FIT" mc --albedo 0.9 --sigma-t 1 --phase hg:g=0.7 --photons 20000 --slab 1.5 --seed 3 --threads 1 >"$tmp/m1" 2>/dev/null &&
  [ -s "$tmp/m0" ] && cmp -s "$tmp/m0" "$tmp/m1" && ok || bad "mc --threads 0: $(cat "$tmp/err")"

# ---- nbt-demo: options are checked, the output before the work (when built with GL)
if [ -n "${NBT_DEMO:-}" ] && [ -x "$NBT_DEMO" ]; then
  NBT_DEMO=$(abspath "$NBT_DEMO")
  mkdir "$tmp/demo" "$tmp/dir.png"
  (cd "$tmp/demo" && "$NBT_DEMO" --foo >../out 2>../err); rc=$?
  [ $rc -eq 2 ] && [ "$(wc -l <"$tmp/err")" -eq 1 ] && grep -q "unknown option '--foo'" "$tmp/err" &&
    [ -z "$(ls -A "$tmp/demo")" ] && ok || bad "nbt-demo --foo: rc=$rc, $(cat "$tmp/err"), wrote: $(ls -A "$tmp/demo")"
  expect_usage "nbt-demo --width without a value" "--width (missing)" "$NBT_DEMO" --width
  expect_usage "nbt-demo --width 12x" "--width 12x is not accepted: an integer 16..4096" "$NBT_DEMO" --width 12x
  expect_usage "nbt-demo two outputs" "one output only" "$NBT_DEMO" "$tmp/demo/a.png" "$tmp/demo/b.png"
  expect_usage "nbt-demo output not .png" "must be a file name ending in .png" "$NBT_DEMO" "$tmp/demo/a.exr"
  # one line, exit 1 and no rendering report: refused before the tables and drawing
  expect_fail "nbt-demo unwritable output" "cannot write '$tmp/missing/x.png': No such file" "$NBT_DEMO" "$tmp/missing/x.png"
  expect_fail "nbt-demo output a directory" "cannot write '$tmp/dir.png': Is a directory" "$NBT_DEMO" "$tmp/dir.png"
  [ -z "$(ls -A "$tmp/demo")" ] && ok || bad "refused nbt-demo runs left $(ls -A "$tmp/demo")"
  # a real run: the picture (6 panels of 16x12 by 2 rows) and nothing else
  PNGCHECK=$(abspath "${NBT_PNGCHECK:-./tests/pngcheck}")
  # Mesa's driver leaks at eglTerminate: no leak report for this GL run in sanitizer builds
  ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0 "$NBT_DEMO" "$tmp/demo/d.png" --width 16 2>"$tmp/err" && [ "$("$PNGCHECK" "$tmp/demo/d.png")" = "96 24" ] &&
    [ "$(ls -A "$tmp/demo")" = "d.png" ] && ok || bad "nbt-demo --width 16: $(cat "$tmp/err"), $(ls -A "$tmp/demo")"
fi

# ---- a signal during a multi-file write removes the run's files: the
# temporaries (PATH.tmpPID) and the finished files of the set and of the
# sets before it, and the directory the run created; the exit is by the signal.
# The moment is fixed by a FIFO in place of one temporary: the writer's open
# blocks on it (no reader), so the run waits there, whatever the machine's speed.
# wait_for COND PID: poll (10 ms, at most 60 s) until the shell test COND holds
wait_for() {
  i=0
  while [ $i -lt 6000 ] && kill -0 "$2" 2>/dev/null; do
    if eval "$1"; then return 0; fi
    sleep 0.01; i=$((i + 1))
  done
  return 1
}
# (1) set 1 (H) written, set 2 (J^20) blocked on its first file. The run creates
# the directory, so the FIFO goes in as soon as it appears (set 1's build, its
# writing and set 2's build, ~1 s, are the margin).
printf 'kappa_t = 0.5\ndistance = 20\ng = 0:0.5\nbasis = legendre\ndiffuse = no\nphong = 20\ntol = 1e-3\n' >"$tmp/sig.scene"
"$NBT_GEN" scene "$tmp/sig.scene" -o "$tmp/sig" >"$tmp/sig.out" 2>"$tmp/sig.err" &
pid=$!
if wait_for '[ -d "$tmp/sig" ]' $pid && mkfifo "$tmp/sig/J20_k0-3.exr.tmp$pid" &&
  wait_for '[ -s "$tmp/sig/H_k0-3.png" ] && [ "$(grep -c "writing 8 file" "$tmp/sig.err")" -eq 2 ] && [ -s "$tmp/sig/J20_k4-7.png" ]' $pid; then
  kill -TERM $pid; wait $pid; rc=$?
  [ $rc -eq 143 ] && [ ! -e "$tmp/sig" ] && grep -q "interrupted: the files of this run were removed" "$tmp/sig.err" && ok ||
    bad "SIGTERM between sets: rc=$rc, left: $(ls "$tmp/sig" 2>&1 | tr '\n' ' ')"
else
  kill -TERM $pid 2>/dev/null; wait $pid; bad "SIGTERM between sets: the FIFO came too late: $(cat "$tmp/sig.err")"
fi
# (2) a 16-file set: the fifth file's temporary is a FIFO made before nbt-gen
# starts (exec keeps the shell's PID); the other writers (one per CPU) finish the
# other 15 (with one CPU: the four before it), then the signal. The directory
# existed before, so it stays (empty).
mkdir "$tmp/sigw"
[ "$(getconf _NPROCESSORS_ONLN)" -ge 2 ] && nexr=15 npng=16 || nexr=4 npng=4
sh -c 'mkfifo "$1/h_k16-19.exr.tmp$$" && shift && exec "$@"' sh "$tmp/sigw" \
  "$NBT_GEN" airlight --kmax 63 --size 385x385 --max 4 -o "$tmp/sigw/h.exr" >"$tmp/sig.out" 2>"$tmp/sig.err" &
pid=$!
if wait_for '[ "$(ls "$tmp/sigw" | grep -c "[.]exr\$")" -eq $nexr ] && [ "$(ls "$tmp/sigw" | grep -c "[.]png\$")" -eq $npng ]' $pid; then
  seen=$(ls "$tmp/sigw" | wc -l)
  kill -TERM $pid; wait $pid; rc=$?
  [ $rc -eq 143 ] && [ -d "$tmp/sigw" ] && [ -z "$(ls -A "$tmp/sigw")" ] && ok ||
    bad "SIGTERM while writing: rc=$rc, $seen files seen, left: $(ls -A "$tmp/sigw" | tr '\n' ' ')"
else
  kill -TERM $pid 2>/dev/null; wait $pid; bad "SIGTERM while writing: the run did not stop at the FIFO: $(cat "$tmp/sig.err"), $(ls "$tmp/sigw" | tr '\n' ' ')"
fi

# (3) before any file: the message says nothing was written (it said "the files
# of this run were removed" also for a run that had none)
"$NBT_GEN" airlight --kmax 15 --size 4096x4096 -o "$tmp/sigw/big.exr" >"$tmp/sig.out" 2>"$tmp/sig.err" &
pid=$!
if wait_for 'grep -q "building" "$tmp/sig.err"' $pid; then
  kill -TERM $pid; wait $pid; rc=$?
  [ $rc -eq 143 ] && [ "$(tail -n 1 "$tmp/sig.err")" = "nbt-gen: interrupted (no files written yet)" ] &&
    [ -z "$(ls -A "$tmp/sigw")" ] && ok || bad "SIGTERM while building: rc=$rc, $(cat "$tmp/sig.err"), left: $(ls -A "$tmp/sigw")"
else
  kill -TERM $pid 2>/dev/null; wait $pid; bad "SIGTERM while building: no progress line: $(cat "$tmp/sig.err")"
fi

# ---- eval psi --model fitted: no per-point bound, so the error column is nan (it
# was 0); outside the fitted tau range (the default model's is [0.5, 10]) the
# value is called an extrapolation
"$NBT_GEN" eval psi --albedo 0.9 --sigma-t 1.3 --B 0.0685 --z 2.3 --r 0.7 --model fitted >"$tmp/out" 2>"$tmp/err" &&
  [ "$(cut -d' ' -f2 "$tmp/out")" = nan ] && ! grep -q extrapolation "$tmp/err" && ok ||
  bad "fitted psi in range: $(cat "$tmp/out" "$tmp/err")"
"$NBT_GEN" eval psi --albedo 0.9 --sigma-t 1.3 --B 0.0685 --z 30 --r 0.7 --model fitted >"$tmp/out" 2>"$tmp/err" &&
  [ "$(cut -d' ' -f2 "$tmp/out")" = nan ] &&
  grep -q "tau = sigma_t z = 39 is outside the fitted range \[0.5, 10\]: the value is an extrapolation" "$tmp/err" && ok ||
  bad "fitted psi outside the range: $(cat "$tmp/out" "$tmp/err")"

# ---- docs: every nbt-fit command of --help is in the man page's SYNOPSIS; the README
# names both variables Open MPI's mpirun needs as root; shaders.md names every
# sampler macro the modules use
srcdir=${top_srcdir:-.}
syn=$(sed -n '/^\.SH SYNOPSIS/,/^\.SH DESCRIPTION/p' "$srcdir/doc/nbt-fit.1")
for c in mc kernel model phase screenmodel; do
  echo "$syn" | grep -q "^\.B nbt-fit $c" && ok || bad "nbt-fit.1 SYNOPSIS lacks '$c'"
done
grep -q "OMPI_ALLOW_RUN_AS_ROOT=1" "$srcdir/README.md" && grep -q "OMPI_ALLOW_RUN_AS_ROOT_CONFIRM=1" "$srcdir/README.md" &&
  ok || bad "README: mpirun as root"
for m in $(cat "$srcdir"/shaders/*.glsl | grep -o '^NBT_SAMPLER[A-Z0-9]*' | sort -u); do
  grep -q "\`$m\`" "$srcdir/doc/shaders.md" && ok || bad "shaders.md does not name $m"
done

finish
