#!/bin/sh
# tests/test_install_examples.sh: make install DESTDIR=<temporary> of this
# build, then the installed examples built with the installed Makefile
# (PREFIX/share/nbt/examples/Makefile) against the installed pkg-config files
# only (PKG_CONFIG_PATH and PKG_CONFIG_SYSROOT_DIR point into the staged
# tree), linked to the staged libnbt, and run: plan_example must meet its
# scene's targets, airlight_example's two methods must agree, demo_fog (in
# builds with GL) must write its PNG. The installed documents may name only
# installed files: every PREFIX/share/nbt/... path they give exists in the
# install, and they do not send the reader to DESIGN.md or nbt_gl.c (not
# installed), nor to doc/examples/default.scene, doc/kernelmodel.sh,
# examples/plan_example.c or examples/demo_fog.c without saying where they
# are installed or that they are in the source tree.
. "${top_srcdir:-.}/tests/testlib.sh"
MAKE_CMD=${MAKE:-make}
for t in pkg-config cc; do
  command -v $t >/dev/null 2>&1 || { echo "SKIP: $t is not installed"; exit 77; }
done
dest=$tmp/dest
# a make of its own (not the jobserver of the make check that runs this test)
env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL $MAKE_CMD -C "${top_builddir:-.}" install DESTDIR="$dest" >"$tmp/install.log" 2>&1 && ok ||
  { bad "make install DESTDIR: $(tail -5 "$tmp/install.log")"; finish; exit 1; }
pc=$(find "$dest" -name nbt.pc | head -1)
ex=$(find "$dest" -path '*/share/nbt/examples/Makefile' | head -1)
lib=$(find "$dest" -name 'libnbt.so.0' | head -1)
[ -n "$pc" ] && [ -n "$ex" ] && [ -n "$lib" ] && ok || { bad "installed: nbt.pc '$pc', examples/Makefile '$ex', libnbt.so.0 '$lib'"; finish; exit 1; }
exdir=$(dirname "$ex")
share=$(dirname "$exdir")               # DEST/PREFIX/share/nbt
prefix=${share%/share/nbt}; prefix=${prefix#"$dest"}
for f in plan_example.c airlight_example.c default.scene demo_fog.c egl_headless.c egl_headless.h font5x7.h; do
  [ -f "$exdir/$f" ] && ok || bad "$f is not installed in $exdir"
done
[ -x "$share/scripts/kernelmodel.sh" ] && ok || bad "kernelmodel.sh is not installed in $share/scripts"

# build in a directory of its own with the installed Makefile; the flags come from the staged .pc files
export PKG_CONFIG_PATH=$(dirname "$pc") PKG_CONFIG_SYSROOT_DIR=$dest
pkg-config --cflags nbt | grep -q -- "-I$dest" && ok || bad "pkg-config --cflags nbt does not point into $dest: $(pkg-config --cflags nbt)"
mkdir "$tmp/build"
(cd "$tmp/build" && env -u MAKEFLAGS -u MFLAGS -u MAKELEVEL $MAKE_CMD -f "$ex" >"$tmp/build.log" 2>&1) && ok ||
  bad "make -f $ex: $(tail -5 "$tmp/build.log")"
export LD_LIBRARY_PATH=$(dirname "$lib")
ldd "$tmp/build/plan_example" 2>&1 | grep "libnbt.so.0 => $dest" >/dev/null && ok ||
  bad "plan_example does not load the staged libnbt: $(ldd "$tmp/build/plan_example" 2>&1 | grep libnbt)"
# the plan example: each set's measured error within the scene's target, its files written
mkdir "$tmp/tables"
"$tmp/build/plan_example" "$tmp/tables" >"$tmp/out" 2>"$tmp/err" && ok || bad "plan_example failed: $(cat "$tmp/err")"
target=$(sed -n 's/.*per-table target \([0-9.e+-]*\) .*/\1/p' "$tmp/out")
for s in H J1; do
  # set, packs, size, mapping, v mapping, target, amplification, |, measured error, ratio
  fwords "$s:10" "$tmp/out"; [ -n "$w" ] || continue
  set -- $w
  awk -v e="$9" -v t="$target" 'BEGIN { exit !(e > 0 && e <= t) }' && ok || bad "$s: measured $9 vs target $target"
  ls "$tmp/tables"/${s}_k0-*.exr >/dev/null 2>&1 && ok || bad "$s: no table file"
done
"$tmp/build/airlight_example" >"$tmp/out" 2>&1 && ok || bad "airlight_example: $(cat "$tmp/out")"
if [ -n "$(find "$dest" -name nbt-gl.pc)" ]; then
  # the GL demo at 16 px per panel on Mesa's software rasteriser: a PNG (6 x 16 by 2 x 16 plus labels)
  (cd "$tmp/build" && ./demo_fog "$tmp/demo.png" --width 16 >"$tmp/out" 2>&1) && [ -s "$tmp/demo.png" ] &&
    od -An -c -N4 "$tmp/demo.png" | grep -q "P   N   G" && ok || bad "demo_fog: $(tail -3 "$tmp/out")"
else
  echo "no nbt-gl in this build: demo_fog not built"
fi

# the installed documents name installed files
docs=$(find "$dest" \( -name '*.md' -o -name '*.1' -o -name '*.h' \) -type f)
echo "installed documents checked: $(echo $docs | wc -w); PREFIX/share/nbt paths they name: $(cat $docs | grep -c -o -E '(PREFIX|/usr/local)/share/nbt/')"
for p in $(cat $docs | grep -o -E '(PREFIX|/usr/local)/share/nbt/[A-Za-z0-9_./-]*[A-Za-z0-9_]' | sort -u); do
  rel=${p#*/share/nbt/}
  [ -e "$share/$rel" ] && ok || bad "the docs name $p, which is not installed"
done
if grep -l -E 'DESIGN\.md|nbt_gl\.c' $docs >"$tmp/hits"; then bad "installed docs name files not installed: $(cat "$tmp/hits")"; else ok; fi
# (per paragraph: a mention must come with where the file is)
awk 'BEGIN { RS = "" } /doc\/examples\/default\.scene|doc\/kernelmodel\.sh|examples\/plan_example\.c|examples\/demo_fog\.c/ &&
     !/source tree|PREFIX\/share|\/usr\/local\/share/ { print FILENAME ": " substr($0, 1, 200) }' $docs >"$tmp/hits"
[ -s "$tmp/hits" ] && bad "installed docs send the reader to the source tree: $(cat "$tmp/hits")" || ok
finish
