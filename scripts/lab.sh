#!/usr/bin/env bash
# Run dbuffer on a fresh Debian/Ubuntu machine, GPU or not: installs what it needs
# (scripts/setup-system.sh), builds in release, and passes its arguments on:
#
#   ./scripts/lab.sh                                   the lab window, on fig7-concave
#   ./scripts/lab.sh gui SCENE                         the lab on a built-in name, a .toml or an .obj
#   ./scripts/lab.sh render fig7-concave --out out/    a headless render (also compare, bench, inspect)
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup-system.sh
exec cargo run --release --locked --quiet -- "$@"
