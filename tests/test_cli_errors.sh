#!/bin/sh
# tests/test_cli_errors.sh: the bad-input and I/O-failure paths of nbt-gen,
# nbt-fit, nbt-scatter and nbt-demo (issue 20), one command a line: the exit
# status (2 bad usage, 1 a failure at run time), the one message, which names
# the bad value and what is accepted, and no output file left where one was
# asked for. Where an option has a bound, the value just outside is refused
# and the value just inside passes that check (the command then stops at a
# later, deliberate error: what it names proves the bound let the value by).
. "${top_srcdir:-.}/tests/testlib.sh"
NBT_GEN=$(abspath "${NBT_GEN:-./nbt-gen}")
NBT_FIT=$(abspath "${NBT_FIT:-./nbt-fit}")
NBT_SCATTER=$(abspath "${NBT_SCATTER:-./nbt-scatter}")
MK=$(abspath "${NBT_MKEXR:-./tests/mkexr}")
G=$NBT_GEN F=$NBT_FIT S=$NBT_SCATTER D=
[ -n "${NBT_DEMO:-}" ] && [ -x "$NBT_DEMO" ] && D=$(abspath "$NBT_DEMO")
o=$tmp/o   # every refused command's output goes here: it must stay empty
mkdir "$o"
gl=0; "$S" --help | grep -q "On GL" && gl=1   # the GL methods (shinya, elek, ...) in this build
cd "$tmp" || exit 1   # runs without -o write into the working directory: $tmp, listed below

# E STATUS TEXT CMD...: CMD exits with STATUS, prints nothing on stdout and
# one line on stderr containing TEXT (a fixed string); $o stays empty
E() {
  _s=$1 _t=$2; shift 2
  timeout 20 "$@" >"$tmp/out" 2>"$tmp/err"; _rc=$?
  if [ $_rc -eq "$_s" ] && [ "$(wc -l <"$tmp/err")" -eq 1 ] && grep -qF -- "$_t" "$tmp/err" && [ ! -s "$tmp/out" ]; then ok
  else bad "$*: rc=$_rc (want $_s), stderr: $(cat "$tmp/err"), stdout: $(head -c 200 "$tmp/out")"; fi
  left "$*"
}
# O HELP CMD... (an unknown option --bogus): one line naming it and 'HELP --help'
# (getopt's own message, which named .libs/PROGRAM in a build tree, is off); exit 2
O() {
  _h=$1; shift
  E 2 "unknown option '--bogus' (see '$_h --help')" "$@"
}
left() {
  if [ -z "$(ls -A "$o")" ]; then ok; else bad "$1 left: $(ls -A "$o")"; rm -rf "$o"/*; fi
}

# ---- fixtures: tiny tables (5x4 nodes, a fraction of a second each), photon-count CSVs
q="--no-preview --quiet"
"$G" airlight --phase hg:g=0.3 --size 5x4 $q -o hf.exr >/dev/null 2>&1 &&
  "$G" surface --phase hg:g=0.3 --size 5x4 $q -o jf1.exr >/dev/null 2>&1 &&
  "$G" surface --kmax 3 --n 3 --size 5x4 $q -o jl3.exr >/dev/null 2>&1 &&
  "$G" surface --g 0:0.5 --basis slices --tol 5e-2 $q -o js.exr >/dev/null 2>&1 &&
  "$G" airlight --g 0:0.5 --basis slices --tol 5e-2 --allow-tol-miss $q -o hs.exr >/dev/null 2>&1 &&
  [ -s hf.exr ] && [ -s jf1.exr ] && [ -s jl3.exr ] && [ -s js.exr ] && [ -s hs.exr ] && ok || bad "fixture tables"
printf 'beta 0 0 0 0 0 0 0\nalpha 0 0 0 0 0 0 0\n' >corr.txt   # a valid (null) kernel correction
hdr=z,r_lo,r_hi,psi,psi_stderr
printf '%s\n' $hdr >empty.csv
printf 'x,y\n1,2\n' >badhdr.csv
printf '%s\n' $hdr 1,0,0.1,1,0.1 1,0.1,0.2,1,0.1 2,0,0.1,1,0.1 >uneven.csv    # 3 rows, 2 planes
printf '%s\n' $hdr 1,0,0.1,1,0.1 2,0,0.1,1,0.1 2,0.1,0.2,1,0.1 1,0.1,0.2,1,0.1 >split.csv  # 4 rows, planes 1 2 1
printf '%s\n' $hdr 1,0,0.1,1,0.1 1,0.1,0.2,1,0.1 2,0,0.1,1,0.1 2,0.1,0.2,1,0.1 >ok.csv     # 2 planes of 2 bins
z16="0 0 0 0 0 0 0 0 0 0 0 0 0 0 0 0"   # a beam model with the half-space coefficients only
printf "half P0 $z16\nhalf P1 $z16\nhalf P2 $z16\nhalf P3 $z16\nhalf P4 $z16\n" >half.txt
# a row with r_hi = r_lo after 1100 good rows (past the reader's first 1024-row block)
{ echo $hdr; i=0; while [ $i -lt 1100 ]; do echo "1,$i,$((i + 1)),1,0.1"; i=$((i + 1)); done; echo 1,5,5,1,0.1; } >late.csv

# ---- nbt-gen eval
A="--kappa-s 0.1 --kappa-t 0.2 --I0 1 --dsv 1 --gamma 1 --dvp 2"
SF="--kappa-s 0.3 --kappa-t 0.5 --I0 2 --dsp 3 --theta-s 0.5 --theta-r 0.5"
E 2 "eval: say what to evaluate: H, J, airlight" "$G" eval
E 2 "eval: 'X' is not accepted: H, J, airlight, surface, moments or psi" "$G" eval X
O "nbt-gen eval" "$G" eval H --k 2 --u 1 --v 0 --bogus
E 2 "eval: unexpected argument 'extra'" "$G" eval H --k 2 --u 1 --v 0 extra
E 2 "eval H: --k and --phase exclude each other" "$G" eval H --k 2 --phase iso --u 1 --v 0
E 2 "eval J: --k K (Legendre order) or --phase SPEC is required" "$G" eval J --n 1 --T 1 --theta 1
# nested quadratures (J, surface) take --tol >= 1e-12 (below it they ran for minutes); H, airlight 1e-15
E 2 "eval J: --tol 1e-13 is not accepted: 1e-12 .. 0.1 (a nested quadrature" "$G" eval J --k 3 --n 20 --T 1.2 --theta 0.3 --tol 1e-13
E 2 "eval surface: --tol 1e-15 is not accepted: 1e-12 .. 0.1" "$G" eval surface --g 0.5 --kappa-s 0.45 --kappa-t 0.5 --I0 1 --dsp 8 --theta-s 0.4 --theta-r 0.3 --kd 1 --ks 0 --n 2 --method series --tol 1e-15
E 2 "--tol: '1e-16' is not accepted: expected a number in [1e-15, 0.1]" "$G" eval H --k 3 --u 1 --v 0.3 --tol 1e-16
timeout 20 "$G" eval J --k 3 --n 20 --T 1.2 --theta 0.3 --tol 1e-12 >"$tmp/out" 2>/dev/null && [ -s "$tmp/out" ] && ok || bad "eval J --tol 1e-12 refused or slow"
E 2 "eval: --g and --phase exclude each other" "$G" eval airlight --g 0.3 --phase iso $A
E 2 "eval: give the phase function with --g G or --phase SPEC" "$G" eval airlight $A
E 2 "--terms applies to --method series|table only" "$G" eval airlight --g 0.3 $A --terms 3
E 2 "--kappa-t: 0.2 is not accepted: extinction must be >= scattering (0.3)" "$G" eval airlight --g 0.3 --kappa-s 0.3 --kappa-t 0.2 --I0 1 --dsv 1 --gamma 1 --dvp 2
E 2 "--kappa-t: 0.2 is not accepted: extinction must be >= scattering (0.3)" "$G" eval surface --g 0.3 --kappa-s 0.3 --kappa-t 0.2 --I0 1 --dsp 1 --theta-s 1 --theta-r 1 --kd 1 --ks 0 --n 2
# kappa_t = kappa_s (no absorption) is accepted: a value, not a refusal
words 2 "$G" eval airlight --g 0.3 --kappa-s 0.2 --kappa-t 0.2 --I0 1 --dsv 1 --gamma 1 --dvp 2
E 2 "--model: 'lineint' is not accepted for moments: ishimaru or smallangle" "$G" eval moments --albedo 0.9 --sigma-t 1 --B 0.1 --z 1 --model lineint
E 2 "--model: 'foo' is not accepted: ishimaru, smallangle, lineint, single, elek or fitted" "$G" eval psi --albedo 0.9 --sigma-t 1 --B 0.1 --z 1 --r 0.5 --model foo
E 2 "--beam-model: 'half.txt' holds no coefficients for the infinite (--infinite) geometry" "$G" eval psi --albedo 0.9 --sigma-t 1 --B 0.1 --z 1 --r 0.5 --model fitted --beam-model half.txt --infinite
"$G" eval --help | grep -q "^Usage: nbt-gen eval" && ok || bad "eval --help"
E 2 "--g: '1' is not accepted: expected a number in (-1, 1)" "$G" eval airlight --g 1 $A
E 2 "--g: '-1' is not accepted: expected a number in (-1, 1)" "$G" eval airlight --g -1 $A
E 2 "--gamma: '3.1416' is not accepted: expected a number in [0, 3.14159]" "$G" eval airlight --g 0.3 --kappa-s 0.1 --kappa-t 0.2 --I0 1 --dsv 1 --gamma 3.1416 --dvp 2
E 2 "--dsv: '0' is not accepted: expected a number in (0, inf)" "$G" eval airlight --g 0.3 --kappa-s 0.1 --kappa-t 0.2 --I0 1 --dsv 0 --gamma 1 --dvp 2
E 2 "--tol: '0.11' is not accepted: expected a number in [1e-15, 0.1]" "$G" eval airlight --g 0.3 $A --tol 0.11
E 2 "--terms: '2049' is not accepted: expected an integer in [1, 2048]" "$G" eval airlight --g 0.3 $A --method series --terms 2049
# gamma = 0 looks along the line to the source: dvp >= dsv crosses it (infinite), dvp < dsv does not
E 2 "--dvp: '1' is not accepted with --gamma 0: the ray would run through the source (dvp >= dsv = 1)" "$G" eval airlight --g 0.3 --kappa-s 0.1 --kappa-t 0.2 --I0 1 --dsv 1 --gamma 0 --dvp 1
E 2 "--dvp: 'inf' is not accepted with --gamma 0" "$G" eval airlight --g 0.3 --kappa-s 0.1 --kappa-t 0.2 --I0 1 --dsv 1 --gamma 0 --dvp inf
words 2 "$G" eval airlight --g 0.3 --kappa-s 0.1 --kappa-t 0.2 --I0 1 --dsv 1 --gamma 0 --dvp 0.999
# a --tol the quadrature cannot reach (1e-14 relative: NBT_ETOL from the first, 4-term series) must not stop the
# series there: it stopped at 4 terms, 0.00410 with a claimed error 4.6e-17 for 0.00449 (g = 0.6). The value
# must agree with the direct integral (default tol 1e-8) within the sum of both reported errors, and the
# warning is given
words 2 "$G" eval airlight --g 0.6 $A; set -- $w; vd=$1 ed=$2
"$G" eval airlight --g 0.6 $A --method series --tol 1e-14 >out 2>err; set -- $(cat out)
awk -v v="$1" -v e="$2" -v d="$vd" -v f="$ed" 'BEGIN { x = v - d; if (x < 0) x = -x; exit !(v != "" && e > 0 && x <= e + f) }' &&
  grep -qF "warning: the requested tolerance was not reached" err && ok ||
  bad "eval series at tol 1e-14: $(cat out err) vs direct $vd +- $ed"

# ---- eval --method table --tables: the files' kinds, count and coverage
T="--method table --tables"
E 2 "--tables: --terms and --tol do not apply (the files fix both)" "$G" eval airlight --g 0.3 $A $T hf.exr --tol 1e-3
E 2 "--dvp: '1' is not accepted with --gamma 0: the ray would run through the source (dvp >= dsv = 1)" "$G" eval airlight --kappa-s 0.1 --kappa-t 0.2 --I0 1 --dsv 1 --gamma 0 --dvp 1 $T hf.exr
words 2 "$G" eval airlight --kappa-s 0.1 --kappa-t 0.2 --I0 1 --dsv 1 --gamma 0 --dvp 0.999 $T hf.exr 2>/dev/null
E 2 "--tables: eval airlight takes one fixed-phase H table, 2 given" "$G" eval airlight $A $T hf.exr hf.exr
E 2 "--tables: eval airlight takes one g-sliced H table, 2 given" "$G" eval airlight --g 0.3 $A $T hs.exr hs.exr
E 2 "--tables: no fixed-phase J table for the specular lobe" "$G" eval surface $SF --kd 0.5 --ks 0.5 --n 3 $T jf1.exr
E 2 "--tables: no g-sliced J table for the specular lobe (n = 3)" "$G" eval surface --g 0.3 $SF --kd 0.5 --ks 0.5 --n 3 $T js.exr
E 2 "--tables: no Legendre J tables for the diffuse lobe" "$G" eval surface --g 0.3 $SF --kd 0.5 --ks 0.5 --n 3 $T jl3.exr
E 2 "--tables: 'jl3.exr' has n = 3; eval surface takes n = 1 (diffuse) or n = 2 (--n) tables" "$G" eval surface --g 0.3 $SF --kd 0.5 --ks 0.5 --n 2 $T jl3.exr
E 2 "eval: --g and --phase exclude each other" "$G" eval surface --g 0.3 --phase iso $SF --kd 0 --ks 0.5 --n 3 $T jl3.exr
E 2 "--phase: unknown phase 'foo'" "$G" eval surface --phase foo $SF --kd 0 --ks 0.5 --n 3 $T jl3.exr
E 2 "--tables: Legendre tables need the phase: --g G or --phase SPEC" "$G" eval surface $SF --kd 0 --ks 0.5 --n 3 $T jl3.exr
# js.exr covers g in [0, 0.5]: 0.5 is inside (a value), 0.5001 outside
E 2 "--g: 0.5001 is not accepted: 'js.exr' covers g in [0, 0.5]" "$G" eval surface --g 0.5001 $SF --kd 0.5 --ks 0 --n 1 $T js.exr
words 2 "$G" eval surface --g 0.5 $SF --kd 0.5 --ks 0 --n 1 $T js.exr 2>/dev/null
# at most 64 files: 64 are read (the first one missing is named), 65 refused before reading
n64=$(i=0; while [ $i -lt 64 ]; do printf 'none.exr '; i=$((i + 1)); done)
E 2 "--tables: none.exr: cannot open" "$G" eval airlight --g 0.3 $A $T $n64
E 2 "--tables: 65 files given, at most 64 accepted" "$G" eval airlight --g 0.3 $A $T $n64 none.exr

# ---- nbt-gen airlight / surface (table building): each refused before any work
E 2 "--size: '1x5' is not accepted: expected WxH with 2 <= W, H <= 4096" "$G" airlight --size 1x5 -o "$o/a.exr"
E 2 "--size: '5x1' is not accepted" "$G" airlight --size 5x1 -o "$o/a.exr"
E 2 "--size: '4097x2' is not accepted" "$G" airlight --size 4097x2 -o "$o/a.exr"
E 2 "--size: '2x4097' is not accepted" "$G" airlight --size 2x4097 -o "$o/a.exr"
E 2 "--size: '5x5x' is not accepted" "$G" airlight --size 5x5x -o "$o/a.exr"
E 2 "-o: '$o/a.txt' is not accepted: the output must be a file name ending in .exr" "$G" airlight --size 2x4096 -o "$o/a.txt"
E 2 "-o: '$o/a.txt' is not accepted" "$G" airlight --size 4096x2 -o "$o/a.txt"
E 2 "--basis: 'foo' is not accepted: legendre, slices or auto" "$G" airlight --basis foo --g 0:0.5
E 2 "--basis slices: --g 0.3:0.3 is one value: give a range LO < HI (or --phase hg:g=0.3)" "$G" surface --basis slices --g 0.3 -o "$o/a.exr"
E 2 "--n applies to 'surface' tables only" "$G" airlight --n 3
E 2 "airlight: unexpected argument 'extra'" "$G" airlight extra
O "nbt-gen surface" "$G" surface --bogus
# a missing value (the last argument), an unknown letter, a flag given a value
E 2 "--size needs a value (see 'nbt-gen surface --help')" "$G" surface --phase iso --size
E 2 "-o needs a value (see 'nbt-gen airlight --help')" "$G" airlight --phase iso -o
E 2 "unknown option '-z' (see 'nbt-gen airlight --help')" "$G" airlight --phase iso -z
E 2 "unknown option '--quiet=1' (see 'nbt-gen airlight --help')" "$G" airlight --phase iso --quiet=1
E 2 "-tol needs a value (see 'nbt-gen eval --help')" "$G" eval H --k 2 --u 1 --v 0 -tol
E 2 "--size and --tol exclude each other: give one" "$G" airlight --size 5x5 --tol 1e-3
E 2 "--kmax and --phase exclude each other" "$G" airlight --kmax 3 --phase iso
E 2 "--g chooses the Legendre orders itself: it excludes --kmax and --phase" "$G" airlight --g 0:0.5 --kmax 3
E 2 "--basis applies to a g range (--g LO:HI) only" "$G" airlight --basis slices
E 2 "--basis slices sizes its table by --tol: --size is not accepted with it" "$G" airlight --basis slices --g 0:0.5 --size 5x5
E 2 "-o: 'x' is not accepted" "$G" airlight --g 0:0.5 --size 5x4 -o x
E 2 "--kmax: '256' is not accepted: expected an integer in [0, 255]" "$G" airlight --kmax 256
E 2 "-o: 'x' is not accepted" "$G" airlight --kmax 255 -o x
E 2 "--tol: '1' is not accepted: expected a number in (0, 1)" "$G" airlight --tol 1
E 2 "--max: '1.0000001e6' is not accepted: expected a number in (0, 1e+06]" "$G" airlight --max 1.0000001e6
E 2 "-o: 'x' is not accepted" "$G" airlight --max 1e6 -o x
E 2 "--n: '10001' is not accepted: expected an integer in [1, 10000]" "$G" surface --n 10001
E 2 "-o: 'x' is not accepted" "$G" surface --n 10000 -o x
E 2 "--g: '-0.991:0' is not accepted: expected a number or LO:HI in [-0.99, 0.99]" "$G" airlight --g -0.991:0
E 2 "--g: '0.5:0.2' is not accepted: the range must be LO:HI with LO <= HI" "$G" airlight --g 0.5:0.2
E 2 "--g: '$(printf '%0130d' 0):0.5' is too long" "$G" airlight --g "$(printf '%0130d' 0):0.5"
E 2 "-o: 'x' is not accepted" "$G" airlight --g -0.99:0.99 -o x
E 1 "-o: cannot write '$tmp/nodir/a.exr': No such file or directory" "$G" airlight --size 5x4 -o "$tmp/nodir/a.exr"
mkdir d.exr
E 1 "-o: cannot write '$tmp/d.exr': Is a directory" "$G" airlight --size 5x4 -o "$tmp/d.exr"
[ -z "$(ls -A d.exr)" ] && ok || bad "a refused run wrote into d.exr"
E 2 "unknown command '--bogus'" "$G" --bogus
# nbt-gen alone builds the default tables; --quiet is its one option: the message names the other one
E 2 "nbt-gen: unknown option '--foo' (see 'nbt-gen --help')" "$G" --quiet --foo
E 2 "nbt-gen: unknown option '--foo' (see 'nbt-gen --help')" "$G" -q -q --foo
[ ! -e nbt-tables ] && ok || bad "a refused nbt-gen --quiet run made nbt-tables"

# ---- nbt-gen info
O "nbt-gen info" "$G" info --bogus hf.exr
E 2 "info: expected exactly one table file" "$G" info hf.exr hf.exr
E 2 "--at: '1,x' is not accepted: expected X,Y or X,Y,G (finite numbers)" "$G" info hf.exr --at 1,x
E 2 "--at: '1,2,3,4' is not accepted" "$G" info hf.exr --at 1,2,3,4
E 2 "--at: '1,inf' is not accepted" "$G" info hf.exr --at 1,inf

# ---- nbt-gen kernel
O "nbt-gen kernel" "$G" kernel --bogus
E 2 "kernel: unexpected argument 'extra'" "$G" kernel --B 0.1 extra
E 2 "--size: '1x4' is not accepted: expected WxH with 2 <= W, H <= 4096" "$G" kernel --B 0.1 --size 1x4 -o "$o/k.exr"
E 2 "--size: '4x4097' is not accepted" "$G" kernel --B 0.1 --size 4x4097 -o "$o/k.exr"
E 2 "-o: '$o/k.txt' is not accepted: the output must end in .exr" "$G" kernel --B 0.1 --size 2x4096 -o "$o/k.txt"
E 2 "--model: 'foo' is not accepted: moments" "$G" kernel --B 0.1 --model foo
E 2 "kernel: --B B (the phase function's spread, > 0) is required" "$G" kernel -o "$o/k.exr"
E 2 "--B: '1000.1' is not accepted: expected a number in (0, 1000]" "$G" kernel --B 1000.1 -o "$o/k.exr"
# a range of one value is no axis: LO = HI refused for each, naming it; a range just wider passes (then -o stops it)
E 2 "--tau: '0.5:0.5' is not accepted: the table's axis needs a range LO:HI with LO < HI" "$G" kernel --B 0.1 --tau 0.5:0.5 -o "$o/k.exr"
E 2 "--albedo: '0.5:0.5' is not accepted: the table's axis needs a range LO:HI with LO < HI" "$G" kernel --B 0.1 --albedo 0.5:0.5 -o "$o/k.exr"
E 2 "--albedo: '0.5' is not accepted" "$G" kernel --B 0.1 --albedo 0.5 -o "$o/k.exr"
E 2 "-o: '$o/k.txt' is not accepted" "$G" kernel --B 0.1 --tau 0.5:0.5000001 --albedo 0.5:0.5000001 -o "$o/k.txt"
E 2 "kernel: --correction applies to the moment kernel, not to --model fitted" "$G" kernel --B 0.1 --model fitted --correction corr.txt -o "$o/k.exr"
E 2 "kernel: --infinite and --beam-model apply to --model fitted only" "$G" kernel --B 0.1 --infinite -o "$o/k.exr"
E 2 "--beam-model: 'half.txt' holds no coefficients for the infinite geometry" "$G" kernel --B 0.1 --model fitted --beam-model half.txt --infinite -o "$o/k.exr"
E 2 "--beam-model: beam model 'corr.txt' line 1: expected 'half|infinite P0..P4'" "$G" kernel --B 0.1 --model fitted --beam-model corr.txt -o "$o/k.exr"
E 1 "-o: cannot write '$tmp/nodir/k.exr'" "$G" kernel --B 0.1 --size 5x4 -o "$tmp/nodir/k.exr"

# ---- nbt-gen scene: the file's lines, its required keys
printf 'kappa_t = 0.5\ndistance = 8\nairlight = maybe\n' >yn.scene
E 2 "yn.scene:3: airlight = 'maybe' is not accepted: yes or no" "$G" scene yn.scene -o "$o/t"
printf 'kappa_t = 0.5\ndistance 8\n' >noeq.scene
E 2 "noeq.scene:2: expected 'key = value', got 'distance 8'" "$G" scene noeq.scene -o "$o/t"
printf 'kappa_t = 0.5\ndistance = 0\n' >d0.scene
E 2 "d0.scene:2: distance = '0' is not accepted: the largest distance must be > 0" "$G" scene d0.scene -o "$o/t"
printf 'kappa_t = 0.5\nphase = iso\n' >nod.scene
E 2 "nod.scene: no 'distance = ...' line: kappa_t and distance are required" "$G" scene nod.scene -o "$o/t"
printf 'distance = 8\nphase = iso\n' >nokt.scene
E 2 "nokt.scene: no 'kappa_t = ...' line: kappa_t and distance are required" "$G" scene nokt.scene -o "$o/t"
printf 'kappa_t = 0.5\ndistance = 8\nphase = foo\n' >ph.scene
E 2 "ph.scene: phase: unknown phase 'foo'" "$G" scene ph.scene -o "$o/t"
# 16 Phong exponents are accepted (the file then misses distance), 17 are not
printf 'kappa_t = 0.5\nphong = 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17\n' >p16.scene
E 2 "p16.scene: no 'distance = ...' line" "$G" scene p16.scene -o "$o/t"
printf 'kappa_t = 0.5\nphong = 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18\n' >p17.scene
E 2 "p17.scene:2: phong: at most 16 Phong exponents" "$G" scene p17.scene -o "$o/t"
E 2 "scene: expected exactly one scene file" "$G" scene yn.scene noeq.scene
O "nbt-gen scene" "$G" scene --bogus yn.scene

# ---- nbt-fit kernel / model / phase (built with Ceres; without it test_fit.sh checks their refusal)
if "$F" kernel --help >/dev/null 2>&1; then
  O "nbt-fit kernel" "$F" kernel --bogus
  E 2 "kernel: give at least one photon-counting file (nbt-fit mc -o FILE)" "$F" kernel -o "$o/k.csv"
  E 2 "--loss: 'foo' is not accepted: none, huber or cauchy" "$F" kernel --loss foo x.csv
  E 2 "--weight: 'foo' is not accepted: stderr (statistical) or rms (the RMS metric)" "$F" kernel --weight foo x.csv
  for v in "--loss none" "--loss huber" "--loss cauchy" "--weight stderr" "--weight rms"; do   # accepted: no file is the error
    E 2 "kernel: give at least one photon-counting file" "$F" kernel $v -o "$o/k.csv"
  done
  E 2 "--correction and --apply exclude each other" "$F" kernel --correction "$o/c.txt" --apply b.txt x.csv
  E 2 "empty.csv: no data rows" "$F" kernel empty.csv -o "$o/k.csv"
  E 2 "badhdr.csv: expected the header z,r_lo,r_hi,psi,psi_stderr" "$F" kernel badhdr.csv -o "$o/k.csv"
  E 2 "uneven.csv: every plane must have the same number of bins" "$F" kernel uneven.csv -o "$o/k.csv"
  E 2 "split.csv: every plane must have the same number of bins" "$F" kernel split.csv -o "$o/k.csv"
  E 2 "late.csv line 1102: '1,5,5,1,0.1' is not accepted: expected z > 0, 0 <= r_lo < r_hi" "$F" kernel late.csv -o "$o/k.csv"
  printf '%s\r\n' $hdr 1,0,0.1,1,0.1 1,0.1,0.2,-1,0.1 >neg.csv   # CR LF line ends; a negative psi
  E 2 "neg.csv line 3: '1,0.1,0.2,-1,0.1' is not accepted" "$F" model neg.csv -o "$o/m.txt"
  E 2 "hf.exr: not a PSI table (nbt-fit mc -o FILE.exr)" "$F" kernel hf.exr -o "$o/k.csv"
  O "nbt-fit model" "$F" model --bogus
  E 2 "model: give at least one photon-counting file (nbt-fit mc -o FILE)" "$F" model -o "$o/m.txt"
  E 2 "model: --density applies to --apply only" "$F" model x.csv -o "$o/m.txt" --density d.txt
  E 2 "--ridge: '1000.5' is not accepted: expected a number in [0, 1000]" "$F" model --ridge 1000.5 x.csv -o "$o/m.txt"
  E 2 "--albedo: '1.01' is not accepted: expected a number in [0, 1]" "$F" model --albedo 1.01 ok.csv -o "$o/m.txt"
  E 2 "--sigma-t: '0' is not accepted: expected a number in (0, 1e+12]" "$F" model --sigma-t 0 ok.csv -o "$o/m.txt"
  E 2 "--B: '0' is not accepted: expected a number in (0, 1e+06]" "$F" model --B 0 ok.csv -o "$o/m.txt"
  E 2 "model: -o MODEL.txt is required" "$F" model --albedo 1 --sigma-t 1e12 --B 1e6 --ridge 1000 ok.csv
  E 2 "--density: badhdr.csv:1: density file: 'x,y' is not accepted" "$F" model --apply default --density badhdr.csv --albedo 0.9 --sigma-t 1 --B 0.1 ok.csv
  E 2 "uneven.csv: every plane must have the same number of bins" "$F" model uneven.csv -o "$o/m.txt"
  printf '%s\n' $hdr 1,0,0.1,0,0 1,0.1,0.2,0,0 2,0,0.1,0,0 2,0.1,0.2,0,0 >zero.csv   # psi = 0 everywhere
  E 2 "zero.csv: no photons counted: cannot fit" "$F" model --albedo 0.9 --sigma-t 1 --B 0.1 zero.csv -o "$o/m.txt"
O "nbt-fit phase" "$F" phase --bogus
E 2 "phase: unexpected argument 'extra'" "$F" phase --target iso --terms 2 extra
fi

# ---- nbt-fit mc
M="--albedo 0.9 --sigma-t 1 --B 0.1"
O "nbt-fit mc" "$F" mc --bogus
E 2 "--photons needs a value (see 'nbt-fit mc --help')" "$F" mc --albedo 0.9 --photons
E 2 "mc: unexpected argument 'extra'" "$F" mc $M --photons 100 -o "$o/x.csv" extra
E 2 "mc: --photons N is required (--albedo, --sigma-t and --photons are)" "$F" mc $M -o "$o/x.csv"
E 2 "mc: --albedo A is required" "$F" mc --sigma-t 1 --B 0.1 --photons 64 -o "$o/x.csv"
E 2 "mc: --sigma-t S is required" "$F" mc --albedo 0.9 --B 0.1 --photons 64 -o "$o/x.csv"
E 2 "--slab and --density exclude each other" "$F" mc $M --photons 100 --slab 1 --density d.txt
E 2 "--z-cut: '0' is not accepted: expected a number in (0, 1e+15]" "$F" mc $M --photons 100 --z-cut 0 -o "$o/x.csv"
E 2 "--r-max-scale: '0' is not accepted: expected a number in (0, 1e+06]" "$F" mc $M --photons 100 --r-max-scale 0 -o "$o/x.csv"
E 2 "--photons: '63' is not accepted: expected a number in [64, 1e+15]" "$F" mc $M --photons 63 -o "$o/x.csv"
E 2 "--estimator: 'both' is not accepted: analog or weighted" "$F" mc $M --photons 64 --estimator both -o "$o/x.csv"
E 1 "-o: cannot write '$tmp/nodir/x.csv': No such file or directory" "$F" mc $M --photons 64 --estimator analog -o "$tmp/nodir/x.csv"

# ---- nbt-fit screenmodel
O "nbt-fit screenmodel" "$F" screenmodel --bogus
E 2 "screenmodel: unexpected argument 'extra'" "$F" screenmodel extra
E 2 "--geometry: 'foo' is not accepted: expected inside, entering or inside,entering" "$F" screenmodel --geometry foo -o "$o/m.txt"
for v in inside,tide ,inside insideinside entering,; do
  E 2 "--geometry: '$v' is not accepted: expected inside, entering or inside,entering" "$F" screenmodel --geometry $v -o "$o/m.txt"
done
for v in inside entering inside,entering; do   # accepted: the run goes on to refuse --tau 1
  E 2 "--tau: " "$F" screenmodel --geometry $v --tau 1 -o "$o/m.txt"
done
E 2 "--phase and --g exclude each other" "$F" screenmodel --phase iso --g 0.3 -o "$o/m.txt"
E 2 "screenmodel: -o MODEL.txt is required (or --check MODEL.txt)" "$F" screenmodel
E 2 "screenmodel: --check writes nothing; drop -o" "$F" screenmodel --check default -o "$o/m.txt"
E 2 "--tau: '1' is not accepted: a model needs two or more depths" "$F" screenmodel --tau 1 -o "$o/m.txt"
E 2 "--phase: unknown phase 'foo'" "$F" screenmodel --phase foo -o "$o/m.txt"
E 2 "--check: screen model 'empty.csv' line 1: unknown line" "$F" screenmodel --check empty.csv
"$F" screenmodel --help | grep -q "^Usage: nbt-fit screenmodel" && ok || bad "screenmodel --help"
E 2 "--albedo: '0,0.5' is not accepted: expected increasing numbers in (0, 1)" "$F" screenmodel --albedo 0,0.5 -o "$o/m.txt"
E 2 "--albedo: '0.5,1' is not accepted" "$F" screenmodel --albedo 0.5,1 -o "$o/m.txt"
E 2 "--g: '0.5,0.5' is not accepted: expected increasing numbers in (-1, 1)" "$F" screenmodel --g 0.5,0.5 -o "$o/m.txt"
E 2 "--g: '0.5,0.3' is not accepted: expected increasing numbers in (-1, 1)" "$F" screenmodel --g 0.5,0.3 -o "$o/m.txt"
# at most 64 values in a list: 64 pass (the run then stops at --tau), 65 do not
l64=$(i=1; while [ $i -le 64 ]; do printf '0.%02d,' $i; i=$((i + 1)); done)
E 2 "--tau: '1' is not accepted" "$F" screenmodel --g "${l64%,}" --tau 1 -o "$o/m.txt"
E 2 "expected a comma-separated list of at most 64 numbers" "$F" screenmodel --g "${l64}0.99" --tau 1 -o "$o/m.txt"

# ---- nbt-scatter scene
O "nbt-scatter" "$S" scene --bogus
E 2 "--size needs a value (see 'nbt-scatter --help')" "$S" scene layers --size
E 2 "--size: '0x4' is not accepted: expected WxH with 1 <= W, H <= 16384" "$S" scene --size 0x4 -o "$o/s.exr" plane
E 2 "--size: '16385x4' is not accepted" "$S" scene --size 16385x4 -o "$o/s.exr" plane
E 2 "--size: '4x16385' is not accepted" "$S" scene --size 4x16385 -o "$o/s.exr" plane
E 2 "scene: -o OUT.exr is required" "$S" scene --size 16384x1 plane
E 2 "scene: -o OUT.exr is required" "$S" scene --size 1x16384 plane
E 2 "scene: name one scene: plane, step, layers, slant, blocks, lamps" "$S" scene --size 4x4 -o "$o/s.exr"
E 2 "scene: 'fog' is not accepted: expected one of plane, step" "$S" scene --size 4x4 -o "$o/s.exr" fog
E 1 "-o: cannot write '$tmp/nodir/s.exr'" "$S" scene --size 4x4 -o "$tmp/nodir/s.exr" plane
"$S" scene --size 7x5 -o in.exr plane >/dev/null 2>&1 && [ -s in.exr ] && ok || bad "nbt-scatter scene plane"

# ---- nbt-scatter: option checks before reading the input
SM="--fov-y 40 --sigma-t 0.1 --albedo 0.9 --B 0.01"
E 2 "--geometry: 'sideways' is not accepted: expected inside (the camera in the medium) or entering" "$S" in.exr -o "$o/o.exr" $SM --geometry sideways
[ $gl = 0 ] || E 2 "-o: 'x' is not accepted: the output is OpenEXR" "$S" in.exr --fov-y 40 --sigma-t 0.1 --albedo 0.9 --phase hg:g=0.5 --method elek --geometry entering -o x
"$S" --help | grep -q "^Usage: nbt-scatter IN.exr" && ok || bad "nbt-scatter --help"
# -o: lower-case .exr as in nbt-gen and nbt-fit (nbt-scatter alone took .EXR)
E 2 "-o: '$o/o.EXR' is not accepted: the output is OpenEXR and its name must end in .exr" "$S" in.exr -o "$o/o.EXR" $SM
E 2 "-o: '$o/o.EXR' is not accepted: the output must be a file name ending in .exr" "$G" airlight --phase iso -o "$o/o.EXR"
E 2 "--display-window: '0,0,3' is not accepted: expected X0,Y0,X1,Y1" "$S" in.exr -o "$o/o.exr" $SM --display-window 0,0,3
E 2 "--display-window: '3,0,2,3' is not accepted: X1 >= X0 and Y1 >= Y0" "$S" in.exr -o "$o/o.exr" $SM --display-window 3,0,2,3
E 2 "--display-window: '0,3,3,2' is not accepted: X1 >= X0 and Y1 >= Y0" "$S" in.exr -o "$o/o.exr" $SM --display-window 0,3,3,2
E 2 "--display-window: '0,0,1073741825,3' is not accepted" "$S" in.exr -o "$o/o.exr" $SM --display-window 0,0,1073741825,3
E 2 "--depth: 'curved' is not accepted: expected plane or ray" "$S" in.exr -o "$o/o.exr" $SM --depth curved
E 2 "--quantize: '1' is not accepted: expected 0 (exact: brute force when needed) or 2..4096" "$S" in.exr -o "$o/o.exr" $SM --quantize 1
E 2 "--quantize: '4097' is not accepted: expected an integer in [0, 4096]" "$S" in.exr -o "$o/o.exr" $SM --quantize 4097
E 2 "--tail: '0.11' is not accepted: expected a number in (0, 0.1]" "$S" in.exr -o "$o/o.exr" $SM --tail 0.11
E 2 "--cut: '0' is not accepted: expected a number in (0, 100]" "$S" in.exr -o "$o/o.exr" $SM --cut 0
E 2 "--eps: '100.1' is not accepted: expected a number in [0, 100]" "$S" in.exr -o "$o/o.exr" $SM --eps 100.1
E 2 "-o OUT.exr is required" "$S" in.exr $SM --tail 0.1 --cut 100 --eps 100 --quantize 2 --display-window 3,3,3,3
O "nbt-scatter" "$S" in.exr -o "$o/o.exr" $SM --bogus
E 2 "name one input render IN.exr" "$S" -o "$o/o.exr" $SM
E 2 "--fov-y DEG is required: the vertical field of view in (0, 180)" "$S" in.exr -o "$o/o.exr" --sigma-t 0.1 --albedo 0.9 --B 0.01
E 2 "--sigma-t X is required: the extinction coefficient, > 0 (or R,G,B)" "$S" in.exr -o "$o/o.exr" --fov-y 40 --albedo 0.9 --B 0.01
E 2 "--albedo A is required: in [0, 1] (or R,G,B)" "$S" in.exr -o "$o/o.exr" --fov-y 40 --sigma-t 0.1 --B 0.01
E 2 "--B and --dtheta: give one phase width" "$S" in.exr -o "$o/o.exr" $SM --dtheta 2
E 2 "--kernel fitted needs --phase SPEC" "$S" in.exr -o "$o/o.exr" $SM --kernel fitted
E 2 "--model: a fitted model serves --phase with --kernel fitted or elek" "$S" in.exr -o "$o/o.exr" $SM --model m.txt
[ $gl = 0 ] || E 2 "--kernel elek: elek's Gaussian comes with --method elek" "$S" in.exr -o "$o/o.exr" --fov-y 40 --sigma-t 0.1 --albedo 0.9 --phase hg:g=0.5 --method shinya --kernel elek
[ $gl = 0 ] || E 2 "--method shinya: the GL methods take one medium for all channels" "$S" in.exr -o "$o/o.exr" --fov-y 40 --sigma-t 0.1,0.2,0.3 --albedo 0.9 --B 0.01 --method shinya
[ $gl = 0 ] || E 2 "--quantize belongs to the CPU references" "$S" in.exr -o "$o/o.exr" $SM --method shinya --quantize 4
E 2 "--method path: --quantize, --density and --compare belong to the screen-space methods" "$S" in.exr -o "$o/o.exr" $SM --method path --quantize 4
E 2 "--density: heterogeneous media take a Gaussian phase (--B) and one medium for all channels" "$S" in.exr -o "$o/o.exr" --fov-y 40 --sigma-t 0.1 --albedo 0.9 --phase hg:g=0.5 --density d.vdb
E 2 "--quantize and --density: per-pixel kernels have no layers to quantise" "$S" in.exr -o "$o/o.exr" $SM --method ref-a --density d.vdb --quantize 4
E 2 "--kernel corrected and --correction FILE go together" "$S" in.exr -o "$o/o.exr" $SM --kernel corrected
E 2 "--phase: give one phase, or three (R, G, B in that order)" "$S" in.exr -o "$o/o.exr" --fov-y 40 --sigma-t 0.1 --albedo 0.9 --phase iso --phase iso --phase iso --phase iso
E 2 "--sigma-t: '$(printf '%040d' 0)...' is too long" "$S" in.exr -o "$o/o.exr" --fov-y 40 --sigma-t "$(printf '%0300d' 1)" --albedo 0.9 --B 0.01
# --density: the ray-march camera and the method checked before the input and the grid are read (the
# camera check came after reading both, elek's after the per-pixel kernels were computed and printed);
# the accepted view (0,1,0) x up (1,0,0) has only a z component
DM="--fov-y 40 --sigma-t 0.5 --albedo 0.9 --B 0.01 --density c1.raw"
E 2 "--look-at 0,0,0 from --camera 0,0,0: the view direction must be non-zero and not parallel to --up 0,1,0" "$S" none.exr -o "$o/o.exr" $DM --method ref-a --look-at 0,0,0
E 2 "--look-at 0,2,0 from --camera 0,1,0: the view direction must be non-zero and not parallel to --up 0,1,0" "$S" none.exr -o "$o/o.exr" $DM --method ref-a --camera 0,1,0 --look-at 0,2,0
E 2 "none.exr: cannot open" "$S" none.exr -o "$o/o.exr" $DM --method ref-a --camera 0,1,0 --look-at 0,2,0 --up 1,0,0
[ $gl = 0 ] || E 2 "--method elek: Elek's W(s) is for homogeneous media, not --density" "$S" none.exr -o "$o/o.exr" $DM --method elek
# the grid's camera and march options without a grid were ignored silently: refused, naming the first given
HM="--fov-y 40 --sigma-t 0.5 --albedo 0.9 --B 0.01"
E 2 "--camera places or marches a --density grid; without --density it would be ignored" "$S" in.exr -o "$o/o.exr" $HM --camera 1,2,3 --up 0,0,1
E 2 "--look-at places or marches" "$S" in.exr -o "$o/o.exr" $HM --look-at 0,0,1
E 2 "--up places or marches" "$S" in.exr -o "$o/o.exr" $HM --up 1,0,0 --camera 0,0,0
E 2 "--grid places or marches" "$S" in.exr -o "$o/o.exr" $HM --grid density
E 2 "--step places or marches" "$S" in.exr -o "$o/o.exr" $HM --step 0.1
"$MK" c1.raw grid 1 >/dev/null 2>&1 && "$S" scene --size 8x6 --overscan 0.25 -o bo.exr blocks >/dev/null 2>&1 &&
  [ -s c1.raw ] && [ -s bo.exr ] && ok || bad "a density grid (tests/mkexr) and an overscanned render"
E 2 "--density with an overscanned render (data window larger than the display window): not supported" "$S" bo.exr -o "$o/o.exr" $DM --method ref-a
# the input read after the checks: a missing, a garbage and a truncated EXR
E 2 "none.exr: cannot open: No such file or directory" "$S" none.exr -o "$o/o.exr" $SM
head -c 100 in.exr >trunc.exr
E 2 "trunc.exr" "$S" trunc.exr -o "$o/o.exr" $SM --method ref-a
E 2 "badhdr.csv" "$S" badhdr.csv -o "$o/o.exr" $SM --method ref-a
E 2 "--model: " "$S" in.exr -o "$o/o.exr" --fov-y 40 --sigma-t 0.1 --albedo 0.9 --phase hg:g=0.5 --model empty.csv
E 2 "--correction: " "$S" in.exr -o "$o/o.exr" $SM --method ref-a --kernel corrected --correction empty.csv
E 2 "--compare: " "$S" in.exr -o "$o/o.exr" $SM --method ref-a --compare none.exr
E 2 "--compare: in.exr has no nbt.sigma_t attribute: the reference must be an nbt-scatter output" "$S" in.exr -o "$o/o.exr" $SM --method ref-a --compare in.exr
E 2 "--phase: the kernel model covers HG phases with g in [0, 0.95], not hg:g=-0.5" "$S" in.exr -o "$o/o.exr" --fov-y 40 --sigma-t 0.1 --albedo 0.9 --phase hg:g=-0.5

# ---- nbt-gen info: a point outside the table is clamped, with a warning naming it
"$G" info hf.exr --at 20,0.5 >/dev/null 2>err && grep -qF "warning: (20, 0.5) lies outside the table" err && ok || bad "info --at outside: $(cat err)"
"$G" info js.exr --at 1,1,0.7 >/dev/null 2>err && grep -qF "g = 0.7 lies outside the table; clamped to its edge" err && ok || bad "info --at g outside: $(cat err)"
"$G" info js.exr --at 1,1,0.5 >/dev/null 2>err && [ ! -s err ] && ok || bad "info --at g = 0.5 (the edge): $(cat err)"

# ---- writes that fail after the checks passed: a file size limit of 0 (ulimit -f; SIGXFSZ
# ignored, so a write fails with EFBIG). stderr and stdout go to a pipe, which the limit does
# not touch. X TEXT CMD...: exit 1, TEXT on stderr, nothing left in $o
X() {
  _t=$1; shift
  _r=$(cd "$o" && sh -c 'trap "" XFSZ; ulimit -f 0 || exit 99; "$@" 2>&1 >/dev/null; echo "exit $?"' sh "$@")
  [ "$(echo "$_r" | tail -n 1)" = "exit 1" ] && echo "$_r" | grep -qF -- "$_t" && ok || bad "$* under ulimit -f 0: $_r"
  left "$*"
}
X "nbt-gen: cannot write 'k.exr'" "$G" kernel --B 0.1 --size 5x4 -o k.exr
X "nbt-gen: cannot write 'k.exr'" "$G" kernel --B 0.1 --size 5x4 --model fitted -o k.exr
X "nbt-gen: cannot write 'a_k0-3.exr'" "$G" airlight --kmax 7 --size 5x4 --no-preview -o a.exr
X "nbt-gen: cannot write 'a.exr'" "$G" surface --phase iso --size 5x4 -o a.exr
# with --quiet the failure is the whole of stderr: one line (libpng's own "libpng error: Write Error"
# lines for the previews were printed beside it)
for c in "airlight --kmax 7" "surface --phase iso"; do
  _r=$(cd "$o" && sh -c 'trap "" XFSZ; ulimit -f 0 || exit 99; "$@" 2>&1 >/dev/null; echo "exit $?"' sh "$G" $c --size 5x4 --quiet -o a.exr)
  case $_r in "nbt-gen: cannot write 'a"*".exr'
exit 1") ok ;; *) bad "$c --quiet under ulimit -f 0: $_r" ;; esac
  left "$c --quiet under ulimit -f 0"
done
X "nbt-fit: cannot write 'm.csv': File too large" "$F" mc --albedo 0.9 --sigma-t 1 --B 0.1 --photons 1000 -o m.csv
X "nbt-fit: cannot write 'm.exr'" "$F" mc --albedo 0.9 --sigma-t 1 --B 0.1 --photons 1000 -o m.exr
"$F" kernel --help >/dev/null 2>&1 && X "nbt-fit: cannot write 'p.txt': File too large" "$F" phase --target hg:g=0.5 --terms 2 -o p.txt
X "nbt-scatter: cannot write the preview 'o.png'" "$S" "$tmp/in.exr" -o o.exr $SM --method ref-a
X "nbt-scatter: s.exr: cannot write OpenEXR data" "$S" scene --size 7x5 -o s.exr plane

# ---- nbt-demo (when built with GL): --width 16..4096, both ends; --version
if [ -n "$D" ]; then
  E 2 "nbt-demo: --width 15 is not accepted: an integer 16..4096" "$D" "$o/d.png" --width 15
  E 2 "nbt-demo: --width 4097 is not accepted: an integer 16..4096" "$D" "$o/d.png" --width 4097
  E 2 "nbt-demo: '$o/d.exr' is not accepted: the output must be a file name ending in .png" "$D" "$o/d.exr" --width 4096
  E 2 "nbt-demo: '$o/d.exr' is not accepted" "$D" "$o/d.exr" --width 16
  # the picture cannot be written (ulimit -f 0, after the rendering): one line naming it and why, no
  # rendering report (it said the picture was made), no temporary left
  _r=$(cd "$o" && sh -c 'trap "" XFSZ; ulimit -f 0 || exit 99; ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0 "$@" 2>&1 >/dev/null; echo "exit $?"' sh "$D" d.png --width 16)
  [ "$_r" = "nbt-demo: cannot write 'd.png': File too large
exit 1" ] && ok || bad "nbt-demo under ulimit -f 0: $_r"
  left "nbt-demo under ulimit -f 0"
  [ "$("$D" --version 2>&1)" = "nbt-demo (nbt) $("$G" --version | sed 's/.* //')" ] && ok || bad "nbt-demo --version: $("$D" --version 2>&1)"
fi

ls -A "$tmp" | grep -v -e '^o$' -e '^d.exr$' -e '\.exr$' -e '\.csv$' -e '\.scene$' -e '^corr.txt$' -e '^stray$' -e '^half.txt$' -e '^c1.raw$' -e '^out$' -e '^words$' -e '^err$' >"$tmp/stray"
[ ! -s "$tmp/stray" ] && ok || bad "files left in the working directory: $(cat "$tmp/stray")"
finish
