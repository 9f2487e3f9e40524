#!/usr/bin/env bash
# mesolab test suite. Installs missing Debian packages, builds, runs every test under CTest
# (GoogleTest; pytest for the Python module and examples/; the GUI smoke test under xvfb-run),
# then builds and runs the whole suite again with AddressSanitizer + UndefinedBehaviorSanitizer,
# but for the tests labelled `slow` (every preset rendered on both backends and checked against
# the gallery: minutes in Release, an hour under the sanitizers) and the Python tests (a
# sanitizer-built module does not load into a plain interpreter). `./test.sh --quick` skips the sanitizer pass.
set -euo pipefail
cd "$(dirname "$0")"
source .ci/setup.sh
ensure_packages
jobs="$(nproc 2>/dev/null || echo 2)"

build build
echo "== tests (Release)"
ctest --test-dir build --output-on-failure -j "$jobs" --timeout 600

if [ "${1:-}" != "--quick" ]; then
  build build-sanitize -DMESOLAB_SANITIZE=ON -DCMAKE_BUILD_TYPE=RelWithDebInfo
  echo "== tests (AddressSanitizer + UndefinedBehaviorSanitizer)"
  export ASAN_OPTIONS="detect_leaks=1:abort_on_error=1:strict_string_checks=1"
  export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
  if ! ctest --test-dir build-sanitize --output-on-failure -j "$jobs" --timeout 900 --label-exclude slow; then
    # LeakSanitizer's exit-time tracer has been seen to crash (signal 11 in StopTheWorld) after a
    # test had passed, with GL driver threads still winding down. Such a test, and only such a
    # one, runs once more; any other failure ends here (.ci/lsan_exit_crash.py names them).
    crashed="$(python3 .ci/lsan_exit_crash.py build-sanitize/Testing/Temporary/LastTest.log)"
    echo "== LeakSanitizer's tracer crashed at exit after these tests had passed; running them once more:"
    echo "$crashed"
    ctest --test-dir build-sanitize --output-on-failure --timeout 900 -R "^($(echo "$crashed" | sed 's/[.]/\\./g' | paste -sd'|'))\$"
  fi
fi
echo "== all tests passed"
