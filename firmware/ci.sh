#!/usr/bin/env bash
# Firmware CI: host unit + randomized tests under ASan/UBSan, then the Cortex-M3
# compile check of the PSoC 5LP sources. Needs gcc, make and gcc-arm-none-eabi
# (python3 optional: checks tests/vectors.h is generated from the vectors copy).
# Run from anywhere: bash firmware/ci.sh
set -euo pipefail
here="$(cd "$(dirname "${BASH_SOURCE[0]}")" && pwd)"
make -C "$here" clean
make -C "$here" test
make -C "$here" host
make -C "$here" harness
make -C "$here" target-check
echo "firmware ci: OK"
