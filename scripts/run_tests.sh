#!/usr/bin/env bash
# Every test: installs dependencies; builds the package with its release tests and runs them
# through catkin (whole sequences, the ROS layer's gtests, the rostests); builds and runs the unit
# and tools' tests under ASan + UBSan with the readers' fuzz targets (scripts/run_sanitizers.sh);
# configures the package from a deep checkout (scripts/check_deep_checkout.sh); prints one
# "N passed, N failed" line.
# Real-data tests read SDF_TRACKER_DATA (default ../shared/data) and skip visibly without it.
set -euo pipefail
repo="$(cd "$(dirname "${BASH_SOURCE[0]}")/.." && pwd)"
bash "$repo/scripts/install_dependencies.sh"
# The package and every release test in one build, so that both cores stay busy to the end.
bash "$repo/scripts/build.sh" -DCATKIN_ENABLE_TESTING=ON all tests test_tum_bag test_camera_replay
export PATH="/usr/bin:$PATH"
cd "$repo/build/ws"
rm -rf build/test_results
# The rostests' nodes log here (their figures are read back below).
export ROS_LOG_DIR="$repo/build/ros_log"
rm -rf "$ROS_LOG_DIR"
set +u
# shellcheck disable=SC1091
source devel/setup.bash
set -u
# One test at a time: the rostests play bags at their real rate and must not share the two cores
# with another test.
cmake --build build --target run_tests -j 1 > "$repo/build/run_tests.log" 2>&1 || true
# The unit and tools' tests under ASan + UBSan, and every reader's fuzz target (no ROS).
# Meanwhile (it is light), the package configures from a checkout path of 150 characters or more.
RESULTS_DIR="$repo/build/ws/build/test_results/build" bash "$repo/scripts/check_deep_checkout.sh" &
deep_checkout=$!
RESULTS_DIR="$repo/build/ws/build/test_results/sanitize" bash "$repo/scripts/run_sanitizers.sh" || true
wait "$deep_checkout" || true
# What the tests printed about themselves: figures, skips, failures.
grep -shE "^\[ (figures|  SKIPPED|  FAILED) *\]|SKIPPED:|Failure|\.cpp:[0-9]+:" "$repo/build/run_tests.log" \
  "$repo"/build/sanitize/test_*.log | sort -u || true
# The rostests' figures are in their logs.
grep -rhoE "\[ figures  \].*" "$ROS_LOG_DIR" 2>/dev/null | sort -u || true
# Count from the result files, so a crashed test binary counts as a failure too.
/usr/bin/python3 - "$repo/build/ws/build/test_results" <<'PY'
import glob, os, sys, xml.etree.ElementTree as ET
root = sys.argv[1]
passed = failed = skipped = 0
files = glob.glob(os.path.join(root, "**", "*.xml"), recursive=True)
for f in files:
    try:
        tree = ET.parse(f)
    except ET.ParseError:
        print(f"unreadable result file {f}: counted as a failure"); failed += 1; continue
    for case in tree.iter("testcase"):
        if case.find("failure") is not None or case.find("error") is not None:
            failed += 1; print("FAILED:", case.get("classname"), case.get("name"))
        elif case.find("skipped") is not None or case.get("status") == "notrun" or case.get("result") == "skipped":
            skipped += 1
        else:
            passed += 1
if not files:
    print("no test result files were written"); failed += 1
print(f"tests: {passed} passed, {failed} failed, {skipped} skipped")
sys.exit(1 if failed else 0)
PY
