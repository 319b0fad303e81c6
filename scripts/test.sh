#!/usr/bin/env bash
# SPDX-License-Identifier: BSD-3-Clause
# Installs, builds (Release, with assertions) and runs every test with ctest.
# Pass ctest arguments after the script, e.g. scripts/test.sh -L fast
set -euo pipefail
cd "$(dirname "$0")/.."
scripts/install-deps.sh
scripts/build.sh build-test RelWithDebInfo -DNURBSFRONT_BUILD_BENCH=ON
ctest --test-dir build-test --output-on-failure --parallel "$(nproc)" --timeout 1200 "$@"
