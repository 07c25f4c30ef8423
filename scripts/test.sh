#!/usr/bin/env bash
# Run every check and test of dbuffer on a fresh Debian/Ubuntu machine, GPU or not:
#
#   ./scripts/test.sh            format, lints, the whole test suite, the ray-query tracer's
#                                tests under Mesa 25 (fetched, scripts/mesa25.sh), the lab's
#                                Xvfb smoke run
#
# It installs the system packages the suite needs first (scripts/setup-system.sh).
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup-system.sh

cargo fmt --all --check
# cargo fmt misses the files only a macro declares (the method registry's): every .rs file too.
scripts/fmt-check.sh
# Lints every target: the library, the binary, the four test binaries, the examples and benches.
cargo clippy --all-targets --locked -- -D warnings
# The library's and the binary's unit tests and the four test binaries (tests/{cpu,gpu,cli,lab}).
# Not the examples: a plain `cargo test` links all five only to see that they build (150 MB and
# 20 s here), and clippy above has already type-checked them.
cargo test --locked --lib --bins --tests
# The documentation's examples, which naming targets above leaves out.
cargo test --locked --doc
# The shadow-ray tracer's hardware path: the system's lavapipe (Mesa 22.3) has no ray queries,
# so the tracer's tests run again under Mesa 25's, fetched beside it (scripts/mesa25.sh), where
# an adapter without ray queries is a failure. Only the gpu binary's trace tests: a few seconds.
# DBUFFER_SKIP_RAY_QUERY_RUN=1 leaves this run out, and says so.
if [ "${DBUFFER_SKIP_RAY_QUERY_RUN:-0}" = 1 ]; then
  echo "DBUFFER_SKIP_RAY_QUERY_RUN=1: the ray-query run under Mesa 25 is left out" >&2
else
  scripts/mesa25.sh env DBUFFER_REQUIRE_RAY_QUERY=1 cargo test --locked --test gpu trace::
fi
# The lab in a real window under Xvfb: renders, screenshots itself, is not blank, exits.
scripts/xvfb-smoke.sh
