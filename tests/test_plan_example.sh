#!/bin/sh
# tests/test_plan_example.sh: runs examples/plan_example (the planner from C)
# into a temporary directory; its EXR files must read back with the header
# its printed plan promises, and meet the scene's per-table target.
. "${top_srcdir:-.}/tests/testlib.sh"
"$NBT_PLAN_EXAMPLE" "$tmp" >"$tmp/out" 2>"$tmp/err" && ok || bad "plan_example failed: $(cat "$tmp/err")"
# one line per set (H and J1), each with a measured error below the target
target=$(sed -n 's/.*per-table target \([0-9.e+-]*\) .*/\1/p' "$tmp/out")
for s in H J1; do
  # set, packs, size, mapping, v mapping, target, amplification, |, measured error, ratio
  fwords "$s:10" "$tmp/out"; [ -n "$w" ] || continue
  set -- $w
  size=$3; err=$9
  awk -v e="$err" -v t="$target" 'BEGIN { exit !(e > 0 && e <= t) }' && ok || bad "$s: measured $err vs target $target"
  # the file holds what the plan says: size and kind
  f=$(ls "$tmp"/${s}_k0-*.exr 2>/dev/null | head -1)
  [ -n "$f" ] && "$NBT_GEN" info "$f" >"$tmp/info" 2>&1 && ok || { bad "$s: no readable EXR"; continue; }
  n=${size%%x*}
  grep -q "^axis0 .* $n nodes" "$tmp/info" && ok || bad "$s: $f is not $size: $(cat "$tmp/info")"
done
finish
