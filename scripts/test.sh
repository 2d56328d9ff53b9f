#!/usr/bin/env bash
# Quick start, command 2: set up, build, and run the whole test suite (ctest over gtest).
# Tests that need ../shared/data skip with a visible message when it is absent.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$UPD_BUILD"
ctest --output-on-failure -j"$(nproc)" "$@"
