#!/usr/bin/env bash
# Remakes the shipped-model corpus (tests/cpu/gltf_shipped.rs reads it): the bundled Fox put
# through the two tools the glTF ecosystem ships models with, and a small fan for sparse
# accessors. Needs Node.js and the npm registry; run from anywhere:
#
#     bash tests/models/shipped/make.sh
#
# The Fox is first made smaller (its texture to 16×16, its animations dropped, then pruned):
# the geometry, the skin and the material stay as they were, and each variant is a few tens of
# KB. The tests compare each variant's triangles with assets/models/Fox.glb's.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
root="$(cd "$here/../../.." && pwd)"
tools="$(mktemp -d)"
trap 'rm -rf "$tools"' EXIT
npm install --silent --no-save --prefix "$tools" \
  @gltf-transform/cli@4.5.1 @gltf-transform/core@4.5.1 gltfpack@1.3.0 >/dev/null
gt="$tools/node_modules/.bin/gltf-transform"
pack="$tools/node_modules/.bin/gltfpack"
export NO_COLOR=1
cp "$here"/*.mjs "$tools/"

# The smaller Fox all variants start from (not kept).
"$gt" resize "$root/assets/models/Fox.glb" "$tools/a.glb" --width 16 --height 16
node "$tools/strip-animations.mjs" "$tools/a.glb" "$tools/b.glb"
"$gt" prune "$tools/b.glb" "$tools/fox-base.glb"

cd "$here"
"$gt" quantize "$tools/fox-base.glb" fox-quant.glb         # KHR_mesh_quantization
"$gt" meshopt "$tools/fox-base.glb" fox-meshopt.glb        # EXT_meshopt_compression + quantization
"$pack" -i "$tools/fox-base.glb" -o fox-pack.glb -cc       # gltfpack: meshopt, quantized, its own layout
"$gt" draco "$tools/fox-base.glb" fox-draco.glb            # KHR_draco_mesh_compression
"$gt" webp fox-quant.glb fox-webp.glb                      # EXT_texture_webp (on the quantized Fox: smaller)
# `gltf-transform sparse` leaves the Fox as it is (no accessor is two-thirds zeros): a small fan
# whose POSITION is sparse on zeros, without a bufferView, and the same fan dense.
node "$tools/fan.mjs" fan.glb fan-sparse.glb
ls -l "$here"/*.glb
