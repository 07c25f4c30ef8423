//! `EXT_meshopt_compression` (and `KHR_meshopt_compression`, the same JSON): a buffer view
//! whose bytes are a meshoptimizer stream, decoded by the `meshopt` crate (meshoptimizer 1.3,
//! the codec gltfpack 1.3 writes) with its filters.
//!
//! Everything the decoder asserts is checked first (stride, mode, filter, count), and the size
//! it would allocate, `count × byteStride`, is checked before it runs: against the view's own
//! `byteLength` (a count that lies is refused), against what the stream's bytes can decode to
//! (at most [`MAX_EXPANSION`] bytes per compressed byte: a 10 KB stream never asks for more
//! than 10 MB), and against the model's byte budget (counted with its buffers).

use super::json::Obj;

/// The most bytes one compressed byte of a meshoptimizer stream can decode to. The vertex codec
/// is the most compact: version 1 spends 2 control bits per byte channel per block of at most
/// 256 vertices (8192 bytes at most) when the channel is all zeros, so a 4-byte-stride block of
/// 256 vertices (1024 bytes) costs one byte; version 0 costs at least a byte per 64. The index
/// codecs spend at least a byte per three indices (triangles) or per index (sequences).
pub(super) const MAX_EXPANSION: u64 = 1024;

/// How the stream encodes the view.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Mode {
    Attributes,
    Triangles,
    Indices,
}

/// The filter applied to decoded attributes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Filter {
    None,
    Octahedral,
    Quaternion,
    Exponential,
    /// KHR_meshopt_compression only.
    Color,
}

/// A compressed buffer view, as its extension describes it.
#[derive(Clone, Debug)]
pub(super) struct Compressed {
    /// Which extension (for messages).
    pub(super) name: &'static str,
    pub(super) buffer: usize,
    pub(super) byte_offset: u64,
    pub(super) byte_length: u64,
    pub(super) byte_stride: usize,
    pub(super) count: u64,
    pub(super) mode: Mode,
    pub(super) filter: Filter,
}

/// The meshopt extension of buffer view `view` (its JSON object), if it has one, every field
/// checked against what the decoder accepts.
pub(super) fn compressed(view: &Obj) -> Result<Option<Compressed>, String> {
    let (name, ext) = match (
        view.extension("EXT_meshopt_compression"),
        view.extension("KHR_meshopt_compression"),
    ) {
        (Some(e), _) => ("EXT_meshopt_compression", e),
        (None, Some(e)) => ("KHR_meshopt_compression", e),
        (None, None) => return Ok(None),
    };
    let at = |field: &str| format!("{} ({name})", ext.at(field));
    let buffer = ext
        .opt_index("buffer")?
        .ok_or_else(|| format!("invalid glTF: {} is missing", at("buffer")))?;
    let byte_offset = ext.opt_uint("byteOffset")?.unwrap_or(0);
    let byte_length = ext.uint("byteLength")?;
    let byte_stride = ext.uint("byteStride")?;
    let count = ext.uint("count")?;
    let mode = match ext.opt_str("mode")? {
        Some("ATTRIBUTES") => Mode::Attributes,
        Some("TRIANGLES") => Mode::Triangles,
        Some("INDICES") => Mode::Indices,
        Some(_) => {
            return Err(format!(
                "invalid glTF: {} is not ATTRIBUTES, TRIANGLES or INDICES",
                at("mode")
            ))
        }
        None => return Err(format!("invalid glTF: {} is missing", at("mode"))),
    };
    let filter = match ext.opt_str("filter")? {
        None | Some("NONE") => Filter::None,
        Some("OCTAHEDRAL") => Filter::Octahedral,
        Some("QUATERNION") => Filter::Quaternion,
        Some("EXPONENTIAL") => Filter::Exponential,
        Some("COLOR") if name == "KHR_meshopt_compression" => Filter::Color,
        Some(_) => {
            return Err(format!(
                "{}: an unknown filter (expected NONE, OCTAHEDRAL, QUATERNION or EXPONENTIAL{})",
                at("filter"),
                if name == "KHR_meshopt_compression" {
                    " or COLOR"
                } else {
                    ""
                }
            ))
        }
    };
    let stride_ok = match (mode, filter) {
        (Mode::Attributes, Filter::None | Filter::Exponential) => {
            byte_stride % 4 == 0 && (4..=256).contains(&byte_stride)
        }
        (Mode::Attributes, Filter::Octahedral | Filter::Color) => matches!(byte_stride, 4 | 8),
        (Mode::Attributes, Filter::Quaternion) => byte_stride == 8,
        (_, Filter::None) => matches!(byte_stride, 2 | 4),
        (_, _) => {
            return Err(format!(
                "{}: a filter applies to ATTRIBUTES only, not to {mode:?} streams",
                at("filter")
            ))
        }
    };
    if !stride_ok {
        return Err(format!(
            "{} is {byte_stride}: a {mode:?} stream{} needs {}",
            at("byteStride"),
            if filter == Filter::None {
                String::new()
            } else {
                format!(" with filter {filter:?}")
            },
            match (mode, filter) {
                (Mode::Attributes, Filter::None | Filter::Exponential) => {
                    "a multiple of 4 from 4 to 256"
                }
                (Mode::Attributes, Filter::Quaternion) => "8",
                (Mode::Attributes, _) => "4 or 8",
                _ => "2 or 4",
            }
        ));
    }
    if mode == Mode::Triangles && count % 3 != 0 {
        return Err(format!(
            "{} is {count}: a TRIANGLES stream holds a multiple of 3 indices",
            at("count")
        ));
    }
    Ok(Some(Compressed {
        name,
        buffer,
        byte_offset,
        byte_length,
        byte_stride: byte_stride as usize,
        count,
        mode,
        filter,
    }))
}

/// Decodes `stream` (the compressed bytes, already cut to `byteLength`) into `count ×
/// byteStride` bytes. `what` names the view in errors. The caller has checked the decoded size
/// against the budget.
pub(super) fn decode(c: &Compressed, stream: &[u8], what: &str) -> Result<Vec<u8>, String> {
    let count = usize::try_from(c.count).map_err(|_| format!("{what}: count too large"))?;
    let failed = |_| {
        format!(
            "{what}: the {} stream ({:?}, {} bytes for {count} items of {} bytes) does not \
             decode: truncated or corrupt",
            c.name,
            c.mode,
            stream.len(),
            c.byte_stride
        )
    };
    if count == 0 {
        return Ok(Vec::new());
    }
    match c.mode {
        Mode::Attributes => {
            let mut bytes = decode_vertices(stream, count, c.byte_stride / 4).map_err(failed)?;
            filter(&mut bytes, c.filter, c.byte_stride);
            Ok(bytes)
        }
        Mode::Triangles | Mode::Indices => {
            let triangles = c.mode == Mode::Triangles;
            if c.byte_stride == 2 {
                let v: Vec<u16> = if triangles {
                    meshopt::encoding::decode_index_buffer(stream, count)
                } else {
                    meshopt::encoding::decode_index_sequence(stream, count)
                }
                .map_err(failed)?;
                Ok(v.iter().flat_map(|x| x.to_le_bytes()).collect())
            } else {
                let v: Vec<u32> = if triangles {
                    meshopt::encoding::decode_index_buffer(stream, count)
                } else {
                    meshopt::encoding::decode_index_sequence(stream, count)
                }
                .map_err(failed)?;
                Ok(v.iter().flat_map(|x| x.to_le_bytes()).collect())
            }
        }
    }
}

/// The vertex codec with a vertex of `words` 32-bit words: the crate takes the vertex size from
/// the element type, so each size from 1 to 64 words is its own instance.
fn decode_vertices(stream: &[u8], count: usize, words: usize) -> Result<Vec<u8>, meshopt::Error> {
    /// A vertex of N words (the standard library has `Default` for arrays up to 32 only).
    #[derive(Clone, Copy)]
    #[repr(transparent)]
    struct Words<const N: usize>([u32; N]);
    impl<const N: usize> Default for Words<N> {
        fn default() -> Self {
            Words([0; N])
        }
    }
    fn run<const N: usize>(stream: &[u8], count: usize) -> Result<Vec<u8>, meshopt::Error> {
        let v: Vec<Words<N>> = meshopt::encoding::decode_vertex_buffer(stream, count)?;
        // The decoder wrote the stream's bytes into the words as they lie in memory.
        Ok(v.iter()
            .flat_map(|w| w.0)
            .flat_map(u32::to_ne_bytes)
            .collect())
    }
    macro_rules! dispatch {
        ($($n:literal)*) => {
            match words {
                $($n => run::<$n>(stream, count),)*
                _ => Err(meshopt::Error::Parse("byteStride over 256".into())),
            }
        };
    }
    dispatch!(1 2 3 4 5 6 7 8 9 10 11 12 13 14 15 16 17 18 19 20 21 22 23 24 25 26 27 28 29 30
        31 32 33 34 35 36 37 38 39 40 41 42 43 44 45 46 47 48 49 50 51 52 53 54 55 56 57 58 59
        60 61 62 63 64)
}

/// The filter, in place, over decoded vertices of `stride` bytes (checked by [`compressed`]).
fn filter(bytes: &mut [u8], filter: Filter, stride: usize) {
    use meshopt::encoding::{
        decode_filter_color, decode_filter_exp, decode_filter_oct, decode_filter_quat,
    };
    match (filter, stride) {
        (Filter::None, _) => {}
        (Filter::Octahedral | Filter::Color, 4) => {
            let mut v: Vec<[i8; 4]> = bytes
                .chunks_exact(4)
                .map(|c| [c[0] as i8, c[1] as i8, c[2] as i8, c[3] as i8])
                .collect();
            if filter == Filter::Color {
                decode_filter_color(&mut v);
            } else {
                decode_filter_oct(&mut v);
            }
            for (out, x) in bytes.chunks_exact_mut(4).zip(v) {
                out.copy_from_slice(&x.map(|b| b as u8));
            }
        }
        (Filter::Octahedral | Filter::Color | Filter::Quaternion, _) => {
            let mut v: Vec<[i16; 4]> = bytes
                .chunks_exact(8)
                .map(|c| std::array::from_fn(|k| i16::from_ne_bytes([c[2 * k], c[2 * k + 1]])))
                .collect();
            match filter {
                Filter::Quaternion => decode_filter_quat(&mut v),
                Filter::Color => decode_filter_color(&mut v),
                _ => decode_filter_oct(&mut v),
            }
            for (out, x) in bytes.chunks_exact_mut(8).zip(v) {
                for (k, h) in x.iter().enumerate() {
                    out[2 * k..2 * k + 2].copy_from_slice(&h.to_ne_bytes());
                }
            }
        }
        (Filter::Exponential, _) => {
            // Each 32-bit word is decoded on its own, whatever the stride.
            let mut v: Vec<[u32; 1]> = bytes
                .chunks_exact(4)
                .map(|c| [u32::from_ne_bytes([c[0], c[1], c[2], c[3]])])
                .collect();
            decode_filter_exp(&mut v);
            for (out, x) in bytes.chunks_exact_mut(4).zip(v) {
                out.copy_from_slice(&x[0].to_ne_bytes());
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn comp(mode: Mode, stride: usize, count: u64) -> Compressed {
        Compressed {
            name: "EXT_meshopt_compression",
            buffer: 0,
            byte_offset: 0,
            byte_length: 0,
            byte_stride: stride,
            count,
            mode,
            filter: Filter::None,
        }
    }

    #[test]
    fn streams_round_trip_through_the_crate() {
        let vertices: Vec<[u16; 4]> = (0..100u16).map(|i| [i, i * 3, 65535 - i, 0]).collect();
        let stream = meshopt::encoding::encode_vertex_buffer(&vertices).unwrap();
        let bytes = decode(&comp(Mode::Attributes, 8, 100), &stream, "v").unwrap();
        let expected: Vec<u8> = vertices
            .iter()
            .flatten()
            .flat_map(|x| x.to_ne_bytes())
            .collect();
        assert_eq!(bytes, expected);
        let indices: Vec<u32> = vec![0, 1, 2, 2, 1, 3, 3, 1, 4];
        let stream = meshopt::encoding::encode_index_buffer(&indices, 5).unwrap();
        let bytes = decode(&comp(Mode::Triangles, 2, 9), &stream, "i").unwrap();
        let back: Vec<u16> = bytes
            .chunks_exact(2)
            .map(|c| u16::from_le_bytes([c[0], c[1]]))
            .collect();
        assert_eq!(back, [0, 1, 2, 2, 1, 3, 3, 1, 4]);
        // Truncated: an error, not garbage.
        let e = decode(
            &comp(Mode::Triangles, 2, 9),
            &stream[..stream.len() - 3],
            "i",
        )
        .unwrap_err();
        assert!(e.contains("does not decode"), "{e}");
    }

    #[test]
    fn the_exponential_filter_gives_floats() {
        // 2^E · M with E = -2 (0xfe) and M = 6: 1.5.
        let mut bytes = ((0xfeu32 << 24) | 6).to_ne_bytes().to_vec();
        filter(&mut bytes, Filter::Exponential, 4);
        assert_eq!(
            f32::from_ne_bytes([bytes[0], bytes[1], bytes[2], bytes[3]]),
            1.5
        );
    }
}
