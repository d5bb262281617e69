#!/bin/sh
# tests/test_python.sh: the nbt Python package (python/nbt, ctypes over the
# build tree's libnbt) against libnbt's own results (tests/pyref), bit for
# bit, plus closed forms and bad input (tests/test_python.py).
. "${top_srcdir:-.}/tests/testlib.sh"
PY=${NBT_PYTHON:-/usr/bin/python3}
REF=$(abspath "${NBT_PYREF:-./tests/pyref}")
if ! "$PY" -c 'import numpy' 2>/dev/null; then
  echo "SKIP: $PY cannot import numpy (Debian: apt-get install python3-numpy); the nbt package needs it"
  exit 77
fi
lib=$(abspath "${top_builddir:-.}/libnbt/.libs/libnbt.so.0")
[ -f "$lib" ] || { echo "FAIL: $lib not built"; exit 1; }
# a sanitizer build (--enable-sanitizers): the interpreter is not instrumented, so ASan's runtime must be
# loaded first, and the interpreter's own leaks are not libnbt's
asan=$(ldd "$lib" 2>/dev/null | awk '/libasan/ { print $3 }')
if [ -n "$asan" ]; then
  LD_PRELOAD=$asan; export LD_PRELOAD
  ASAN_OPTIONS=${ASAN_OPTIONS:+$ASAN_OPTIONS:}detect_leaks=0; export ASAN_OPTIONS
fi
"$REF" >"$tmp/ref" || { echo "FAIL: tests/pyref"; exit 1; }
NBT_LIBRARY=$lib PYTHONPATH="${top_srcdir:-.}/python" "$PY" "${top_srcdir:-.}/tests/test_python.py" "$tmp/ref" && ok ||
  bad "tests/test_python.py"
# the loader: a wrong NBT_LIBRARY is reported with the path tried
NBT_LIBRARY=$tmp/none.so PYTHONPATH="${top_srcdir:-.}/python" "$PY" -c 'import nbt' 2>"$tmp/err" && bad "bad NBT_LIBRARY imports" ||
  { grep -q "NBT_LIBRARY" "$tmp/err" && grep -q "none.so" "$tmp/err" && ok || bad "bad NBT_LIBRARY message: $(cat "$tmp/err")"; }
# without NBT_LIBRARY the package finds the build tree's libnbt (in-tree builds; or an installed one)
[ -d "${top_srcdir:-.}/libnbt/.libs" ] && PYTHONPATH="${top_srcdir:-.}/python" "$PY" -c 'import nbt; print(nbt.library_path)' >"$tmp/out" 2>&1 && ok ||
  bad "import nbt without NBT_LIBRARY: $(cat "$tmp/out")"
true
echo "$pass passed, $fail failed"
[ "$fail" -eq 0 ]
