#!/bin/sh
# tests/timelimit.sh: the per-test time limit (make check's LOG_COMPILER), so a
# test that hangs fails with a message instead of stalling CI. The limit is
# NBT_TEST_TIMEOUT seconds (default 300: the slowest test takes about 60 s on a
# shared 2-core machine, several times that under ASan). timeout(1) signals
# the whole process group, so programs a shell test started stop too.
limit=${NBT_TEST_TIMEOUT:-300}
timeout -k 10 "$limit" "$@"
rc=$?
if [ $rc -eq 124 ] || [ $rc -eq 137 ]; then
  echo "FAIL: $* did not finish within the per-test limit of $limit s (NBT_TEST_TIMEOUT)"
  exit 1
fi
exit $rc
