#!/usr/bin/env bash
# Quick start, command 2: set up, build, and run the whole test suite (ctest over gtest).
# Tests that need ../shared/data skip with a visible message when it is absent.
# In CI (CI=true), or with UPD_RELIABILITY=1, the reliability steps follow: each fuzzer for
# UPD_FUZZ_SECONDS (default 30) and the suite under ASan + UBSan (docs/RELIABILITY.md).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/setup.sh"
cd "$UPD_BUILD"
ctest --output-on-failure -j"$(nproc)" "$@"
if [ "${CI:-}" = true ] || [ "${UPD_RELIABILITY:-0}" = 1 ]; then
  "$UPD_ROOT/scripts/fuzz.sh" "${UPD_FUZZ_SECONDS:-30}"
  "$UPD_ROOT/scripts/sanitize.sh"
fi
