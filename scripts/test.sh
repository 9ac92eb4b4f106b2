#!/usr/bin/env bash
# The test command: install what is missing, build, run every test (GoogleTest through CTest),
# then the whole suite again under ASan + UBSan (scripts/test_sanitizers.sh, build-asan/) and
# each libFuzzer target for 60 s (scripts/fuzz.sh, build-fuzz/). docs/testing.md gives the times.
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/setup.sh
scripts/build.sh
(cd build && ctest --output-on-failure -j "$(nproc)" --timeout 900)
scripts/test_sanitizers.sh
scripts/fuzz.sh
