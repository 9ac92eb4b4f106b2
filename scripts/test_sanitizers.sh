#!/usr/bin/env bash
# The whole test suite built with AddressSanitizer + UndefinedBehaviorSanitizer (gcc) in
# build-asan/, then run: any invalid access, leak or undefined behaviour fails its test.
# Long tests take their small size (DYNSKY_TEST_SMALL=1, tests/test_support.h) so the run fits CI.
# Extra arguments go to ctest (e.g. -R AnimateCli).
set -euo pipefail
cd "$(dirname "$0")/.."
root=$PWD
# A finding exits non-zero with its report (UBSan too: halt_on_error); leaks in uninstrumented system
# libraries only are suppressed by name (tests/sanitizers/lsan.supp). The variables also reach the
# test discovery that runs each test program at build time.
export ASAN_OPTIONS="detect_leaks=1:check_initialization_order=1"
export LSAN_OPTIONS="suppressions=$root/tests/sanitizers/lsan.supp:print_suppressions=0"
export UBSAN_OPTIONS="print_stacktrace=1:halt_on_error=1"
export DYNSKY_TEST_SMALL=1
# RelWithDebInfo at -O1 -g1 (line tables): ASan's usual level, and compiling takes far less than at
# -O2 -g in CI's budget; reports still name files and lines.
cmake -S . -B build-asan -G Ninja -DCMAKE_BUILD_TYPE=RelWithDebInfo "-DCMAKE_CXX_FLAGS_RELWITHDEBINFO=-O1 -g1 -DNDEBUG" \
  -DDYNSKY_SANITIZE=ON -DDYNSKY_BUILD_BENCH=OFF >/dev/null
ninja -C build-asan -j "$(nproc)"
cd build-asan
# The Python training test runs no C++ of ours: the plain build's run covers it.
ctest --output-on-failure -j "$(nproc)" --timeout 900 -E '^NetworksTraining$' "$@"
