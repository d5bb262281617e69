#!/bin/sh
# tests/test_man.sh: the hand-written man pages in doc/ render without a single
# groff warning (-ww) or man(1) warning, and each names every option that its
# program's --help (and every command's --help) prints.
. "${top_srcdir:-.}/tests/testlib.sh"
src=${top_srcdir:-.}
NBT_GEN=$(abspath "${NBT_GEN:-./nbt-gen}")
NBT_FIT=$(abspath "${NBT_FIT:-./nbt-fit}")
NBT_SCATTER=$(abspath "${NBT_SCATTER:-./nbt-scatter}")

for page in nbt-gen nbt-fit nbt-scatter nbt-demo; do
  f=$src/doc/$page.1
  [ -s "$f" ] && ok || { bad "$f missing"; continue; }
  groff -ww -z -man "$f" >"$tmp/gw" 2>&1
  [ $? -eq 0 ] && [ ! -s "$tmp/gw" ] && ok || bad "$page.1: groff -ww: $(cat "$tmp/gw")"
  if command -v man >/dev/null 2>&1; then
    MANWIDTH=80 man --warnings -l "$f" >"$tmp/txt" 2>"$tmp/mw"
    [ $? -eq 0 ] && [ ! -s "$tmp/mw" ] && grep -q "^NAME" "$tmp/txt" && ok || bad "$page.1: man -l: $(cat "$tmp/mw")"
  fi
done

# options: long ones (--word) and single-letter ones followed by a blank, comma or ]
opts_of() {
  grep -oE -e '--[A-Za-z][A-Za-z0-9-]*' -e '(^|[ [(|])-[A-Za-z]([ ,]|]|$)' | sed -e 's/^[ [(|]//' -e 's/[ ,]$//' -e 's/]$//' | sort -u
}
# the roff source with \- as -, font escapes and zero-width \& removed
plain() { sed -e 's/\\-/-/g' -e 's/\\f[BIRP]//g' -e 's/\\&//g' "$1"; }
check_page() {
  page=$1; min=$2; shift 2
  plain "$src/doc/$page.1" >"$tmp/src"
  n=0
  for o in $(cat "$tmp/opts"); do
    n=$((n + 1))
    grep -qE -e "(^|[^A-Za-z0-9-])$o([^A-Za-z0-9-]|\$)" "$tmp/src" && ok || bad "$page.1 does not name $o (in $* --help)"
  done
  [ $n -ge $min ] && ok || bad "$page: only $n options found in --help (the extraction is broken)"
}
{ "$NBT_GEN" --help; for c in airlight surface scene eval info kernel; do "$NBT_GEN" $c --help; done; } | opts_of >"$tmp/opts"
check_page nbt-gen 30 nbt-gen
# kernel and phase exist only in builds with Ceres; their --help fails otherwise
{ "$NBT_FIT" --help; for c in mc kernel phase model; do "$NBT_FIT" $c --help 2>/dev/null; done; } | opts_of >"$tmp/opts"
check_page nbt-fit 15 nbt-fit
"$NBT_SCATTER" --help | opts_of >"$tmp/opts"
check_page nbt-scatter 20 nbt-scatter
if [ -n "${NBT_DEMO:-}" ]; then
  "$NBT_DEMO" --help | opts_of >"$tmp/opts"
  check_page nbt-demo 1 nbt-demo
fi
finish
