# tests/testlib.sh: the harness of the command-line tests (sourced).
# ok / bad DESCRIPTION count checks; expect_usage DESCRIPTION PATTERN CMD...
# asserts exit status 2 and one line on stderr matching PATTERN; expect_fail
# DESCRIPTION PATTERN CMD... asserts exit status 1, one line on stderr matching
# PATTERN and nothing on stdout, within 10 s (a check made before the work);
# close A B TOL
# DESCRIPTION compares numbers (and fails unless both are numbers); finish prints "N passed, M failed".
pass=0; fail=0
ok()  { pass=$((pass + 1)); }
bad() { fail=$((fail + 1)); echo "FAIL: $*"; }
tmp=$(mktemp -d /tmp/nbt-test.XXXXXX)
trap 'rm -rf "$tmp"' EXIT
abspath() { case $1 in /*) echo "$1" ;; *) echo "$(pwd)/$1" ;; esac; }
expect_usage() {
  d=$1; pat=$2; shift 2
  "$@" >"$tmp/out" 2>"$tmp/err"; rc=$?
  if [ $rc -eq 2 ] && [ "$(wc -l <"$tmp/err")" -eq 1 ] && grep -q -- "$pat" "$tmp/err"; then ok
  else bad "$d: rc=$rc, stderr: $(cat "$tmp/err")"; fi
}
expect_fail() {
  d=$1; pat=$2; shift 2
  timeout 10 "$@" >"$tmp/out" 2>"$tmp/err"; rc=$?
  if [ $rc -eq 1 ] && [ "$(wc -l <"$tmp/err")" -eq 1 ] && grep -q -- "$pat" "$tmp/err" && [ ! -s "$tmp/out" ]; then ok
  else bad "$d: rc=$rc, stderr: $(cat "$tmp/err"), stdout: $(head -c 300 "$tmp/out")"; fi
}
close() {
  # both must be numbers (awk would read an empty or garbled output as 0)
  if awk -v a="$1" -v b="$2" -v t="$3" 'BEGIN { n = "^[-+]?([0-9]+[.]?[0-9]*|[.][0-9]+)([eE][-+]?[0-9]+)?$";
      if (a !~ n || b !~ n) exit 1; d = a - b; if (d < 0) d = -d; s = b < 0 ? -b : b; exit !(d <= t * s) }'
  then ok; else bad "$4: $1 vs $2 (rel tol $3)"; fi
}
finish() {
  echo "$pass passed, $fail failed"
  [ $fail -eq 0 ]
}
