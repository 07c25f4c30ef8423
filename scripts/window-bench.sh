#!/usr/bin/env bash
# Time the lab's real window: `dbuffer gui SCENE --bench N` under Xvfb where there is no
# display, release build. Prints the table (window fps against the floor, CPU and GPU per frame)
# and writes it as JSON.
#
#   ./scripts/window-bench.sh [SCENE] [FRAMES] [OUT.json]     default: fig7-concave 60 out/window-bench.json
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup-system.sh
target="${CARGO_TARGET_DIR:-target}"
scene="${1:-fig7-concave}"
frames="${2:-60}"
out="${3:-out/window-bench.json}"
mkdir -p "$(dirname "$out")"
cargo build --locked --release --quiet --bin dbuffer
run=("$target/release/dbuffer" gui "$scene" --bench "$frames" --bench-out "$out")
if [ -n "${DISPLAY:-}" ]; then
  "${run[@]}"
else
  unset WAYLAND_DISPLAY
  xvfb-run -a -s "-screen 0 1280x800x24" "${run[@]}"
fi
