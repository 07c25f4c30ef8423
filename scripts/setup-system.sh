#!/usr/bin/env bash
# Installs the system packages dbuffer loads at run time, on Debian/Ubuntu, when it can (root or
# sudo); otherwise prints the exact apt-get line. Sourced by scripts/test.sh and scripts/lab.sh.
#
# mesa-vulkan-drivers + libvulkan1: lavapipe, Mesa's Vulkan on the CPU, so wgpu has an adapter
# on machines without a GPU (and a GPU machine keeps its own driver).
# libegl1 + libegl-mesa0 + libgl1-mesa-dri: llvmpipe through EGL, wgpu's GL backend
# (`--backend gl`, the GL tests of tests/cli/adapters.rs).
# xvfb + xauth + the X11 client libraries winit loads: the lab's window, and its smoke run under
# Xvfb in scripts/test.sh (scripts/xvfb-smoke.sh).
DBUFFER_PACKAGES=(mesa-vulkan-drivers libvulkan1 libegl1 libegl-mesa0 libgl1-mesa-dri xvfb xauth libxkbcommon-x11-0 libxcursor1 libxrandr2 libxi6 libx11-xcb1)

dbuffer_install_packages() {
  local missing=() p SUDO
  if ! command -v dpkg-query >/dev/null; then
    return 0 # not Debian/Ubuntu: the user brings a Vulkan driver
  fi
  for p in "$@"; do
    dpkg-query -W -f='${Status}' "$p" 2>/dev/null | grep -q "install ok installed" || missing+=("$p")
  done
  [ ${#missing[@]} -eq 0 ] && return 0
  if [ "$(id -u)" = 0 ]; then SUDO=""; elif command -v sudo >/dev/null; then SUDO="sudo"; else SUDO="none"; fi
  if [ "$SUDO" = none ] || ! command -v apt-get >/dev/null; then
    echo "dbuffer needs: ${missing[*]}" >&2
    echo "install them with:  sudo apt-get install -y --no-install-recommends ${missing[*]}" >&2
    return 1
  fi
  echo "installing ${missing[*]}"
  $SUDO apt-get update -qq
  DEBIAN_FRONTEND=noninteractive $SUDO apt-get install -y -qq --no-install-recommends "${missing[@]}"
}

if ! command -v cargo >/dev/null; then
  echo "dbuffer needs Rust: install it from https://rustup.rs, then run this again" >&2
  exit 1
fi
dbuffer_install_packages "${DBUFFER_PACKAGES[@]}" || exit 1
# Without a GPU, prefer Vulkan (lavapipe): wgpu's GL fallback cannot render to 32-bit float targets.
export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"
# Mesa's device-select layer complains without a session; it has nothing to choose here.
export NODEVICE_SELECT="${NODEVICE_SELECT:-1}"
