#!/usr/bin/env bash
# Run every check and test of dbuffer on a fresh Debian/Ubuntu machine, GPU or not:
#
#   ./scripts/test.sh            format, lints, the whole test suite, the lab's Xvfb smoke run
#
# It installs the system packages the suite needs first (scripts/setup-system.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup-system.sh

cargo fmt --all --check
cargo clippy --all-targets --locked -- -D warnings
cargo test --locked
# The lab in a real window under Xvfb: renders, screenshots itself, is not blank, exits.
scripts/xvfb-smoke.sh
