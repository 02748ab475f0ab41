#!/usr/bin/env bash
# The C++ tests under AddressSanitizer + UndefinedBehaviorSanitizer: builds
# build-asan/ (SIMLOOP_SANITIZE=ON, -O1 -g) and runs ctest there. Any report
# fails the run: UBSan does not recover, ASan stops at the first error, and
# LeakSanitizer checks every test process at exit. Needs what scripts/setup.sh
# installs; run it after that (or after scripts/test.sh).
set -euo pipefail
cd "$(dirname "${BASH_SOURCE[0]}")/.."
jobs=${SIMLOOP_JOBS:-$(nproc)}
cmake -S . -B build-asan -DSIMLOOP_SANITIZE=ON -DSIMLOOP_BUILD_BENCH=OFF -DCMAKE_BUILD_TYPE=RelWithDebInfo \
  -DCMAKE_CXX_FLAGS_RELWITHDEBINFO="-O1 -g" >/dev/null
cmake --build build-asan -j "$jobs"
export ASAN_OPTIONS=${ASAN_OPTIONS:-abort_on_error=0:detect_leaks=1:strict_string_checks=1:check_initialization_order=1}
export UBSAN_OPTIONS=${UBSAN_OPTIONS:-print_stacktrace=1:halt_on_error=1}
ctest --test-dir build-asan --output-on-failure -j "$jobs"
