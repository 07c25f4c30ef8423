#!/usr/bin/env bash
# Prepare a folder that runs dbuffer's measurements on a bare Linux machine with a GPU (NVIDIA or
# AMD, its Vulkan driver installed) and no Rust:
#
#   ./scripts/gpu-study.sh BUNDLE          build (release) and fill BUNDLE: the binary, the Vulkan
#                                          loader it loads (libvulkan.so.1), and run.sh
#   BUNDLE/run.sh [RESULTS]                on the GPU machine: `adapters`, `bench --quick` and
#                                          `study --quick` into RESULTS (default
#                                          BUNDLE/results-HOST-DATE), with the machine's lscpu,
#                                          nvidia-smi / vulkaninfo where present, and the logs
#
# Copy BUNDLE over (scp -r, a tarball) and run it there; bring RESULTS back. The binary links only
# libc, libm and libgcc_s; Vulkan, X11 and the rest are loaded at run time, and the loader is
# carried beside it (the GPU's own driver, its ICD, is the machine's). Tested here on lavapipe:
# `./scripts/gpu-study.sh /tmp/bundle && /tmp/bundle/run.sh` (docs/guide/study.md).
set -euo pipefail
cd "$(dirname "$0")/.."

bundle="${1:?usage: scripts/gpu-study.sh BUNDLE}"
mkdir -p "$bundle"
cargo build --release --locked --bin dbuffer
cp target/release/dbuffer "$bundle/dbuffer"
# The release profile keeps debug info (about 160 of its 180 MB); the bundle need not carry it.
if command -v strip >/dev/null; then strip --strip-debug "$bundle/dbuffer"; fi
# The loader the binary dlopens; the machine's own is used first when it has one.
loader=$(ldconfig -p 2>/dev/null | awk '/libvulkan\.so\.1 / {print $NF; exit}')
if [ -n "${loader:-}" ] && [ -e "$loader" ]; then
  mkdir -p "$bundle/lib"
  cp -L "$loader" "$bundle/lib/libvulkan.so.1"
else
  echo "note: no libvulkan.so.1 here to carry (install libvulkan1); the GPU machine's own is needed" >&2
fi
git rev-parse HEAD > "$bundle/COMMIT" 2>/dev/null || true

cat > "$bundle/run.sh" <<'EOF'
#!/usr/bin/env bash
# Run dbuffer's measurements on this machine's GPU into one folder (see scripts/gpu-study.sh).
set -uo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
out="${1:-$here/results-$(hostname)-$(date +%Y%m%d-%H%M%S)}"
mkdir -p "$out"
# The machine's loader where it has one (LD_LIBRARY_PATH would come before it); the carried one
# where it has none.
if ! ldconfig -p 2>/dev/null | grep -q 'libvulkan\.so\.1 '; then
  export LD_LIBRARY_PATH="${LD_LIBRARY_PATH:+$LD_LIBRARY_PATH:}$here/lib"
fi
export WGPU_BACKEND="${WGPU_BACKEND:-vulkan}"
export NODEVICE_SELECT=1
{
  echo "commit: $(cat "$here/COMMIT" 2>/dev/null)"
  echo "date: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  lscpu 2>/dev/null | grep -E 'Model name|^CPU\(s\)'
  command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total --format=csv
  command -v vulkaninfo >/dev/null && vulkaninfo --summary 2>/dev/null | grep -E 'deviceName|driverInfo|apiVersion'
} > "$out/machine.txt" 2>&1
status=0
run() {
  local name="$1"; shift
  echo "== $name: dbuffer $*" | tee -a "$out/log.txt"
  local t0=$(date +%s)
  if ! "$here/dbuffer" "$@" >"$out/$name.stdout" 2>"$out/$name.stderr"; then
    echo "   FAILED (see $name.stderr)" | tee -a "$out/log.txt"
    status=1
  fi
  echo "   $(( $(date +%s) - t0 )) s" | tee -a "$out/log.txt"
}
run adapters adapters
run bench bench --quick --out "$out/bench"
run study study --quick --out "$out/study"
echo "results in $out"
exit $status
EOF
chmod +x "$bundle/run.sh"
echo "bundle ready: $bundle (run $bundle/run.sh on the GPU machine)"
