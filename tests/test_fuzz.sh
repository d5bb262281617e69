#!/bin/sh
# tests/test_fuzz.sh: the parsers under fuzzing (tests/fuzz_parsers.c: density,
# phase SPEC, phase table, sum of Gaussians, CSV, table and image EXR, kernel
# correction, CLI numbers). The committed seed corpus is replayed, then
# NBT_FUZZ_SECONDS (default 20) of fuzzing: libFuzzer with ASan and UBSan when
# configure found clang's libFuzzer (NBT_FUZZER), else the harness's own
# mutation driver. A crash, hang (> 10 s on one input), leak or failed check
# inside the harness fails the test; the run's executions are printed.
. "${top_srcdir:-.}/tests/testlib.sh"
T=${NBT_FUZZ_SECONDS:-20}
corpus=${NBT_FUZZ_CORPUS:-${top_srcdir:-.}/tests/fuzz/corpus}
replay=${NBT_FUZZ_REPLAY:-./tests/fuzz_replay}

n=$(ls "$corpus" | wc -l)
[ "$n" -ge 9 ] && ok || bad "seed corpus $corpus has $n files (one or more per reader expected)"
"$replay" "$corpus" >"$tmp/replay" 2>&1 && ok || bad "corpus replay: $(tail -n 20 "$tmp/replay")"
cat "$tmp/replay"

if [ -n "${NBT_FUZZER:-}" ]; then
  [ -x "$NBT_FUZZER" ] && ok || bad "libFuzzer harness $NBT_FUZZER not built"
  mkdir "$tmp/corpus" && cp "$corpus"/* "$tmp/corpus/"
  # new inputs go to the scratch copy; the committed corpus stays as it is
  ASAN_OPTIONS=${ASAN_OPTIONS:-detect_leaks=1} "$NBT_FUZZER" -max_total_time="$T" -timeout=10 -rss_limit_mb=2048 \
    -max_len=4096 -print_final_stats=1 -artifact_prefix="$tmp/" "$tmp/corpus" >"$tmp/fuzz" 2>&1
  rc=$?
  if [ $rc -eq 0 ]; then ok; else
    bad "libFuzzer found a failing input (rc $rc): $(grep -m 5 -E 'ERROR|SUMMARY|Test unit written' "$tmp/fuzz")"
    for a in "$tmp"/crash-* "$tmp"/timeout-* "$tmp"/leak-*; do [ -f "$a" ] && { echo "input ($a):"; od -c "$a" | head -20; }; done
  fi
  runs=$(sed -n 's/^stat::number_of_executed_units: *//p' "$tmp/fuzz")
  echo "libFuzzer: ${runs:-?} executions in $T s, corpus $n -> $(ls "$tmp/corpus" | wc -l) inputs"
  [ -n "$runs" ] && [ "$runs" -gt 100 ] && ok || bad "libFuzzer ran ${runs:-no} inputs: $(tail -n 5 "$tmp/fuzz")"
else
  echo "libFuzzer not configured (no clang with -fsanitize=fuzzer): fuzzing with the harness's mutation driver"
  "$replay" -t "$T" -s 2385 "$corpus" >"$tmp/fuzz" 2>&1 && ok || bad "mutation driver: $(tail -n 20 "$tmp/fuzz")"
  cat "$tmp/fuzz"
fi
finish
