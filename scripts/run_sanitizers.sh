#!/usr/bin/env bash
# The core's unit tests (test_core: test/unit/) and the tools' tests (test_tools: test/tools/),
# built and run here only, under AddressSanitizer + UndefinedBehaviorSanitizer, and every
# reader's fuzz target for FUZZ_SECONDS (default 12) from its committed corpus (test/fuzz/corpus/).
# Whole sequences (test/sequences/) and the ROS tests run in the release build
# (scripts/run_tests.sh). Builds in build/sanitize (plain CMake, no ROS). Results go to RESULTS_DIR
# (default build/sanitize/results) as JUnit XML, which run_tests.sh counts.
#   scripts/run_sanitizers.sh
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
build="$repo/build/sanitize"
results="${RESULTS_DIR:-$build/results}"
seconds="${FUZZ_SECONDS:-12}"
# Ninja, as the release build (scripts/build.sh); a folder configured by make is configured again.
if [ -f "$build/CMakeCache.txt" ] && ! grep -q "^CMAKE_GENERATOR:INTERNAL=Ninja$" "$build/CMakeCache.txt"; then
  rm -rf "$build"
fi
mkdir -p "$build" "$results"
export PATH="/usr/bin:$PATH"
# Any report is a failure; leaks are checked too.
export ASAN_OPTIONS="abort_on_error=1:detect_leaks=1"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"

junit() {  # junit NAME PASSED(0/1) MESSAGE
  local failure=""
  [ "$2" = 1 ] || failure="<failure message=\"$(printf '%s' "$3" | sed 's/&/\&amp;/g; s/</\&lt;/g; s/"/\&quot;/g')\"/>"
  printf '<testsuite name="sanitize" tests="1"><testcase classname="sanitize" name="%s">%s</testcase></testsuite>\n' \
    "$1" "$failure" > "$results/$1.xml"
}

if ! { cmake -G Ninja -S "$repo/test/sanitize" -B "$build" -DCMAKE_BUILD_TYPE=RelWithDebInfo > "$build/cmake.log" 2>&1 &&
       cmake --build "$build" -j"$(nproc)" --target test_core test_tools fuzz_depth_png fuzz_vti fuzz_sdfmap fuzz_ply \
         fuzz_tum_folder > "$build/build.log" 2>&1; }; then
  tail -n 30 "$build/build.log" 2>/dev/null || tail -n 30 "$build/cmake.log"
  junit sanitizer_build 0 "the sanitizer build failed (build/sanitize/build.log)"
  exit 1
fi
status=0
run_test() {  # run_test NAME: runs test_NAME, reports what a failure or a sanitizer printed
  echo "sanitizers: $1 under ASan + UBSan"
  if ! "$build/$1" --gtest_output="xml:$results/$1.xml" > "$build/$1.log" 2>&1; then
    grep -E "ERROR: (Address|Leak)Sanitizer|runtime error|FAILED" "$build/$1.log" | head -n 20
    # A sanitizer abort leaves no XML: count it.
    grep -q "<testsuites" "$results/$1.xml" 2>/dev/null || junit "$1" 0 "aborted: see build/sanitize/$1.log"
    return 1
  fi
}
fuzz() {  # fuzz TARGET: runs it for the full FUZZ_SECONDS and leaves its JUnit result
  if "$build/fuzz_$1" "$repo/test/fuzz/corpus/$1" "$seconds" 1 > "$build/fuzz_$1.log" 2>&1; then
    echo "sanitizers: fuzzed $1 for $seconds s: $(tail -n 1 "$build/fuzz_$1.log")"
    junit "fuzz_$1" 1 ""
  else
    echo "sanitizers: fuzzing $1 failed"
    grep -E "ERROR: (Address|Leak)Sanitizer|runtime error|SUMMARY" "$build/fuzz_$1.log" | head -n 20
    junit "fuzz_$1" 0 "fuzz_$1 crashed or a sanitizer reported (build/sanitize/fuzz_$1.log)"
    return 1
  fi
}
# The unit tests use both cores (OpenMP). Then the tools' tests and the fuzz targets share them,
# one job per core, the next starting as soon as one ends.
run_test test_core || status=1
jobs_left=("run_test test_tools" "fuzz depth_png" "fuzz vti" "fuzz sdfmap" "fuzz ply" "fuzz tum_folder")
running=0
for job in "${jobs_left[@]}"; do
  if ((running == $(nproc))); then
    wait -n || status=1
    running=$((running - 1))
  fi
  $job &
  running=$((running + 1))
done
for ((; running > 0; running--)); do wait -n || status=1; done
exit $status
