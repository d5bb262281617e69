#!/bin/sh
# tests/test_fit.sh: nbt-fit mc end to end: output format, slab values,
# identical output for any thread count, bad input (exit 2, one line, no file).
. "${top_srcdir:-.}/tests/testlib.sh"
NBT_FIT=$(abspath "${NBT_FIT:-./nbt-fit}")

"$NBT_FIT" --version >"$tmp/v" && grep -q "nbt-fit (nbt)" "$tmp/v" && ok || bad "--version (exit status 0)"
"$NBT_FIT" mc --help | grep -q "z,r_lo,r_hi,psi,psi_stderr" && ok || bad "mc --help"

# slab: R and T lines, within 4 standard errors of van de Hulst (0.09739, 0.66096)
"$NBT_FIT" mc --albedo 0.9 --sigma-t 1 --phase hg:g=0.75 --photons 400000 --slab 2 >"$tmp/slab" 2>/dev/null
awk '$1 == "R" { r = ($2 - 0.09739) / $3 } $1 == "T" { t = ($2 - 0.66096) / $3 }
     END { exit !(r * r < 16 && t * t < 16 && NR == 2) }' "$tmp/slab" && ok || bad "slab R/T: $(cat "$tmp/slab")"

# the weighted estimator: the same slab within 4 standard errors, and it says so in an EXR
"$NBT_FIT" mc --albedo 0.9 --sigma-t 1 --phase hg:g=0.75 --photons 400000 --slab 2 --estimator weighted >"$tmp/wslab" 2>/dev/null
awk '$1 == "R" { r = ($2 - 0.09739) / $3 } $1 == "T" { t = ($2 - 0.66096) / $3 }
     END { exit !(r * r < 16 && t * t < 16 && NR == 2) }' "$tmp/wslab" && ok || bad "weighted slab R/T: $(cat "$tmp/wslab")"
cmp -s "$tmp/slab" "$tmp/wslab" && bad "--estimator weighted changed nothing" || ok

# --gpu: the GLSL compute counter (llvmpipe in CI): the slab within 4 standard errors, the same
# output twice; refusals exit 2 with one line naming what is missing, and write nothing
G="--albedo 0.9 --sigma-t 1 --phase hg:g=0.75 --photons 300000 --slab 2 --gpu"
# the GL driver leaks at eglTerminate (DESIGN.md): no leak report under ASan for --gpu runs
gl() { ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0 "$@"; }
if gl "$NBT_FIT" mc $G >"$tmp/gslab" 2>"$tmp/gerr"; then
  awk '$1 == "R" { r = ($2 - 0.09739) / $3 } $1 == "T" { t = ($2 - 0.66096) / $3 }
       END { exit !(r * r < 16 && t * t < 16 && NR == 2) }' "$tmp/gslab" && ok || bad "--gpu slab R/T: $(cat "$tmp/gslab")"
  gl "$NBT_FIT" mc $G >"$tmp/gslab2" 2>/dev/null && cmp -s "$tmp/gslab" "$tmp/gslab2" && ok || bad "--gpu: two runs differ"
  expect_usage "--gpu, Rayleigh" "single-Gaussian" gl "$NBT_FIT" mc --albedo 0.9 --sigma-t 1 --phase rayleigh --photons 1000 \
    --z-planes 1:2:2 --gpu -o "$tmp/g.csv"
  [ ! -e "$tmp/g.csv" ] && ok || bad "--gpu refusal left a file"
  # no EGL vendor (as on a machine without Mesa's EGL): the message names the packages
  expect_usage "--gpu without EGL" "libegl-mesa0" gl env __EGL_VENDOR_LIBRARY_FILENAMES=/nonexistent "$NBT_FIT" mc $G
else
  grep -q "built without OpenGL" "$tmp/gerr" && ok || bad "--gpu failed: $(cat "$tmp/gerr")"
  echo "NOTE: nbt-fit was built without GL: --gpu checked only for its refusal"
fi

# planes: CSV format and size; the same for 1 and 2 threads
M="--albedo 0.7 --sigma-t 1.3 --B 0.0685 --photons 20000 --z-planes 1:4:4 --r-bins 7 --seed 11"
"$NBT_FIT" mc $M --threads 1 -o "$tmp/a.csv" >"$tmp/m1" 2>/dev/null &&
  "$NBT_FIT" mc $M --threads 2 -o "$tmp/b.csv" >"$tmp/m2" 2>/dev/null && ok || bad "plane runs"
[ "$(head -1 "$tmp/a.csv")" = "z,r_lo,r_hi,psi,psi_stderr" ] && [ "$(wc -l <"$tmp/a.csv")" -eq 29 ] && ok ||
  bad "CSV header and 4 x 7 rows"
cmp -s "$tmp/a.csv" "$tmp/b.csv" && cmp -s "$tmp/m1" "$tmp/m2" && ok || bad "output differs between 1 and 2 threads"
[ "$(grep -c '^M ' "$tmp/m1")" -eq 4 ] && ok || bad "one moment line per plane"
# progress: photons are counted every 256 as they finish (not only at the end of each of the 64
# batches); NBT_PROGRESS_SECONDS=0 prints every update as a line of its own (stderr is a file here,
# not a terminal): with one thread, 20000 photons give 78 counts of 256 and 64 batch ends: more than
# 64 lines with an ETA, then one 100% line, the last; percent never falling; no carriage returns.
# --quiet: nothing on stderr. Output identical either way.
NBT_PROGRESS_SECONDS=0 "$NBT_FIT" mc $M --threads 1 -o "$tmp/p.csv" >"$tmp/mp" 2>"$tmp/perr" && ok || bad "mc with progress"
[ "$(grep -c '^nbt-fit: mc: .*% done, .* elapsed, ETA ' "$tmp/perr")" -gt 64 ] &&
  [ "$(grep -c '^nbt-fit: mc: 100% done' "$tmp/perr")" -eq 1 ] && grep '% done' "$tmp/perr" | tail -1 | grep -q '100% done' &&
  ok || bad "mc progress: ETA lines within batches, one 100% at the end: $(cat "$tmp/perr")"
sed -n 's/^nbt-fit: mc: *\([0-9.e-]*\)% done.*/\1/p' "$tmp/perr" | awk 'NR > 1 && $1 + 0 < p { exit 1 } { p = $1 + 0 } END { exit NR < 65 }' &&
  ok || bad "mc progress: percent not rising"
# two threads: the same, whichever thread ends last (the calling thread reports while it waits)
NBT_PROGRESS_SECONDS=0 "$NBT_FIT" mc $M --threads 2 -o "$tmp/p2.csv" >/dev/null 2>"$tmp/p2err" &&
  [ "$(grep -c '^nbt-fit: mc: 100% done' "$tmp/p2err")" -eq 1 ] && grep '% done' "$tmp/p2err" | tail -1 | grep -q '100% done' &&
  cmp -s "$tmp/p2.csv" "$tmp/a.csv" && ok || bad "mc progress, 2 threads: $(cat "$tmp/p2err")"
# a run of 10^12 photons (one batch alone is 1.6e10 photons, hours): progress and the long-run warning
# arrive while the first batches run (at ~2 s and ~0.5 s; waited for up to 60 s, not timed); SIGTERM
# then ends it with no output file and no temporary left behind
mkdir "$tmp/big"
"$NBT_FIT" mc --albedo 0.9 --sigma-t 1 --B 0.0685 --photons 1e12 --threads 2 -o "$tmp/big/psi.exr" >/dev/null 2>"$tmp/bigerr" &
pid=$!
i=0
while [ $i -lt 300 ] && ! grep -q '% done, .* elapsed, ETA ' "$tmp/bigerr"; do sleep 0.2; i=$((i + 1)); done
kill -TERM $pid; wait $pid; rc=$?
grep -q '^nbt-fit: mc: warning: this run will take about .* h .* (projected from .*% done in ' "$tmp/bigerr" &&
  grep -q '^nbt-fit: mc: [0-9.e-]*% done, .* elapsed, ETA [0-9]* h ' "$tmp/bigerr" && [ $rc -eq 143 ] && ok ||
  bad "mc 1e12 photons: a progress line and the warning within a batch (rc $rc): $(cat "$tmp/bigerr")"
[ -z "$(ls -A "$tmp/big")" ] && ok || bad "mc killed by SIGTERM left files: $(ls -A "$tmp/big")"
rmdir "$tmp/big"
tr -d '\n' <"$tmp/perr" | grep -q "$(printf '\r')" && bad "mc progress: carriage return off a terminal" || ok
# no warning at the default 60 s; exactly one (before any progress line) when the limit is tiny
grep -q "warning" "$tmp/perr" && bad "mc: a long-run warning for a short run" || ok
NBT_PROGRESS_WARN_SECONDS=1e-9 "$NBT_FIT" mc $M --threads 1 -o "$tmp/w.csv" >/dev/null 2>"$tmp/werr"
[ "$(grep -c '^nbt-fit: mc: warning: this run will take about .* (projected from ' "$tmp/werr")" -eq 1 ] &&
  head -1 "$tmp/werr" | grep -q warning && ok || bad "mc long-run warning: $(cat "$tmp/werr")"
"$NBT_FIT" mc $M --threads 1 --quiet -o "$tmp/q.csv" >"$tmp/mq" 2>"$tmp/qerr" && [ ! -s "$tmp/qerr" ] && ok ||
  bad "mc --quiet: stderr $(cat "$tmp/qerr")"
cmp -s "$tmp/p.csv" "$tmp/a.csv" && cmp -s "$tmp/q.csv" "$tmp/a.csv" && cmp -s "$tmp/mp" "$tmp/m1" && cmp -s "$tmp/mq" "$tmp/m1" &&
  ok || bad "mc output differs with progress or --quiet"
# Psi is per unit area: sum psi * annulus area over bins <= M0 of the plane (bins cover r < z only)
awk -F, 'NR > 1 && $1 == 2 { s += $4 * 3.141592653589793 * ($3 * $3 - $2 * $2) } END { print s }' "$tmp/a.csv" >"$tmp/s"
m0=$(awk '$2 == 2 { print $3 }' "$tmp/m1")
awk -v s="$(cat "$tmp/s")" -v m="$m0" 'BEGIN { exit !(s > 0.5 * m && s <= m * (1 + 1e-12)) }' && ok ||
  bad "binned Psi integrates to at most M0 ($(cat "$tmp/s") vs $m0)"
# EXR: a PSI table holding the same numbers (as float) as the CSV
"$NBT_FIT" mc $M -o "$tmp/a.exr" >/dev/null 2>&1 && ok || bad "EXR output"
NBT_GEN=${NBT_GEN:-$(dirname "$NBT_FIT")/nbt-gen}
"$NBT_GEN" info "$tmp/a.exr" --at 0.5,3 >"$tmp/info" 2>&1 && grep -q "kind        PSI" "$tmp/info" && ok || bad "info on a PSI table: $(cat "$tmp/info")"
# bin 3 of 7 has its centre at r/z = 0.5; plane z = 3
want=$(awk -F, '$1 == 3 && $2 < 1.5 && $3 > 1.5 { printf "%.9g", $4 }' "$tmp/a.csv")
got=$(sed -n 's/^at .*: \([^ ]*\) .*/\1/p' "$tmp/info")
close "$got" "$want" 1e-6 "EXR node = CSV bin"
# layered: a density file
printf '# a vacuum gap\n0 1\n1 0\n2 1\n' >"$tmp/d.txt"
"$NBT_FIT" mc $M --density "$tmp/d.txt" -o "$tmp/d.csv" >/dev/null 2>&1 && [ -s "$tmp/d.csv" ] && ok || bad "--density run"
# --infinite: the medium also fills z < 0; same seed, so every plane's M0 and M2 is >= the half-space's
"$NBT_FIT" mc $M --infinite -o "$tmp/inf.csv" >"$tmp/minf" 2>/dev/null && [ -s "$tmp/inf.csv" ] && ok || bad "--infinite run"
paste "$tmp/m1" "$tmp/minf" | awk '{ if ($9 < $3 || $11 < $5) bad = 1; s += $9 - $3 } END { exit bad || !(s > 0) }' && ok ||
  bad "--infinite gives at least the half-space's light at every plane: $(paste "$tmp/m1" "$tmp/minf")"
"$NBT_FIT" mc $M --infinite --order-max 1 -o "$tmp/i1.csv" >"$tmp/mi1" 2>/dev/null &&
  "$NBT_FIT" mc $M --order-max 1 -o "$tmp/h1.csv" >"$tmp/mh1" 2>/dev/null && cmp -s "$tmp/i1.csv" "$tmp/h1.csv" &&
  cmp -s "$tmp/mi1" "$tmp/mh1" && ok || bad "--order-max 1: single scattering identical in both geometries"
"$NBT_FIT" mc $M --infinite -o "$tmp/inf.exr" >/dev/null 2>&1 && "$NBT_GEN" info "$tmp/inf.exr" 2>&1 | grep -q "infinite" && ok ||
  bad "an infinite run says so in its EXR metadata"

# ---- fits (Ceres) ----
if ! "$NBT_FIT" kernel --help >/dev/null 2>"$tmp/err"; then
  # a build without Ceres must say so clearly; CI configures --with-ceres, so this is not CI's path
  grep -q "needs Ceres" "$tmp/err" && ok || bad "kernel without Ceres: $(cat "$tmp/err")"
  echo "NOTE: nbt-fit was built without Ceres: kernel and phase fits checked only for their refusal"
else
  # phase: known lobes come back
  "$NBT_FIT" phase --target gauss:B=0.05 --terms 1 >"$tmp/p1" 2>&1 || bad "phase K=1"
  fwords w:4 "$tmp/p1"; set -- $w
  close "$2" 1 1e-9 "one lobe: w = 1"; close "$4" 0.05 1e-6 "one lobe: B = 0.05"
  printf '# two lobes\n0.3 0.01\n0.7 0.2\n' >"$tmp/two.sog"
  "$NBT_FIT" phase --target "sog:$tmp/two.sog" --terms 2 -o "$tmp/fit.sog" >"$tmp/p2" 2>&1 || bad "phase K=2"
  sort -g -k2 "$tmp/fit.sog" | grep -v '^#' >"$tmp/fit.sorted"
  head -1 "$tmp/fit.sorted" >"$tmp/l1"; fwords 2 "$tmp/l1"; set -- $w; close "$1" 0.3 1e-5 "two lobes: w1"; close "$2" 0.01 1e-5 "two lobes: B1"
  tail -1 "$tmp/fit.sorted" >"$tmp/l2"; fwords 2 "$tmp/l2"; set -- $w; close "$1" 0.7 1e-5 "two lobes: w2"; close "$2" 0.2 1e-5 "two lobes: B2"
  "$NBT_FIT" phase --target hg:g=0.8 --terms 4 -o "$tmp/hg.sog" >"$tmp/p3" 2>&1
  awk '/^K / { if (n++ && $4 > prev * (1 + 1e-9)) bad = 1; prev = $4 } END { exit bad || n != 4 || prev > 0.01 }' "$tmp/p3" && ok ||
    bad "HG 0.8: errors fall with K to < 1%: $(cat "$tmp/p3")"
  "${NBT_GEN:-$(dirname "$NBT_FIT")/nbt-gen}" eval H --phase "sog:$tmp/hg.sog" --u 1 --v 0.5 >/dev/null && ok || bad "sog:FILE accepted"
  expect_usage "phase without target" "--target" "$NBT_FIT" phase --terms 2
  expect_usage "phase terms 0" "--terms" "$NBT_FIT" phase --target iso --terms 0
  expect_usage "phase bad target" "mie" "$NBT_FIT" phase --target mie --terms 2

  # kernel: photon counts at dtheta = 30 deg, albedo 0.7
  K="--albedo 0.7 --sigma-t 1 --B 0.0685 --photons 300000 --z-planes 1:6:4 --r-bins 12"
  "$NBT_FIT" mc $K --seed 21 -o "$tmp/k1.csv" >/dev/null 2>&1 && "$NBT_FIT" mc $K --seed 22 -o "$tmp/k2.exr" >/dev/null 2>&1 || bad "mc for kernel"
  "$NBT_FIT" kernel "$tmp/k1.csv" --albedo 0.7 --sigma-t 1 --B 0.0685 -o "$tmp/kfit.csv" 2>"$tmp/krms" && ok || bad "kernel fit: $(cat "$tmp/krms")"
  [ "$(head -1 "$tmp/kfit.csv")" = "z,alpha,beta,alpha_stderr,beta_stderr,rms_before,rms_after,chi2_dof,status" ] &&
    [ "$(wc -l <"$tmp/kfit.csv")" -eq 5 ] && ok || bad "kernel CSV: header and one row per plane"
  fwords RMS:13 "$tmp/krms"; set -- $w
  [ "$3 $5" = "moment fitted" ] && awk -v a="$6" -v b="$4" 'BEGIN { exit !(a < b) }' && ok || bad "the fitted kernel beats the moment kernel: $(cat "$tmp/krms")"
  # rms_after is the relative RMS of 2 pi r Psi (doc/fit.md) of the fitted Psi = alpha/r G(r/beta) against
  # the counts, plane by plane: recomputed here with G(x) = erfc(x/sqrt 2)/2 from A&S 7.1.26 (|error|
  # < 1.5e-7) and each annulus mean by Simpson's rule (64 panels in r/beta), within 1e-4 of itself
  # (the CSV prints 6 digits)
  awk -v fit="$tmp/kfit.csv" '
  function G(x,   y, t) { y = x / sqrt(2); t = 1 / (1 + 0.3275911 * y)
    return 0.5 * t * (0.254829592 + t * (-0.284496736 + t * (1.421413741 + t * (-1.453152027 + t * 1.061405429)))) * exp(-y * y) }
  function mean(a, b, lo, hi,   xl, xh, h, s, i) { xl = lo / b; xh = hi / b; h = (xh - xl) / 64; s = G(xl) + G(xh)
    for (i = 1; i < 64; i++) s += (i % 2 ? 4 : 2) * G(xl + i * h)
    return 2 * 3.14159265358979 * a * b * s * h / 3 / (3.14159265358979 * (hi * hi - lo * lo)) }
  BEGIN { FS = "," }
  FNR == 1 { next }
  FILENAME == fit { n++; A[$1 + 0] = $2; B[$1 + 0] = $3; R[$1 + 0] = $7; next }
  { z = $1 + 0; w = 3.14159265358979 * ($2 + $3); m = mean(A[z], B[z], $2, $3); num[z] += w * w * (m - $4) ^ 2; den[z] += w * w * $4 * $4 }
  END { for (z in R) { r = sqrt(num[z] / den[z]); d = r - R[z]; if (d * d > (1e-4 * R[z]) ^ 2) bad = 1 }; exit bad || n != 4 }' "$tmp/kfit.csv" "$tmp/k1.csv" && ok || bad "kernel CSV: rms_after recomputed from alpha, beta and the counts"
  # --weight rms: the standard errors are the sandwich of doc/fit.md with the RMS metric's fixed weights
  # w_k = 2 pi r_c (their scale cancels): Cov = H^-1 [sum w^4 se_k^2 g g^T] H^-1, H = sum w^2 g g^T, g = dm_k/d(alpha,
  # beta). Recomputed here from the counts and the fitted alpha, beta by another route: m_k by Simpson (64 panels)
  # over the annulus, dm/dbeta by a central difference (step 1e-5 beta: ~1e-10 relative), erfc from its series
  # and continued fraction; measured agreement 1e-10, so 1e-6. (A bin weighted as lo + the next bin's hi: 12-24% off.)
  "$NBT_FIT" kernel "$tmp/k1.csv" --albedo 0.7 --sigma-t 1 --B 0.0685 --weight rms -o "$tmp/krw.csv" 2>"$tmp/krw.err" ||
    bad "kernel --weight rms: $(cat "$tmp/krw.err")"
  awk -v fit="$tmp/krw.csv" '
  function erfc(y,   t, s, K, n) { # the series of erf below 2, the continued fraction of erfc above
    if (y < 2) { t = y; s = y; for (n = 1; n < 60; n++) { t *= -y * y / n; s += t / (2 * n + 1) }; return 1 - 2 / sqrt(3.141592653589793) * s }
    K = y; for (n = 80; n >= 1; n--) K = y + (n / 2) / K; return exp(-y * y) / (sqrt(3.141592653589793) * K) }
  function G(x) { return 0.5 * erfc(x / sqrt(2)) }
  function m(a, b, lo, hi,   h, s, i) { h = (hi - lo) / 64; s = G(lo / b) + G(hi / b)
    for (i = 1; i < 64; i++) s += (i % 2 ? 4 : 2) * G((lo + i * h) / b)
    return 2 * a * s * h / 3 / (hi * hi - lo * lo) }
  BEGIN { FS = "," }
  FNR == 1 { next }
  FILENAME == fit { if ($NF == "ok" || $NF == "misfit") { A[$1 + 0] = $2; B[$1 + 0] = $3; SA[$1 + 0] = $4; SB[$1 + 0] = $5; n++ }; next }
  ($1 + 0) in A { z = $1 + 0; a = A[z]; b = B[z]; if (!($5 > 0)) bad = 1
    w = 3.14159265358979 * ($2 + $3); ga = m(a, b, $2, $3) / a; db = 1e-5 * b
    gb = (m(a, b + db, $2, $3) - m(a, b - db, $2, $3)) / (2 * db)
    h11[z] += w * w * ga * ga; h12[z] += w * w * ga * gb; h22[z] += w * w * gb * gb
    v = w ^ 4 * $5 * $5; b11[z] += v * ga * ga; b12[z] += v * ga * gb; b22[z] += v * gb * gb }
  END { for (z in A) { d = h11[z] * h22[z] - h12[z] * h12[z]; i11 = h22[z] / d; i12 = -h12[z] / d; i22 = h11[z] / d
      c11 = i11 * (b11[z] * i11 + b12[z] * i12) + i12 * (b12[z] * i11 + b22[z] * i12)
      c22 = i12 * (b11[z] * i12 + b12[z] * i22) + i22 * (b12[z] * i12 + b22[z] * i22)
      ea = sqrt(c11) / SA[z] - 1; eb = sqrt(c22) / SB[z] - 1
      printf "z %g: alpha_stderr %.9g (sandwich %.9g), beta_stderr %.9g (%.9g)\n", z, SA[z], sqrt(c11), SB[z], sqrt(c22)
      if (!(ea * ea <= 1e-12 && eb * eb <= 1e-12)) bad = 1 }
    exit bad || n != 4 }' "$tmp/krw.csv" "$tmp/k1.csv" >"$tmp/krw.chk" && ok ||
    bad "kernel --weight rms: standard errors = the sandwich with weights 2 pi r: $(cat "$tmp/krw.chk" "$tmp/krw.csv")"
  "$NBT_FIT" kernel "$tmp/k2.exr" --shape erfc+gauss -o "$tmp/kg.csv" 2>"$tmp/kgrms" && ok || bad "erfc+gauss on EXR input (medium from metadata): $(cat "$tmp/kgrms")"
  fwords RMS:13 "$tmp/kgrms"; set -- $w
  [ "$3 $5" = "moment fitted" ] && awk -v a="$6" -v b="$4" 'BEGIN { exit !(a < 0.5 * b && a < 0.06) }' && ok || bad "erfc+gauss within 6%: $(cat "$tmp/kgrms")"
  # and on every plane, not just on average: the Gaussian part carries light at each depth (M > 0, no bound),
  # and each plane's RMS is within the same 6% (measured 0.014 to 0.046; erfc alone leaves 0.04 to 0.29)
  awk -F, 'NR == 1 { for (i = 1; i <= NF; i++) c[$i] = i; next } { n++; if (!($c["M"] > 0 && $c["rms_after"] < 0.06 && $c["status"] != "bound")) bad = 1 }
    END { exit bad || n != 4 }' "$tmp/kg.csv" && ok || bad "erfc+gauss: M > 0 and RMS < 6% on each of the 4 planes: $(cat "$tmp/kg.csv")"
  # the smooth correction, fitted on two runs, judged on a third it has not seen
  "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.0685 --photons 300000 --z-planes 1:6:4 --r-bins 12 --seed 23 -o "$tmp/k3.exr" >/dev/null 2>&1
  "$NBT_FIT" mc --albedo 0.9 --sigma-t 1 --B 0.0685 --photons 300000 --z-planes 1:6:4 --r-bins 12 --seed 24 -o "$tmp/k4.exr" >/dev/null 2>&1
  "$NBT_FIT" kernel "$tmp/k3.exr" "$tmp/k4.exr" --correction "$tmp/corr.txt" -o "$tmp/kc.csv" 2>"$tmp/kcerr" && [ -s "$tmp/corr.txt" ] && ok || bad "--correction"
  # a correction file that cannot be written once the fit is done (the start's check passed): exit status 1
  # (nbt-fit.1), one message naming it, nothing left. A file size limit of 0 (ulimit -f, SIGXFSZ ignored) makes
  # the write fail with EFBIG; stdout and stderr go to a pipe, which the limit does not touch
  out=$(sh -c 'trap "" XFSZ; ulimit -f 0 || exit 99; "$@" 2>&1 >/dev/null; echo "exit $?"' sh \
    "$NBT_FIT" kernel "$tmp/k3.exr" "$tmp/k4.exr" --correction "$tmp/cfull.txt")
  # lowering a soft limit is always allowed, so a refusal is a broken shell, not a reason to skip
  if [ "$out" = "exit 99" ]; then bad "ulimit -f 0 refused: the late --correction write failure cannot be checked"
  else
    [ "$(echo "$out" | tail -n 1)" = "exit 1" ] && echo "$out" | grep -q "^nbt-fit: cannot write '$tmp/cfull.txt': " &&
      [ -z "$(ls "$tmp" | grep cfull)" ] && ok || bad "--correction write failing after the start: $out"
  fi
  # --apply on the fit's own two runs prints the fit's RMS lines: each run's name with its numbers
  "$NBT_FIT" kernel "$tmp/k3.exr" "$tmp/k4.exr" --apply "$tmp/corr.txt" 2>/dev/null | grep '^RMS' >"$tmp/app2" &&
    [ "$(wc -l <"$tmp/app2")" -eq 2 ] && grep '^RMS .* corrected ' "$tmp/kcerr" | cmp -s - "$tmp/app2" && ok ||
    bad "--apply = the --correction fit's RMS lines: $(cat "$tmp/app2" "$tmp/kcerr")"
  "$NBT_FIT" kernel "$tmp/k2.exr" --apply "$tmp/corr.txt" >"$tmp/app" 2>&1 || bad "--apply on k2.exr: $(cat "$tmp/app")"
  fwords RMS:6 "$tmp/app"; set -- $w
  [ "$3 $5" = "moment corrected" ] && awk -v a="$6" -v b="$4" 'BEGIN { exit !(a < b) }' && ok || bad "the correction helps on a held-out run: $(cat "$tmp/app")"
  # phase --against: the widths' common factor that makes the moment kernel match the counts
  "$NBT_FIT" phase --target gauss:B=0.0685 --terms 1 --against "$tmp/k2.exr" -o "$tmp/ag.sog" >"$tmp/ag" 2>&1 || bad "--against: $(cat "$tmp/ag")"
  fwords against:16 "$tmp/ag"; set -- $w
  [ "$4 $9 ${12}" = "RMS lobes, widths" ] && awk -v b="$5" -v a="${10}" 'BEGIN { exit !(a <= b && a > 0) }' && [ -s "$tmp/ag.sog" ] && ok ||
    bad "--against improves the moment kernel: $(cat "$tmp/ag")"
  # its starting RMS is the moment kernel of the fitted lobe (gauss:B=0.0685 fits itself with one lobe, L2
  # error ~1e-12) against k2.exr: the number nbt-fit kernel prints as the moment kernel's RMS on the same
  # counts (a different command path, medium from the EXR); both print 4 digits. The factor must move it.
  awk -v k="$(awk '/^RMS/ { print $4 }' "$tmp/kgrms")" '/^against/ { b = $5; a = $10; f = $14 }
    END { exit !(k != "" && b == k && a + 0 < b + 0 && f != 1) }' "$tmp/ag" && ok ||
    bad "--against starts from the moment kernel's RMS of nbt-fit kernel ($(cat "$tmp/kgrms")): $(cat "$tmp/ag")"
  # its status: one moment-kernel lobe misses these counts by RMS ~0.1 while 3e5 photons leave ~1% noise
  # per bin, so chi^2/dof ~ (0.1 / 0.01)^2 ~ 100, far above the 0.001 limit (~1.8 at 47 dof): misfit
  grep -q '^against .* status misfit$' "$tmp/ag" &&
    awk '/chi\^2\/dof = / { for (i = 1; i < NF; i++) if ($i == "=" && $(i - 1) == "chi^2/dof") v = $(i + 1) + 0 } END { exit !(v > 20) }' "$tmp/ag" && ok ||
    bad "--against judges the moment kernel a misfit at chi^2/dof > 20: $(cat "$tmp/ag")"
  expect_usage "--against a CSV without medium" "does not name its medium" "$NBT_FIT" phase --target iso --terms 1 --against "$tmp/k1.csv"
  # an EXR whose header (nbt.phase "mc albedo=A sigma_t=S ...", plain text) names only one of the two:
  # the same bytes with one key renamed (same length, so the file stays valid) are refused too
  LC_ALL=C sed 's/ sigma_t=/ sigma_x=/' "$tmp/k2.exr" >"$tmp/k2-nos.exr"
  LC_ALL=C sed 's/ albedo=/ albedx=/' "$tmp/k2.exr" >"$tmp/k2-noa.exr"
  expect_usage "--against an EXR without sigma_t" "k2-nos.exr does not name its medium" "$NBT_FIT" phase --target iso --terms 1 --against "$tmp/k2-nos.exr"
  expect_usage "--against an EXR without albedo" "k2-noa.exr does not name its medium" "$NBT_FIT" phase --target iso --terms 1 --against "$tmp/k2-noa.exr"
  # three coefficients per parameter over 2 x 4 planes of 3e5 photons: the smooth correction misses the counts' noise
  grep -q '^# fit status: misfit: chi^2/dof = .* is above ' "$tmp/corr.txt" && ok || bad "the correction file records its fit status: $(grep status "$tmp/corr.txt")"

  # ---- honest fits: every fit judged (doc/fit.md) ----
  # check_rows CSV ERR WIDTHCOLS AMPCOLS SECOLS: one row per plane (10: a header alone passed before); every row
  # 'ok' or 'misfit' has finite standard errors, an
  # RMS no worse than the moment kernel's, no width on its bound (100 x the plane's largest radius, = 100 z
  # here) and no amplitude at 0; 'ok' rows a chi2_dof below 3.2 (the limit at the largest dof here, 48, is
  # 1.83; at 10, 3.12) and 'misfit' rows one above 1.8; every other row has nan standard errors; every row
  # but 'ok' has one stderr line "plane z = Z: STATUS: why"; as many such lines as such rows
  check_rows() {
    awk -F, -v w="$3" -v a="$4" -v e="$5" 'NR > 1 {
        nw = split(w, W, " "); na = split(a, A, " "); ne = split(e, E, " ")
        if ($NF == "ok" || $NF == "misfit") {
          for (i = 1; i <= ne; i++) if (($E[i] "") == "nan" || ($E[i] "") ~ /inf/ || $E[i] + 0 <= 0) { print $NF " row with stderr " $E[i] ": " $0; bad = 1 }
          if ($(NF - 2) + 0 > $(NF - 3) + 0) { print $NF " row worse than the moment kernel: " $0; bad = 1 }
          for (i = 1; i <= nw; i++) if ($W[i] + 0 >= 100 * $1 * (1 - 1e-6)) { print $NF " row on the width bound: " $0; bad = 1 }
          for (i = 1; i <= na; i++) if ($A[i] + 0 == 0) { print $NF " row with a zero amplitude: " $0; bad = 1 }
          if ($NF == "ok" && !($(NF - 1) + 0 < 3.2)) { print "ok row with chi2_dof " $(NF - 1) ": " $0; bad = 1 }
          if ($NF == "misfit") { if (!($(NF - 1) + 0 > 1.8)) { print "misfit row with chi2_dof " $(NF - 1) ": " $0; bad = 1 }; print $1, $NF > "/dev/stderr" }
        } else if ($NF ~ /^(bound|noconv|illcond|worse)$/) {
          for (i = 1; i <= ne; i++) if (($E[i] "") != "nan") { print "flagged row with a stderr: " $0; bad = 1 }
          print $1, $NF > "/dev/stderr"
        } else { print "unknown status: " $0; bad = 1 }
      } END { if (NR != 11) print "rows: " NR - 1 ", not one per plane (10)"; exit bad || NR != 11 }' "$1" 2>"$tmp/flagged" || return 1
    while read -r z st; do grep -q "plane z = $z: $st: " "$2" || { echo "no flag line for z = $z ($st)"; return 1; }; done <"$tmp/flagged"
    [ "$(grep -c ': plane z = [^:]*: [a-z]*: ' "$2")" -eq "$(wc -l <"$tmp/flagged")" ] || { echo "flag lines != flagged rows"; return 1; }
  }
  # the user's case (the README's psi.csv, 2e5 photons): z = 10 runs to beta = infinity (it used to
  # print beta = 6.9e7 +- 0) on every seed; which other planes end on the bound varies with the seed
  U="--albedo 0.9 --sigma-t 1 --B 0.0685"
  "$NBT_FIT" mc $U --photons 200000 --seed 1 -o "$tmp/u.csv" >/dev/null 2>&1 || bad "mc: the user's case"
  "$NBT_FIT" kernel "$tmp/u.csv" $U -o "$tmp/ufit.csv" 2>"$tmp/uerr" && ok || bad "user's case: flags are not errors: $(cat "$tmp/uerr")"
  awk -F, '$1 == 10 { n++; good = $NF == "bound" && $3 == 1000 && ($5 "") == "nan" } END { exit !(n == 1 && good) }' "$tmp/ufit.csv" && ok ||
    bad "z = 10: beta on its bound, no standard error: $(grep '^10,' "$tmp/ufit.csv")"
  grep -q "u.csv: plane z = 10: bound: beta = 1000 is on its upper bound 1000" "$tmp/uerr" && ok || bad "flag line for z = 10: $(cat "$tmp/uerr")"
  nflag=$(grep -c ',\(bound\|worse\|illcond\|noconv\)$' "$tmp/ufit.csv")
  grep -q "^RMS .*($nflag of 10 planes flagged, $((10 - nflag)) misfit)" "$tmp/uerr" && ok || bad "summary counts the flagged planes: $(cat "$tmp/uerr")"
  # a plain erfc at 5-42% RMS is no 'ok': every plane not flagged misfits (chi^2/dof 6-200)
  [ "$(grep -c ',misfit$' "$tmp/ufit.csv")" -eq $((10 - nflag)) ] && ! grep -q ',ok$' "$tmp/ufit.csv" &&
    grep -q "u.csv: plane z = 3: misfit: chi^2/dof = .* (dof 48) is above 1.83, " "$tmp/uerr" && ok ||
    bad "the user's case: misfits: $(cat "$tmp/ufit.csv" "$tmp/uerr")"
  # 'worse': the fit weighs bins by their counting errors, the RMS does not, so on some realizations a
  # plane ends above the moment kernel's RMS it started from (z = 5 of seed 7: 0.3170 vs 0.3154; about 1
  # seed in 10). Seeds 2.. until one has such a plane: its row has no standard errors and a flag line
  worse=""
  for s in 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30; do
    "$NBT_FIT" mc $U --photons 200000 --seed $s -o "$tmp/uw.csv" >/dev/null 2>&1 &&
      "$NBT_FIT" kernel "$tmp/uw.csv" $U -o "$tmp/uwfit.csv" 2>"$tmp/uwerr" || { bad "the user's case, seed $s"; break; }
    msg=$(check_rows "$tmp/uwfit.csv" "$tmp/uwerr" "3" "2" "4 5") || { bad "erfc rows, seed $s: $msg"; break; }
    worse=$(awk -F, '$NF == "worse" { print $1; exit }' "$tmp/uwfit.csv")
    [ -n "$worse" ] && break
  done
  [ -n "$worse" ] && awk -F, -v z="$worse" '$1 == z { n++; good = $7 > $6 && ($4 "") == "nan" && ($5 "") == "nan" } END { exit !(n == 1 && good) }' "$tmp/uwfit.csv" &&
    grep -q "uw.csv: plane z = $worse: worse: RMS .* is above the RMS .* of the moment kernel it started from" "$tmp/uwerr" && ok ||
    bad "a plane worse than the moment kernel in 29 seeds, flagged without standard errors: $(cat "$tmp/uwfit.csv" "$tmp/uwerr")"
  msg=$(check_rows "$tmp/ufit.csv" "$tmp/uerr" "3" "2" "4 5") && ok || bad "erfc rows: $msg"
  # the two-part shapes on the same counts: degenerate splits (a part collapsed to zero or to 1/r) are flagged
  "$NBT_FIT" kernel "$tmp/u.csv" $U --shape erfc2 -o "$tmp/u2.csv" 2>"$tmp/u2err" && ok || bad "erfc2 on the user's case"
  msg=$(check_rows "$tmp/u2.csv" "$tmp/u2err" "3 7" "2 6" "4 5 8 9") && ok || bad "erfc2 rows: $msg"
  grep -q "bound\|illcond" "$tmp/u2err" && ok || bad "erfc2: degenerate planes flagged: $(cat "$tmp/u2err")"
  "$NBT_FIT" kernel "$tmp/u.csv" $U --shape erfc+gauss -o "$tmp/ug.csv" 2>"$tmp/ugerr" && ok || bad "erfc+gauss on the user's case"
  msg=$(check_rows "$tmp/ug.csv" "$tmp/ugerr" "3 7" "2 6" "4 5 8 9") && ok || bad "erfc+gauss rows: $msg"
  # --strict: any flag is an error, one line, nothing written
  expect_usage "--strict with flagged planes" "strict: $nflag of 10 fits flagged, nothing written; the first: .*u.csv: plane z = [0-9]*: bound: beta = " \
    "$NBT_FIT" kernel "$tmp/u.csv" $U --strict -o "$tmp/us.csv"
  [ ! -e "$tmp/us.csv" ] && [ ! -s "$tmp/out" ] && ok || bad "--strict left output"
  expect_usage "--strict with a correction" "strict" "$NBT_FIT" kernel "$tmp/u.csv" $U --strict --correction "$tmp/uc.txt" -o "$tmp/us.csv"
  [ ! -e "$tmp/us.csv" ] && [ ! -e "$tmp/uc.txt" ] && ok || bad "--strict left a correction"
  # standard errors against the spread of the fitted values over independent photon-counting runs
  # (seeds). spread_check FILE N LO HI: for every plane and parameter of the rows in FILE (N seeds), the
  # sample SD over seeds / the mean reported standard error within [LO, HI]. With correct errors,
  # (N - 1) SD^2 / sigma^2 is chi^2(N - 1): for N = 20 the ratio lies in [0.53, 1.52] with probability
  # 0.998 (chi^2(19) 0.1% and 99.9% points 5.41, 43.82), for N = 12 in [0.41, 1.69] (chi^2(11): 1.83, 31.26)
  spread_check() {
    awk -F, -v N="$2" -v lo="$3" -v hi="$4" '{ n[$1]++; for (c = 2; c <= 3; c++) { s[$1, c] += $c; s2[$1, c] += $c * $c; e[$1, c] += $(c + 2) } }
      END { for (z in n) for (c = 2; c <= 3; c++) { m = s[z, c] / n[z]; sd = sqrt((s2[z, c] - n[z] * m * m) / (n[z] - 1));
              r = sd / (e[z, c] / n[z]); printf "z %s %s: spread %.3g, mean stderr %.3g, ratio %.2f\n", z, c == 2 ? "alpha" : "beta", sd, e[z, c] / n[z], r
              if (!(r >= lo && r <= hi) || n[z] != N) bad = 1 }
            exit bad }' "$1"
  }
  # a good fit (albedo 0.5, z = 1, 2, 10^4 photons: erfc within the noise): all 40 ok under --strict
  : >"$tmp/boot"
  for s in 1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20; do
    "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.0685 --photons 10000 --z-planes 1:2:2 --r-bins 12 --seed $s -o "$tmp/b.csv" >/dev/null 2>&1 &&
      "$NBT_FIT" kernel "$tmp/b.csv" --albedo 0.5 --sigma-t 1 --B 0.0685 --strict 2>>"$tmp/booterr" | tail -n +2 >>"$tmp/boot"
  done
  [ "$(grep -c ',ok$' "$tmp/boot")" -eq 40 ] && ok || bad "good fits: 40 of 40 ok under --strict: $(cat "$tmp/booterr")"
  spread_check "$tmp/boot" 20 0.53 1.52 >"$tmp/bootr" && ok || bad "good fits: standard errors vs the spread over 20 seeds: $(cat "$tmp/bootr")"
  # a misfit (albedo 0.9, z = 2, 4, 6, 8, 1e5 photons: one erfc cannot follow the diffuse profile, chi^2/dof
  # 80-350): every fit 'misfit', with standard errors that still match the spread over 12 seeds (measured
  # 0.90-1.36; scaling (J^T J)^-1 by sqrt(chi^2/dof) gave 0.22-0.39 here, no scaling 2.4-6.1: doc/fit.md)
  : >"$tmp/mboot"
  : >"$tmp/mboot2"
  for s in 1 2 3 4 5 6 7 8 9 10 11 12; do
    "$NBT_FIT" mc --albedo 0.9 --sigma-t 1 --B 0.0685 --photons 100000 --z-planes 2:8:4 --r-bins 12 --seed $s -o "$tmp/b.csv" >/dev/null 2>&1 &&
      "$NBT_FIT" kernel "$tmp/b.csv" --albedo 0.9 --sigma-t 1 --B 0.0685 --strict 2>>"$tmp/mbooterr" | tail -n +2 >>"$tmp/mboot"
    "$NBT_FIT" kernel "$tmp/b.csv" --albedo 0.9 --sigma-t 1 --B 0.0685 --shape erfc+gauss 2>/dev/null | awk -F, '$1 == 2' >>"$tmp/mboot2"
  done
  # the two-part shape's four standard-error columns (4, 5, 8, 9 for the parameters in 2, 3, 6, 7) at z = 2,
  # where erfc+gauss fits with finite errors on every seed: each within the same chi^2(11) band of its own
  # parameter's spread (measured 1.00-1.30; the errors differ by 5x between parameters, so a column swap shows)
  awk -F, '{ n++; for (k = 0; k < 4; k++) { c = k < 2 ? 2 + k : 4 + k; s[k] += $c; s2[k] += $c * $c; e[k] += $(c + 2) } }
    END { for (k = 0; k < 4; k++) { m = s[k] / n; sd = sqrt((s2[k] - n * m * m) / (n - 1)); r = sd / (e[k] / n)
            printf "parameter %d: spread %.3g, mean stderr %.3g, ratio %.2f\n", k + 1, sd, e[k] / n, r
            if (!(r >= 0.41 && r <= 1.69)) bad = 1 }
          exit bad || n != 12 }' "$tmp/mboot2" >"$tmp/bootr" && ok ||
    bad "erfc+gauss: standard errors vs the spread over 12 seeds: $(cat "$tmp/bootr")"
  [ "$(grep -c ',misfit$' "$tmp/mboot")" -eq 48 ] && [ "$(grep -c ': misfit: chi^2/dof = ' "$tmp/mbooterr")" -eq 48 ] && ok ||
    bad "misfits: 48 of 48 under --strict, one line each: $(cat "$tmp/mboot" "$tmp/mbooterr")"
  spread_check "$tmp/mboot" 12 0.41 1.69 >"$tmp/bootr" && ok || bad "misfits: standard errors vs the spread over 12 seeds: $(cat "$tmp/bootr")"
  # phase: redundant lobes and lobes on their bounds are flagged; a fit above --tol (default 0.01) is a
  # misfit, which passes --strict (exit 0): HG 0.8's errors are 0.33, 0.073, 0.020, 0.0054 for K = 1..4
  "$NBT_FIT" phase --target hg:g=0.8 --terms 4 --strict -o "$tmp/hgs.sog" >"$tmp/p4" 2>"$tmp/p4err" &&
    [ "$(grep -c 'status misfit$' "$tmp/p4")" -eq 3 ] && grep -q '^K 4 .* status ok$' "$tmp/p4" &&
    [ "$(grep -c '^nbt-fit: phase K = [123]: misfit: relative L2 error .* is above --tol 0.01' "$tmp/p4err")" -eq 3 ] &&
    grep -q "^# fit status: ok" "$tmp/hgs.sog" && ok || bad "HG 0.8, K = 1..3 misfit, 4 ok: $(cat "$tmp/p4" "$tmp/p4err")"
  "$NBT_FIT" phase --target hg:g=0.8 --terms 2 --tol 0.1 >"$tmp/p4" 2>"$tmp/p4err" && grep -q '^K 1 .* status misfit$' "$tmp/p4" &&
    grep -q '^K 2 .* status ok$' "$tmp/p4" && ok || bad "phase --tol 0.1: K = 2 (error 0.073) ok: $(cat "$tmp/p4" "$tmp/p4err")"
  expect_usage "phase --tol 0" "--tol" "$NBT_FIT" phase --target iso --terms 1 --tol 0
  # the upper end: a relative L2 error of 1 is what no lobes at all give, so --tol 1 would pass any fit (man: (0, 1))
  expect_usage "phase --tol 1" "--tol: '1' is not accepted: expected a number in (0, 1)" "$NBT_FIT" phase --target iso --terms 1 --tol 1
  "$NBT_FIT" phase --target gauss:B=0.05 --terms 3 >"$tmp/p5" 2>"$tmp/p5err"
  grep -q "^K 1 .* status ok" "$tmp/p5" && ! grep -q "^K [23] .* status ok" "$tmp/p5" &&
    [ "$(grep -c '^nbt-fit: phase K = [23]: \(illcond\|bound\|worse\): ' "$tmp/p5err")" -eq 2 ] && ok ||
    bad "one Gaussian with 2, 3 lobes: redundant, flagged: $(cat "$tmp/p5" "$tmp/p5err")"
  "$NBT_FIT" phase --target rayleigh --terms 4 -o "$tmp/ray.sog" >"$tmp/p6" 2>"$tmp/p6err"
  grep -q '^K 1 .* status misfit$' "$tmp/p6" && [ "$(grep -c '^nbt-fit: phase K = [234]: ' "$tmp/p6err")" -eq 3 ] &&
    grep -q "^# fit status: bound: " "$tmp/ray.sog" && ok || bad "Rayleigh: K >= 2 flagged: $(cat "$tmp/p6" "$tmp/p6err")"
  expect_usage "phase --strict" "strict: 3 of 4 fits flagged" "$NBT_FIT" phase --target rayleigh --terms 4 --strict -o "$tmp/rs.sog"
  [ ! -e "$tmp/rs.sog" ] && [ ! -s "$tmp/out" ] && ok || bad "phase --strict left output"

  # model: the kernel model over depth, albedo and B (nbt-fit model), fitted to 9 small half-space runs
  # (3 albedos x 3 widths) and 2 infinite ones: every run ends well below the moment kernel's RMS
  for a in 0.3 0.6 0.9; do for B in 0.03 0.0685 0.154; do
    "$NBT_FIT" mc --albedo $a --sigma-t 1 --B $B --photons 20000 --z-planes 1:8:8 --r-bins 12 --seed 5 -o "$tmp/mh-$a-$B.exr" >/dev/null 2>&1
  done; done
  "$NBT_FIT" model "$tmp"/mh-*.exr -o "$tmp/m.txt" 2>"$tmp/merr" && ok || bad "model fit: $(cat "$tmp/merr")"
  # a sound fit, but at 2-3% RMS against counts with ~1% noise it misfits: one line, exit 0, in the file
  [ "$(grep -c '^RMS ' "$tmp/merr")" -eq 9 ] && [ "$(grep -c "^nbt-fit: model" "$tmp/merr")" -eq 1 ] &&
    grep -q "^nbt-fit: model (half): misfit: chi^2/dof = .* (dof 784) is above 1.21" "$tmp/merr" &&
    grep -q "chi^2/dof .*, fit status misfit" "$tmp/m.txt" && ok ||
    bad "model: one RMS line per run, a misfit: $(cat "$tmp/merr" "$tmp/m.txt")"
  # the moment kernel misses these by 11-27%; the model (80 coefficients on 9 runs) must reach half of that or better
  # (measured 0.07-0.43 of it over seeds 5-8; from one start only, 3 of those 4 seeds ended in a local minimum at
  # chi^2/dof 12 and up to 0.59)
  awk '/^RMS/ { if (!($4 + 0 < 0.5 * $6)) { print; b = 1 } } END { exit b }' "$tmp/merr" >"$tmp/mbad" && ok ||
    bad "model RMS below half the moment kernel's on every run: $(cat "$tmp/mbad")"
  [ "$(grep -c '^half P[0-4] ' "$tmp/m.txt")" -eq 5 ] && ! grep -q '^infinite ' "$tmp/m.txt" && grep -q '^range tau 1 8$' "$tmp/m.txt" &&
    grep -q '^range albedo 0.29999999999999999 0.90000000000000002$' "$tmp/m.txt" && grep -q '^range B 0.029999999999999999 0.154$' "$tmp/m.txt" && ok ||
    bad "model file: 5 half-space lines, the ranges of tau, albedo and B (the runs' 1..8, 0.3..0.9, 0.03..0.154): $(cat "$tmp/m.txt")"
  # --apply gives the same numbers as the fit's report
  "$NBT_FIT" model --apply "$tmp/m.txt" "$tmp"/mh-*.exr >"$tmp/mapp" 2>&1 && ok || bad "model --apply: $(cat "$tmp/mapp")"
  awk 'NR == FNR { if ($1 == "RMS") f[$2] = $4; next } /^half/ { n++; if (f[$7] != sprintf("%.4f", $5)) b = 1 } END { exit b || n != 9 }' \
    "$tmp/merr" "$tmp/mapp" && ok || bad "--apply = the fit's RMS: $(cat "$tmp/mapp")"
  # the shipped model on these runs (it was fitted to other seeds and a finer grid): within 5% where the runs' own noise
  # allows (their mc_se column is ~1-3%), and below the moment kernel
  "$NBT_FIT" model --apply default "$tmp"/mh-*.exr >"$tmp/mdef" 2>&1 &&
    awk '/^half/ { if (!($5 < 0.05 + 2 * $4 && $5 < $6)) { print; b = 1 } } END { exit b }' "$tmp/mdef" >"$tmp/mbad" && ok ||
    bad "the shipped model on fresh runs: $(cat "$tmp/mbad" "$tmp/mdef")"
  # an infinite run: the geometry comes from the EXR; a half-space-only model refuses it
  "$NBT_FIT" mc --albedo 0.6 --sigma-t 1 --B 0.0685 --photons 20000 --z-planes 1:8:8 --r-bins 12 --seed 5 --infinite -o "$tmp/mi.exr" >/dev/null 2>&1
  expect_usage "model --apply, geometry missing" "no coefficients for the infinite geometry" "$NBT_FIT" model --apply "$tmp/m.txt" "$tmp/mi.exr"
  "$NBT_FIT" model --apply default "$tmp/mi.exr" 2>&1 | grep -q '^infinite ' && ok || bad "the default model holds the infinite geometry"
  # --strict: a flagged fit (two runs cannot determine 80 coefficients without the ridge) writes nothing
  expect_usage "model --strict" "strict: 1 of 1 fits flagged" "$NBT_FIT" model "$tmp/mh-0.3-0.03.exr" "$tmp/mh-0.9-0.154.exr" --ridge 0 --strict -o "$tmp/ms.txt"
  [ ! -e "$tmp/ms.txt" ] && ok || bad "model --strict left a file"
  expect_usage "model without -o" "-o MODEL.txt" "$NBT_FIT" model "$tmp/mi.exr"
  expect_usage "model -o and --apply" "exclude" "$NBT_FIT" model "$tmp/mi.exr" --apply default -o "$tmp/ms.txt"
  expect_usage "model --apply missing" "No such file or directory" "$NBT_FIT" model --apply /nonexistent/m.txt "$tmp/mi.exr"
  expect_usage "model bad ridge" "--ridge" "$NBT_FIT" model "$tmp/mi.exr" --ridge -1 -o "$tmp/ms.txt"
  expect_usage "model CSV, medium unknown" "--albedo" "$NBT_FIT" model "$tmp/k1.csv" -o "$tmp/ms.txt"
  expect_fail "model to a missing directory" "-o: cannot write .*No such file or directory" "$NBT_FIT" model "$tmp/mi.exr" -o /nonexistent/dir/m.txt
  [ ! -e "$tmp/ms.txt" ] && ok || bad "refused model fits left output"

  # degenerate data
  printf 'z,r_lo,r_hi,psi,psi_stderr\n1,0,0.5,0,0\n1,0.5,1,0,0\n1,1,1.5,0,0\n1,1.5,2,0,0\n1,2,2.5,0,0\n1,2.5,3,0,0\n' >"$tmp/zero.csv"
  expect_usage "all-zero histogram" "all-zero" "$NBT_FIT" kernel "$tmp/zero.csv" --albedo 0.5 --sigma-t 1 --B 0.1 -o "$tmp/z.csv"
  printf 'z,r_lo,r_hi,psi,psi_stderr\n1,0,0.5,2,0.1\n' >"$tmp/one.csv"
  expect_usage "one bin" "bins per plane" "$NBT_FIT" kernel "$tmp/one.csv" --albedo 0.5 --sigma-t 1 --B 0.1 -o "$tmp/z.csv"
  printf 'z,r_lo,r_hi,psi,psi_stderr\n1,0,0.5,nan,0.1\n' >"$tmp/nan.csv"
  expect_usage "NaN" "line 2" "$NBT_FIT" kernel "$tmp/nan.csv" --albedo 0.5 --sigma-t 1 --B 0.1 -o "$tmp/z.csv"
  expect_usage "unknown medium" "--albedo" "$NBT_FIT" kernel "$tmp/k1.csv" -o "$tmp/z.csv"
  expect_usage "bad shape" "--shape" "$NBT_FIT" kernel "$tmp/k1.csv" --shape spline -o "$tmp/z.csv"
  [ ! -e "$tmp/z.csv" ] && ok || bad "rejected fits left output"
fi

# doc/accuracy.sh replaces the tracked doc/beam_rms.txt only after a whole successful run: in a scratch
# tree with a stub experiment, without gnuplot it stops first (one message, nothing changed); with a stub
# gnuplot that draws nothing it changes nothing; with one that draws, both files are replaced
acc=$(abspath "${top_srcdir:-.}/doc/accuracy.sh")
mkdir -p "$tmp/acc/doc/figures" "$tmp/acc/bench" "$tmp/acc/bin"
for t in mktemp rm mv cat tee; do ln -s "$(command -v $t)" "$tmp/acc/bin/$t"; done
printf '#!/bin/sh\nexit 0\n' >"$tmp/acc/bin/make"
printf '#!/bin/sh\necho new results; : >"$2/rms.dat"\n' >"$tmp/acc/bench/beam_accuracy"
chmod +x "$tmp/acc/bin/make" "$tmp/acc/bench/beam_accuracy"
echo tracked >"$tmp/acc/doc/beam_rms.txt"; echo tracked >"$tmp/acc/doc/figures/beam_rms.png"
(cd "$tmp/acc" && PATH="$tmp/acc/bin" /bin/sh "$acc" 10 >/dev/null 2>"$tmp/accerr"); rc=$?
[ $rc -ne 0 ] && grep -q "gnuplot is needed" "$tmp/accerr" && [ "$(cat "$tmp/acc/doc/beam_rms.txt")" = tracked ] && ok ||
  bad "accuracy.sh without gnuplot: rc=$rc, $(cat "$tmp/accerr"), beam_rms.txt: $(cat "$tmp/acc/doc/beam_rms.txt")"
printf '#!/bin/sh\ncat >/dev/null\n' >"$tmp/acc/bin/gnuplot"; chmod +x "$tmp/acc/bin/gnuplot"
(cd "$tmp/acc" && PATH="$tmp/acc/bin" /bin/sh "$acc" 10 >/dev/null 2>"$tmp/accerr"); rc=$?
[ $rc -ne 0 ] && [ "$(cat "$tmp/acc/doc/beam_rms.txt")" = tracked ] && [ "$(cat "$tmp/acc/doc/figures/beam_rms.png")" = tracked ] && ok ||
  bad "accuracy.sh with a failed plot: rc=$rc, beam_rms.txt: $(cat "$tmp/acc/doc/beam_rms.txt")"
printf '#!/bin/sh\nf=$(sed -n "s/^set output \\"\\(.*\\)\\"/\\1/p"); echo png >"$f"\n' >"$tmp/acc/bin/gnuplot"
ln -s "$(command -v sed)" "$tmp/acc/bin/sed"
(cd "$tmp/acc" && PATH="$tmp/acc/bin" /bin/sh "$acc" 10 >/dev/null 2>"$tmp/accerr"); rc=$?
[ $rc -eq 0 ] && [ "$(cat "$tmp/acc/doc/beam_rms.txt")" = "new results" ] && [ "$(cat "$tmp/acc/doc/figures/beam_rms.png")" = png ] && ok ||
  bad "accuracy.sh success replaces both: rc=$rc, $(cat "$tmp/accerr"), $(cat "$tmp/acc/doc/beam_rms.txt")"
rm -rf "$tmp/acc" "$tmp/accerr"

# bad input
expect_usage "albedo > 1" "--albedo" "$NBT_FIT" mc --albedo 1.2 --sigma-t 1 --B 0.1 --photons 1000 -o "$tmp/x.csv"
expect_usage "negative sigma_t" "--sigma-t" "$NBT_FIT" mc --albedo 0.5 --sigma-t -1 --B 0.1 --photons 1000 -o "$tmp/x.csv"
expect_usage "NaN" "--B" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B nan --photons 1000 -o "$tmp/x.csv"
expect_usage "both phases" "exactly one" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --phase iso --photons 1000 -o "$tmp/x.csv"
expect_usage "too few photons" "--photons" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 10 -o "$tmp/x.csv"
expect_usage "bad planes" "--z-planes" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000 --z-planes 3:1:4 -o "$tmp/x.csv"
: >"$tmp/empty.txt"
expect_usage "empty density file" "empty" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000 --density "$tmp/empty.txt" -o "$tmp/x.csv"
printf '0 1\n0.5 -2\n' >"$tmp/neg.txt"
expect_usage "negative density" "neg.txt:2: density file: rho = -2 is not accepted: rho must be >= 0" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000 --density "$tmp/neg.txt" -o "$tmp/x.csv"
printf '0 1\nO.5 2\n' >"$tmp/letter.txt"
expect_usage "density: letter O" "letter.txt:2: density file: 'O.5 2' is not accepted" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000 --density "$tmp/letter.txt" -o "$tmp/x.csv"
expect_usage "not csv or exr" "\.exr" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000 -o "$tmp/x.png"
expect_usage "EXR with one plane" "2 planes" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000 --z-planes 1:1:1 -o "$tmp/x.exr"
expect_usage "infinite slab" "--infinite" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000 --slab 2 --infinite
expect_usage "unknown estimator" "--estimator" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000 --slab 2 --estimator mcml
expect_usage "order-max 0" "--order-max" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000 --order-max 0 -o "$tmp/x.csv"
expect_usage "no output" "-o" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000
expect_usage "unknown command" "frob" "$NBT_FIT" frob
expect_usage "no command: all listed" "mc, kernel, phase, model or screenmodel" "$NBT_FIT"
[ ! -e "$tmp/x.csv" ] && [ ! -e "$tmp/x.exr" ] && [ ! -e "$tmp/x.png" ] && ok || bad "rejected runs left output"
# a missing or unreadable input file is bad input in every command that reads one: exit 2, one line with the OS reason
miss=/nonexistent/dir/in
enoent="No such file or directory"
expect_usage "mc --density missing" "$enoent" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --B 0.1 --photons 1000 --density $miss.txt -o "$tmp/x.csv"
expect_usage "mc --phase table missing" "$enoent" "$NBT_FIT" mc --albedo 0.5 --sigma-t 1 --phase table:$miss.txt --photons 1000 -o "$tmp/x.csv"
if "$NBT_FIT" kernel --help >/dev/null 2>&1; then
  expect_usage "kernel CSV missing" "$enoent" "$NBT_FIT" kernel $miss.csv --albedo 0.5 --sigma-t 1 --B 0.1
  expect_usage "kernel EXR missing" "$enoent" "$NBT_FIT" kernel $miss.exr
  "$NBT_FIT" mc $M -o "$tmp/w.csv" >/dev/null 2>&1
  expect_usage "kernel --apply missing" "$enoent" "$NBT_FIT" kernel "$tmp/w.csv" --albedo 0.7 --sigma-t 1.3 --B 0.0685 --apply $miss.txt
  expect_usage "phase --target table missing" "$enoent" "$NBT_FIT" phase --target table:$miss.txt --terms 2
  expect_usage "phase --target sog missing" "$enoent" "$NBT_FIT" phase --target sog:$miss.sog --terms 2
  # read before the fits (16 lobes would take a while)
  expect_usage "phase --against missing" "$enoent" timeout 10 "$NBT_FIT" phase --target hg:g=0.9 --terms 16 --against $miss.exr
  # malformed photon counts: the line named, nothing fitted
  printf 'z,r_lo,r_hi,psi,psi_stderr\n1,0,0.1,0.5,0.01\n1,0.1,0.2,-0.3,0.01\n' >"$tmp/neg.csv"
  expect_usage "kernel CSV with a negative psi" "neg.csv line 3: '1,0.1,0.2,-0.3,0.01' is not accepted: expected .*psi >= 0" "$NBT_FIT" kernel "$tmp/neg.csv" --albedo 0.5 --sigma-t 1 --B 0.1
  printf 'z,r_lo,r_hi,psi,psi_stderr\n1,0.2,0.1,0.5,0.01\n' >"$tmp/neg.csv"
  expect_usage "kernel CSV with r_hi < r_lo" "neg.csv line 2: '1,0.2,0.1,0.5,0.01' is not accepted: expected" "$NBT_FIT" kernel "$tmp/neg.csv" --albedo 0.5 --sigma-t 1 --B 0.1
  rm -f "$tmp/neg.csv"
fi
[ ! -e "$tmp/x.csv" ] && ok || bad "missing inputs left output"

# unwritable outputs: refused before any work (these runs would take minutes), with the OS reason
enoent="cannot write .*No such file or directory"
BIG="--albedo 0.9 --sigma-t 1 --B 0.1 --photons 1e10"
# bins per plane: a shape of k parameters needs k + 1; erfc (2) fits 3 and refuses 2 naming 3, erfc2 (4) refuses 3 naming 5
K="--albedo 0.7 --sigma-t 1.3 --B 0.0685"
"$NBT_FIT" mc $K --photons 2000 --z-planes 1:2:2 --r-bins 2 --seed 3 -o "$tmp/b2.csv" >/dev/null 2>&1 &&
  "$NBT_FIT" mc $K --photons 2000 --z-planes 1:2:2 --r-bins 3 --seed 3 -o "$tmp/b3.csv" >/dev/null 2>&1 &&
  "$NBT_FIT" kernel "$tmp/b3.csv" $K -o "$tmp/b3f.csv" 2>/dev/null && ok || bad "kernel: erfc on 3 bins per plane"
expect_usage "kernel: erfc on 2 bins" "2 bins per plane: this shape needs at least 3$" "$NBT_FIT" kernel "$tmp/b2.csv" $K
expect_usage "kernel: erfc2 on 3 bins" "3 bins per plane: this shape needs at least 5$" "$NBT_FIT" kernel "$tmp/b3.csv" $K --shape erfc2
# a counts CSV with an infinite r_hi (each of the five fields must be finite): refused naming the line
printf 'z,r_lo,r_hi,psi,psi_stderr\n1,0,0.1,2.5,0.1\n1,0.1,inf,1.5,0.1\n' >"$tmp/rinf.csv"
expect_usage "counts CSV with r_hi = inf" "rinf.csv line 3: '1,0.1,inf,1.5,0.1' is not accepted: expected .* (finite)" "$NBT_FIT" kernel "$tmp/rinf.csv" --albedo 0.7 --sigma-t 1.3 --B 0.0685
# --photons: the closed range [64, 1e15]: 64 counts, 63 is refused with the range
"$NBT_FIT" mc --albedo 0.9 --sigma-t 1 --B 0.0685 --photons 64 --z-planes 1:2:2 -o "$tmp/p64.csv" >/dev/null 2>&1 &&
  [ -s "$tmp/p64.csv" ] && ok || bad "mc --photons 64 (the smallest accepted)"
expect_usage "mc --photons 63" "expected a number in \[64, 1e+15\]" "$NBT_FIT" mc --albedo 0.9 --sigma-t 1 --B 0.0685 --photons 63 --z-planes 1:2:2
expect_fail "mc CSV to a missing directory" "-o: $enoent" "$NBT_FIT" mc $BIG -o /nonexistent/dir/x.csv
expect_fail "mc EXR to a missing directory" "-o: $enoent" "$NBT_FIT" mc $BIG -o /nonexistent/dir/x.exr
mkdir "$tmp/dir.csv"
expect_fail "mc output is a directory" "-o: cannot write .*Is a directory" "$NBT_FIT" mc $BIG -o "$tmp/dir.csv"
rmdir "$tmp/dir.csv"
if "$NBT_FIT" kernel --help >/dev/null 2>&1; then
  "$NBT_FIT" mc $M -o "$tmp/w.csv" >/dev/null 2>&1
  expect_fail "kernel fit to a missing directory" "-o: $enoent" "$NBT_FIT" kernel "$tmp/w.csv" --albedo 0.7 --sigma-t 1.3 --B 0.0685 -o /nonexistent/dir/f.csv
  expect_fail "kernel correction to a missing directory" "--correction: $enoent" \
    "$NBT_FIT" kernel "$tmp/w.csv" --albedo 0.7 --sigma-t 1.3 --B 0.0685 --correction /nonexistent/dir/c.txt -o "$tmp/f.csv"
  [ ! -e "$tmp/f.csv" ] && ok || bad "a refused kernel fit wrote its -o file"
  expect_fail "phase fit to a missing directory" "-o: $enoent" "$NBT_FIT" phase --target hg:g=0.9 --terms 16 -o /nonexistent/dir/p.sog
fi

# screenmodel: a small model (one g, albedo, two depths, 2e5 photons, both geometries) fitted, then checked
# against fresh counts of another seed: per point the mass bias within 2x and the radial relative L1 within
# 3x the fresh counts' own noise (measured 0.8x and 1.9x at worst: the model carries its own counting noise)
"$NBT_FIT" screenmodel -o "$tmp/sm.txt" --g 0.7 --albedo 0.95 --tau 0.5,3 --photons 200000 --seed 1 --quiet &&
  grep -q "^param 0.7$" "$tmp/sm.txt" && grep -q "^albedo 0.95$" "$tmp/sm.txt" && grep -q "^tau 0.5 3$" "$tmp/sm.txt" &&
  [ "$(grep -c '^node ' "$tmp/sm.txt")" -eq 4 ] && ok || bad "screenmodel writes the requested grid: $(head -12 "$tmp/sm.txt")"
"$NBT_FIT" screenmodel --check "$tmp/sm.txt" --g 0.7 --albedo 0.95 --tau 0.5,3 --photons 200000 --seed 7 \
  2>/dev/null >"$tmp/smc"
[ "$(grep -c '^inside\|^entering' "$tmp/smc")" -eq 4 ] &&
  awk '/^(inside|entering)/ { b = $7 < 0 ? -$7 : $7; if (!(b <= 2 * $10 && $8 <= 3 * $10 && $10 > 0)) bad = 1 } END { exit bad }' \
  "$tmp/smc" && ok || bad "screenmodel --check: model vs fresh counts within their noise: $(cat "$tmp/smc")"
# a fixed phase (two-term HG): its model is keyed by the phase's fingerprint; another phase is refused.
# The model from 1e6 photons: radial L1 within 3.5x (measured 2.0-2.4x at tau 0.5 entering over seeds 7-11;
# a model from 2e5 photons carries its own noise, 3.2-4.1x), mass bias within 2x
P2=hg2:g1=0.8,g2=-0.3,w=0.85
"$NBT_FIT" screenmodel -o "$tmp/smp.txt" --phase $P2 --albedo 0.95 --tau 0.5,3 --photons 1000000 --seed 1 --quiet &&
  grep -q "^family fixed $P2$" "$tmp/smp.txt" && grep -q "^fingerprint " "$tmp/smp.txt" && ok ||
  bad "screenmodel --phase writes a fixed-phase model: $(head -6 "$tmp/smp.txt")"
"$NBT_FIT" screenmodel --check "$tmp/smp.txt" --phase $P2 --albedo 0.95 --tau 0.5,3 --photons 200000 --seed 7 \
  2>/dev/null >"$tmp/smc"
[ "$(grep -c '^inside\|^entering' "$tmp/smc")" -eq 4 ] &&
  awk '/^(inside|entering)/ { b = $7 < 0 ? -$7 : $7; if (!(b <= 2 * $10 && $8 <= 3.5 * $10 && $10 > 0)) bad = 1 } END { exit bad }' \
  "$tmp/smc" && ok || bad "screenmodel --check, fixed phase: within the noise: $(cat "$tmp/smc")"
"$NBT_FIT" screenmodel --check "$tmp/smp.txt" --phase hg:g=0.8 --albedo 0.95 --tau 0.5,3 --photons 2000 >/dev/null \
  2>"$tmp/err" && bad "a fixed-phase model checked against another phase" ||
  { grep -q "does not cover hg:g=0.8" "$tmp/err" && ok || bad "fixed-phase model vs another phase: $(cat "$tmp/err")"; }
# points where no photon scattered twice (tau = 1e-5, 2e-5: a second scattering has probability of order
# tau^2 ~ 1e-10 per photon, of 1000) have no counted mass to be relative to: their bias and relL1 read 0
# (no measure), not a 100% bias
"$NBT_FIT" screenmodel --check default --g 0.7 --albedo 0.95 --tau 1e-5,2e-5 --photons 1000 --seed 3 --threads 1 \
  2>/dev/null >"$tmp/smz"
awk '/^(inside|entering) / { n++; if ($5 != 0 || $7 != 0 || $8 != 0) bad = 1 } END { exit bad || n != 4 }' "$tmp/smz" && ok ||
  bad "screenmodel --check: zero counted mass, bias and relL1 0: $(cat "$tmp/smz")"

# a list must increase at every step, not only against the one before last: 0.1,0.5,0.3 falls at its third
# entry (0.3 > 0.1 but < 0.5); with three entries a check against v[n - 2] would let it through
expect_usage "screenmodel --tau 0.1,0.5,0.3 (not increasing)" "--tau: '0.1,0.5,0.3' is not accepted: expected increasing" \
  "$NBT_FIT" screenmodel -o "$tmp/smbad.txt" --g 0.7 --albedo 0.95 --tau 0.1,0.5,0.3 --photons 1000
[ ! -e "$tmp/smbad.txt" ] && ok || bad "a refused --tau list left $tmp/smbad.txt"

# the run description stored in an mc EXR (nbt.run, 128 bytes with its terminator) is cut at 127
# characters: these options make it longer (a table phase under a 120-character directory, a 10-digit seed,
# infinite, order_max, weighted), and the stored line is its first 127 characters
ld="$tmp/$(printf 'd%.0s' $(seq 1 120))"; mkdir -p "$ld" && printf -- '-1 0.3\n1 1.2\n' >"$ld/p.txt"
"$NBT_FIT" mc --albedo 0.912345 --sigma-t 1.23456 --phase "table:$ld/p.txt" --photons 20000 --seed 2147483647 --infinite \
  --order-max 3 --estimator weighted --z-planes 1:2:2 -o "$tmp/lrun.exr" --quiet >/dev/null 2>&1
"$NBT_GEN" info "$tmp/lrun.exr" 2>/dev/null | sed -n 's/^run  *//p' >"$tmp/lrun"
awk 'NR == 1 { r = $0 } END { exit !(NR == 1 && length(r) == 127 && index(r, "mc albedo=0.912345 sigma_t=1.23456 phase=table:") == 1 &&
  r ~ / seed=[0-9]+$/ && index(" seed=2147483647", substr(r, index(r, " seed="))) == 1) }' "$tmp/lrun" && ok ||
  bad "mc EXR: a long run description cut at 127 characters: $(cat "$tmp/lrun")"

finish
