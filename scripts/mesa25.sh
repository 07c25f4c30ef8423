#!/usr/bin/env bash
# Runs a command under Mesa 25's lavapipe, which has hardware ray queries (VK_KHR_ray_query),
# beside the system's Mesa (Debian bookworm's 22.3 has none), without installing it:
#
#   scripts/mesa25.sh cargo test --locked --test gpu trace
#
# The first run fetches mesa-vulkan-drivers and the libdrm it needs from bookworm-backports with
# a private apt configuration (its own sources list, package lists and cache under the folder
# below; nothing under /etc/apt changes, no root needed), unpacks them with `dpkg -x` into
# $DBUFFER_MESA25_DIR (default target/mesa25) and writes an ICD file there whose library_path is
# the absolute path of the unpacked libvulkan_lvp.so. Later runs reuse it. The command then runs
# with VK_ICD_FILENAMES naming that ICD alone and LD_LIBRARY_PATH its libraries.
#
# When the download fails (no network, not a Debian machine) it says so and exits non-zero: a
# run that asks for Mesa 25 never falls back on the system driver silently.
set -euo pipefail
cd "$(dirname "$0")/.."

dir="${DBUFFER_MESA25_DIR:-target/mesa25}"
mkdir -p "$dir"
dir="$(cd "$dir" && pwd)"
root="$dir/root"
lib="$root/usr/lib/x86_64-linux-gnu"
icd="$dir/lvp25.json"
packages=(mesa-vulkan-drivers libdrm2 libdrm-amdgpu1)
suite=bookworm-backports

fail() {
  echo "scripts/mesa25.sh: $*" >&2
  echo "scripts/mesa25.sh: the ray-query tests need Mesa 25's lavapipe; without it they cannot run" >&2
  echo "scripts/mesa25.sh: (scripts/test.sh leaves that run out with DBUFFER_SKIP_RAY_QUERY_RUN=1, and says so)" >&2
  exit 1
}

fetch() {
  command -v apt-get >/dev/null && command -v dpkg >/dev/null ||
    fail "apt-get and dpkg are needed to fetch Mesa 25 from Debian's $suite"
  [ "$(dpkg --print-architecture)" = amd64 ] || fail "only amd64 is fetched (this is $(dpkg --print-architecture))"
  local apt="$dir/apt" keyring=/usr/share/keyrings/debian-archive-keyring.gpg
  [ -r "$keyring" ] || fail "Debian's archive keyring ($keyring) is missing: apt-get install debian-archive-keyring"
  rm -rf "$apt" "$dir/debs" "$root"
  mkdir -p "$apt/lists/partial" "$apt/cache/archives/partial" "$apt/etc/preferences.d" "$dir/debs"
  echo "deb [signed-by=$keyring] http://deb.debian.org/debian $suite main" >"$apt/etc/sources.list"
  # The machine's own apt configuration is left alone: these options point apt at a sources
  # list, package lists and a cache of its own, so nothing it fetches can reach a later
  # `apt-get install` (backports stays out of the system's sources).
  local opts=(
    -o "Dir::Etc::SourceList=$apt/etc/sources.list"
    -o "Dir::Etc::SourceParts=$apt/etc/sources.list.d"
    -o "Dir::Etc::PreferencesParts=$apt/etc/preferences.d"
    -o "Dir::State::Lists=$apt/lists"
    -o "Dir::Cache=$apt/cache"
    -o "Debug::NoLocking=1"
    -o "APT::Get::List-Cleanup=0"
  )
  # As root apt hands downloads to its _apt user, who cannot write into a user's folder.
  [ "$(id -u)" = 0 ] && opts+=(-o "APT::Sandbox::User=root")
  mkdir -p "$apt/etc/sources.list.d"
  echo "fetching Mesa 25 (${packages[*]}) from $suite into $dir"
  apt-get "${opts[@]}" -qq --error-on=any update || fail "apt-get update of $suite failed (no network?)"
  (cd "$dir/debs" && apt-get "${opts[@]}" -qq download -t "$suite" "${packages[@]}") ||
    fail "apt-get download of ${packages[*]} from $suite failed (no network?)"
  local deb
  for deb in "$dir"/debs/*.deb; do
    dpkg -x "$deb" "$root" || fail "cannot unpack $deb"
  done
  [ -f "$lib/libvulkan_lvp.so" ] || fail "the unpacked packages hold no $lib/libvulkan_lvp.so"
  local version
  version="$(dpkg-deb -f "$dir"/debs/mesa-vulkan-drivers_*.deb Version)"
  # The package's own ICD file names the library without a path; this one names the unpacked
  # copy, so the loader cannot pick up the system's.
  printf '{"ICD": {"api_version": "1.4.305", "library_path": "%s"}, "file_format_version": "1.0.0"}\n' \
    "$lib/libvulkan_lvp.so" >"$icd"
  echo "$version" >"$dir/version"
  echo "Mesa $version unpacked into $root"
}

[ -f "$icd" ] && [ -f "$lib/libvulkan_lvp.so" ] || fetch

if [ $# -eq 0 ]; then
  echo "VK_ICD_FILENAMES=$icd LD_LIBRARY_PATH=$lib"
  exit 0
fi
echo "under Mesa $(cat "$dir/version" 2>/dev/null || echo 25) lavapipe ($icd): $*"
VK_ICD_FILENAMES="$icd" LD_LIBRARY_PATH="$lib${LD_LIBRARY_PATH:+:$LD_LIBRARY_PATH}" exec "$@"
