//! Small glTF models written byte by byte: the GLB container, the unit tetrahedron as a
//! document with its binary buffer, and base64 for `data:` URIs. Shared by the glTF tests
//! (`tests/cpu/gltf_models.rs`) and the glTF fuzz target's seeds (this crate's `lib.rs`).

use serde_json::{json, Value};

/// A GLB file: header, JSON chunk (space-padded), BIN chunk (zero-padded) if any.
pub fn glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let j = serde_json::to_vec(json).unwrap();
    glb_raw(&j, (!bin.is_empty()).then_some(bin))
}

/// A GLB file from the JSON chunk's bytes and the BIN chunk's, if any, each padded to a
/// multiple of 4 bytes (JSON with spaces, BIN with zeros); every length matches.
pub fn glb_raw(json: &[u8], bin: Option<&[u8]>) -> Vec<u8> {
    let mut j = json.to_vec();
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let b = bin.map(|b| {
        let mut b = b.to_vec();
        while !b.len().is_multiple_of(4) {
            b.push(0);
        }
        b
    });
    let total = 12 + 8 + j.len() + b.as_ref().map_or(0, |b| 8 + b.len());
    let mut out = Vec::with_capacity(total);
    out.extend(b"glTF");
    out.extend(2u32.to_le_bytes());
    out.extend((total as u32).to_le_bytes());
    out.extend((j.len() as u32).to_le_bytes());
    out.extend(b"JSON");
    out.extend(j);
    if let Some(b) = b {
        out.extend((b.len() as u32).to_le_bytes());
        out.extend(b"BIN\0");
        out.extend(b);
    }
    out
}

/// The unit tetrahedron (0,0,0), (1,0,0), (0,1,0), (0,0,1), wound outward.
pub const TET: [[f32; 3]; 4] = [
    [0.0, 0.0, 0.0],
    [1.0, 0.0, 0.0],
    [0.0, 1.0, 0.0],
    [0.0, 0.0, 1.0],
];
pub const TET_FACES: [[u32; 3]; 4] = [[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]];

pub fn f32_bytes(v: &[[f32; 3]]) -> Vec<u8> {
    v.iter().flatten().flat_map(|x| x.to_le_bytes()).collect()
}

/// Index bytes of `faces` as component type `ty` (5121 u8, 5123 u16, 5125 u32).
pub fn index_bytes(faces: &[[u32; 3]], ty: u32) -> Vec<u8> {
    faces
        .iter()
        .flatten()
        .flat_map(|&i| match ty {
            5121 => vec![i as u8],
            5123 => (i as u16).to_le_bytes().to_vec(),
            _ => i.to_le_bytes().to_vec(),
        })
        .collect()
}

/// A document with the tetrahedron as mesh 0 (indexed with `index_type`, or not), the given
/// nodes (scene 0 lists `roots`), and the binary data for one buffer.
pub fn tet_doc(index_type: Option<u32>, nodes: Value, roots: Value) -> (Value, Vec<u8>) {
    let mut bin = f32_bytes(&TET);
    let pos_len = bin.len();
    let mut views = vec![json!({"buffer": 0, "byteOffset": 0, "byteLength": pos_len})];
    let mut accessors = vec![json!({
        "bufferView": 0, "componentType": 5126, "count": 4, "type": "VEC3",
        "min": [0, 0, 0], "max": [1, 1, 1]
    })];
    let mut primitive = json!({"attributes": {"POSITION": 0}});
    match index_type {
        Some(ty) => {
            let idx = index_bytes(&TET_FACES, ty);
            views.push(json!({"buffer": 0, "byteOffset": pos_len, "byteLength": idx.len()}));
            accessors
                .push(json!({"bufferView": 1, "componentType": ty, "count": 12, "type": "SCALAR"}));
            primitive["indices"] = json!(1);
            bin.extend(idx);
        }
        None => {
            // Non-indexed: every corner of every face written out.
            let corners: Vec<[f32; 3]> = TET_FACES
                .iter()
                .flatten()
                .map(|&i| TET[i as usize])
                .collect();
            bin = f32_bytes(&corners);
            views[0]["byteLength"] = json!(bin.len());
            accessors[0]["count"] = json!(12);
        }
    }
    let doc = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [{"primitives": [primitive]}],
        "accessors": accessors,
        "bufferViews": views,
        "buffers": [{"byteLength": bin.len()}],
    });
    (doc, bin)
}

/// Standard base64 with `=` padding (what a `data:` URI holds).
pub fn base64(bytes: &[u8]) -> String {
    const A: &[u8] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let mut n = [0u8; 3];
        n[..chunk.len()].copy_from_slice(chunk);
        let v = u32::from(n[0]) << 16 | u32::from(n[1]) << 8 | u32::from(n[2]);
        for i in 0..=chunk.len() {
            out.push(A[(v >> (18 - 6 * i) & 63) as usize] as char);
        }
        for _ in chunk.len()..3 {
            out.push('=');
        }
    }
    out
}

/// A GLB of one triangle strip over 256 vertices, `indices` one-byte indices long, placed by
/// `nodes` nodes: `nodes × (indices − 2)` triangles.
pub fn instanced_strip(indices: usize, nodes: usize) -> Vec<u8> {
    let positions: Vec<[f32; 3]> = (0..256)
        .map(|i| [i as f32, ((i * i) % 17) as f32, (i % 7) as f32])
        .collect();
    let mut bin = f32_bytes(&positions);
    let pos_len = bin.len();
    bin.extend((0..indices).map(|k| (k % 256) as u8));
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": (0..nodes).collect::<Vec<_>>()}],
        "nodes": vec![json!({"mesh": 0}); nodes],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1, "mode": 5}]}],
        "accessors": [
            {"bufferView": 0, "componentType": 5126, "count": 256, "type": "VEC3"},
            {"bufferView": 1, "componentType": 5121, "count": indices, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteLength": pos_len},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": indices}
        ],
        "buffers": [{"byteLength": bin.len()}],
    });
    glb(&doc, &bin)
}

/// The tetrahedron with its corners stored as `ty` integers (KHR_mesh_quantization: 5120
/// byte, 5121 unsigned byte, 5122 short, 5123 unsigned short), `normalized` or not: scaled into
/// the integers by their maximum (normalized) or by 100, with the node's scale of 1/100 taking
/// them back. Each element is padded to 4 bytes, as glTF asks of vertex attributes.
pub fn quantized_tet(ty: u32, normalized: bool) -> (Value, Vec<u8>) {
    let (size, max) = match ty {
        5120 => (1, 127.0),
        5121 => (1, 255.0),
        5122 => (2, 32767.0),
        _ => (2, 65535.0),
    };
    let k: f32 = if normalized { max } else { 100.0 };
    let stride = 4 * size;
    let mut bin = Vec::new();
    for p in TET {
        let mut elem = vec![0u8; stride];
        for (j, c) in p.iter().enumerate() {
            let q = (c * k).round() as i64;
            elem[j * size..(j + 1) * size].copy_from_slice(&q.to_le_bytes()[..size]);
        }
        bin.extend(elem);
    }
    let pos_len = bin.len();
    let idx = index_bytes(&TET_FACES, 5123);
    bin.extend(&idx);
    let scale = if normalized { 1.0 } else { 1.0 / k };
    let doc = json!({
        "asset": {"version": "2.0"},
        "extensionsUsed": ["KHR_mesh_quantization"],
        "extensionsRequired": ["KHR_mesh_quantization"],
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0, "scale": [scale, scale, scale]}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"bufferView": 0, "componentType": ty, "normalized": normalized, "count": 4,
             "type": "VEC3"},
            {"bufferView": 1, "componentType": 5123, "count": 12, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteLength": pos_len, "byteStride": stride},
            {"buffer": 0, "byteOffset": pos_len, "byteLength": idx.len()}
        ],
        "buffers": [{"byteLength": bin.len()}],
    });
    (doc, bin)
}

/// The tetrahedron with POSITION on no bufferView (four zeros) and sparse values for corners
/// 1, 2 and 3 (one-byte sparse indices), one-byte face indices.
pub fn sparse_tet() -> (Value, Vec<u8>) {
    let mut bin = f32_bytes(&TET[1..]);
    bin.extend([1u8, 2, 3, 0]);
    bin.extend(index_bytes(&TET_FACES, 5121));
    let doc = json!({
        "asset": {"version": "2.0"},
        "scenes": [{"nodes": [0]}],
        "nodes": [{"mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": 0}, "indices": 1}]}],
        "accessors": [
            {"componentType": 5126, "count": 4, "type": "VEC3",
             "sparse": {"count": 3, "indices": {"bufferView": 1, "componentType": 5121},
                        "values": {"bufferView": 0}}},
            {"bufferView": 2, "componentType": 5121, "count": 12, "type": "SCALAR"}
        ],
        "bufferViews": [
            {"buffer": 0, "byteLength": 36},
            {"buffer": 0, "byteOffset": 36, "byteLength": 3},
            {"buffer": 0, "byteOffset": 40, "byteLength": 12}
        ],
        "buffers": [{"byteLength": bin.len()}],
    });
    (doc, bin)
}
