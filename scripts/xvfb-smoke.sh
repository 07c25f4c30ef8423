#!/usr/bin/env bash
# The lab in a real X window, scripted: start `dbuffer gui fig7-concave` under Xvfb, let it render
# frames, screenshot the window (DBUFFER_SMOKE_SCREENSHOT), check that neither the window nor the
# viewport is blank, and exit cleanly. Run by scripts/test.sh.
#
#   ./scripts/xvfb-smoke.sh [shot.png]     default: $CARGO_TARGET_DIR/xvfb-smoke.png
set -euo pipefail
cd "$(dirname "$0")/.."
source scripts/setup-system.sh
target="${CARGO_TARGET_DIR:-target}"
shot="${1:-$target/xvfb-smoke.png}"
cargo build --locked --quiet --bin dbuffer
rm -f "$shot"
# A window, not Wayland: the lab is built for X11 (XWayland elsewhere).
unset WAYLAND_DISPLAY
DBUFFER_SMOKE_SCREENSHOT="$shot" timeout 300 \
  xvfb-run -a -s "-screen 0 1280x800x24" "$target/debug/dbuffer" gui fig7-concave
if [ ! -s "$shot" ]; then
  echo "xvfb smoke: no screenshot at $shot" >&2
  exit 1
fi
echo "xvfb smoke: ok, screenshot $shot"
