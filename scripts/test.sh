#!/usr/bin/env bash
# The README's test command: installs dependencies, builds with warnings as errors, runs the
# test suite, then runs it again under AddressSanitizer + UndefinedBehaviorSanitizer.
set -euo pipefail
cd "$(dirname "$0")/.."
./scripts/install-deps.sh
BUILD_DIR=build ./scripts/build.sh -DISOCHARTS_WERROR=ON
(cd build && ctest --output-on-failure -j "$(nproc)")
if [ "${ISOCHARTS_SKIP_SANITIZERS:-0}" != 1 ]; then
  # Tests tagged [slow] are left out of the sanitized build (see tests/CMakeLists.txt).
  BUILD_DIR=build-asan ./scripts/build.sh -DISOCHARTS_WERROR=ON -DISOCHARTS_SANITIZE=ON
  (cd build-asan && ctest --output-on-failure -j "$(nproc)")
fi
echo "test.sh: all tests passed"
