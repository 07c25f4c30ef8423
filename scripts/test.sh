#!/usr/bin/env bash
# Run every check and test of dbuffer on a fresh Debian/Ubuntu machine, GPU or not.
#
#   ./scripts/test.sh            format, lints, the whole test suite
#
# It installs the system packages the suite needs when it can (root or sudo); otherwise it prints
# the exact apt-get line to run. Rust itself comes from https://rustup.rs.
set -euo pipefail
cd "$(dirname "$0")/.."

# System packages the tests load at run time: Mesa's Vulkan driver (lavapipe, a CPU adapter for
# wgpu on machines without a GPU) and the Vulkan loader.
PACKAGES=(mesa-vulkan-drivers libvulkan1)

missing=()
for p in "${PACKAGES[@]}"; do
  dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
done
if [ ${#missing[@]} -gt 0 ]; then
  if [ "$(id -u)" = 0 ]; then SUDO=""; elif command -v sudo >/dev/null; then SUDO="sudo"; else SUDO="none"; fi
  if [ "$SUDO" = none ] || ! command -v apt-get >/dev/null; then
    echo "dbuffer tests need: ${missing[*]}" >&2
    echo "install them with:  sudo apt-get install -y --no-install-recommends ${missing[*]}" >&2
    exit 1
  fi
  echo "installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
fi

if ! command -v cargo >/dev/null; then
  echo "dbuffer needs Rust: install it from https://rustup.rs, then run this again" >&2
  exit 1
fi

export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"
# Mesa's device-select layer complains without a session; it has nothing to choose here.
export NODEVICE_SELECT="${NODEVICE_SELECT:-1}"
cargo fmt --all --check
cargo clippy --all-targets --locked -- -D warnings
cargo test --locked
