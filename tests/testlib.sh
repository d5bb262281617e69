# tests/testlib.sh: the harness of the command-line tests (sourced).
# ok / bad DESCRIPTION count checks; expect_usage DESCRIPTION PATTERN CMD...
# asserts exit status 2 and one line on stderr matching PATTERN; expect_fail
# DESCRIPTION PATTERN CMD... asserts exit status 1, one line on stderr matching
# PATTERN and nothing on stdout, within 10 s (a check made before the work);
# close A B TOL
# DESCRIPTION compares numbers (and fails unless both are numbers); words SPEC CMD... and fwords SPEC FILE
# (below) read a program's result line; finish prints "N passed, M failed".
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
# words SPEC CMD...: run CMD and set w to its result line, where SPEC is N (CMD
# prints exactly one line, of N words) or LABEL:N (the one line whose first word is LABEL, N words). When CMD
# exits non-zero or its output does not match, count a failure and leave w empty: the checks that read w
# cannot rescue the test (awk reads an empty field as 0, which passes any '< bound').
# fwords SPEC FILE: the same for a file already written (its writer's exit status checked by the caller).
fwords() {
  w=$(awk -v s="$1" 'BEGIN { n = split(s, p, ":"); lab = n == 2 ? p[1] : ""; nw = p[n] }
    lab == "" || $1 == lab { k++; l = $0; f = NF } END { if (k != 1 || f != nw || (lab == "" && NR != 1)) exit 1; print l }' "$2") ||
    { bad "expected one line of $1 words in $2: $(head -c 300 "$2")"; w=; }
}
words() {
  _s=$1; shift
  if "$@" >"$tmp/words"; then fwords "$_s" "$tmp/words"
  else bad "exit status $? from: $* (stdout: $(head -c 300 "$tmp/words"))"; w=; fi
  rm -f "$tmp/words"   # tests list what is left in $tmp
}
finish() {
  echo "$pass passed, $fail failed"
  [ $fail -eq 0 ]
}
