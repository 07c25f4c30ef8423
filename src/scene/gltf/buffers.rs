//! The bytes behind each buffer view a mesh uses: a range of a buffer (the GLB's BIN chunk, a
//! base64 `data:` URI, or a file beside the model, read once), or a meshopt stream decoded
//! once, all within the byte budget.

use super::json::Doc;
use super::meshopt::{compressed, decode, Compressed, Mode, MAX_EXPANSION};
use super::{read_regular_file, MAX_FILE_BYTES, MAX_PLACED_VERTICES, MAX_TRIANGLES};
use std::collections::HashMap;
use std::path::{Component, Path};

/// A buffer view, as the JSON gives it.
#[derive(Clone, Debug)]
pub(super) struct View {
    pub(super) index: usize,
    pub(super) buffer: usize,
    pub(super) byte_offset: u64,
    pub(super) byte_length: u64,
    pub(super) byte_stride: Option<u64>,
    /// EXT_meshopt_compression: the view's bytes are decoded from a stream elsewhere.
    pub(super) compressed: Option<Compressed>,
}

/// Buffer view `i` of `doc`; `from` names who uses it.
pub(super) fn parse_view(doc: &Doc, i: usize, from: &str) -> Result<View, String> {
    let v = doc.element("bufferViews", i, from)?;
    let byte_stride = v.opt_uint("byteStride")?;
    Ok(View {
        index: i,
        buffer: v
            .opt_index("buffer")?
            .ok_or_else(|| format!("invalid glTF: {} is missing", v.at("buffer")))?,
        byte_offset: v.opt_uint("byteOffset")?.unwrap_or(0),
        byte_length: v.uint("byteLength")?,
        // 0 is not a valid stride; some writers put it for "tightly packed".
        byte_stride: byte_stride.filter(|&s| s != 0),
        compressed: compressed(&v)?,
    })
}

/// The buffers read so far, by index, and the compressed views decoded so far.
pub(super) struct Buffers<'a> {
    pub(super) doc: &'a Doc,
    pub(super) base_dir: Option<&'a Path>,
    pub(super) bin: Option<&'a [u8]>,
    /// Whether the file is a GLB (a buffer without uri is then its BIN chunk, which must be
    /// there); in a `.gltf` such a buffer has no data at all.
    pub(super) glb: bool,
    /// One line each: buffers read as zeros.
    pub(super) notes: Vec<String>,
    pub(super) loaded: HashMap<usize, Vec<u8>>,
    pub(super) decoded: HashMap<usize, Vec<u8>>,
    /// Bytes read and decoded so far, against [`MAX_FILE_BYTES`].
    pub(super) total: u64,
}

impl<'a> Buffers<'a> {
    pub(super) fn new(
        doc: &'a Doc,
        base_dir: Option<&'a Path>,
        bin: Option<&'a [u8]>,
        glb: bool,
    ) -> Self {
        Buffers {
            doc,
            base_dir,
            bin,
            glb,
            notes: Vec::new(),
            loaded: HashMap::new(),
            decoded: HashMap::new(),
            total: 0,
        }
    }

    fn count(&mut self, bytes: u64) -> Result<(), String> {
        self.total = self.total.saturating_add(bytes);
        if self.total > MAX_FILE_BYTES {
            return Err(format!(
                "its buffers (read and decoded) add up to more than the limit of \
                 {MAX_FILE_BYTES} bytes (MAX_MODEL_FILE_BYTES)"
            ));
        }
        Ok(())
    }

    /// Whether buffer `index` has no data at all: no uri in a `.gltf` (the validator lets a
    /// JSON-only file leave its data to the application). Its bytes are read as zeros, as an
    /// accessor without a buffer view is, with a note, and without allocating them.
    pub(super) fn absent(&mut self, index: usize) -> bool {
        let Ok(b) = self.doc.element("buffers", index, "") else {
            return false;
        };
        let fallback = ["EXT_meshopt_compression", "KHR_meshopt_compression"]
            .iter()
            .any(|e| b.extension(e).is_some());
        let absent = !self.glb && b.get("uri").is_none() && !fallback;
        if absent
            && !self
                .notes
                .iter()
                .any(|n| n.starts_with(&format!("buffer {index} ")))
        {
            self.notes.push(format!(
                "buffer {index} has no uri and the file is not a GLB: it has no data, read as \
                 zeros"
            ));
        }
        absent
    }

    /// The bytes of buffer `index`, at least its declared `byteLength` long (checked), read on
    /// first use.
    pub(super) fn get(&mut self, index: usize, from: &str) -> Result<&[u8], String> {
        if !self.loaded.contains_key(&index) {
            let b = self.doc.element("buffers", index, from)?;
            let declared = b.uint("byteLength")?;
            let uri = b.opt_str("uri")?;
            let fallback = ["EXT_meshopt_compression", "KHR_meshopt_compression"]
                .iter()
                .any(|e| {
                    b.extension(e)
                        .is_some_and(|x| x.opt_bool("fallback").ok().flatten() == Some(true))
                });
            let bytes = match uri {
                None if fallback => {
                    return Err(format!(
                        "buffer {index} is a meshopt fallback buffer with no data, used by {from} \
                         without the extension's own stream"
                    ))
                }
                None => {
                    let bin = self.bin.ok_or_else(|| {
                        format!("buffer {index} has no uri and the file has no GLB BIN chunk")
                    })?;
                    if (bin.len() as u64) < declared {
                        return Err(format!(
                            "buffer {index} says {declared} bytes but the GLB BIN chunk has {}",
                            bin.len()
                        ));
                    }
                    bin[..declared as usize].to_vec()
                }
                Some(uri) => self.read_uri(index, uri)?,
            };
            if (bytes.len() as u64) < declared {
                return Err(format!(
                    "buffer {index} says {declared} bytes but its data has {}",
                    bytes.len()
                ));
            }
            self.count(bytes.len() as u64)?;
            self.loaded.insert(index, bytes);
        }
        Ok(self.loaded.get(&index).map(Vec::as_slice).unwrap_or(&[]))
    }

    /// The `byteLength` bytes of `view`: a range of its buffer (checked), or its meshopt stream
    /// decoded (once), every size checked before the decoder allocates.
    pub(super) fn view(&mut self, view: &View) -> Result<&[u8], String> {
        let i = view.index;
        let from = format!("buffer view {i}");
        let Some(c) = &view.compressed else {
            let data = self.get(view.buffer, &from)?;
            let has = data.len() as u64;
            // A byteOffset near 2^64 must not wrap around.
            return match view.byte_offset.checked_add(view.byte_length) {
                Some(end) if end <= has => Ok(&data[view.byte_offset as usize..end as usize]),
                _ => Err(format!(
                    "buffer view {i} is out of range: {} bytes from byte {} of buffer {}, which \
                     has {has}",
                    view.byte_length, view.byte_offset, view.buffer
                )),
            };
        };
        if !self.decoded.contains_key(&i) {
            let what = format!("buffer view {i} ({})", c.name);
            let decoded = c.count.checked_mul(c.byte_stride as u64);
            if decoded != Some(view.byte_length) {
                return Err(format!(
                    "{what}: count {} × byteStride {} is not the view's byteLength {}: the \
                     counts disagree",
                    c.count, c.byte_stride, view.byte_length
                ));
            }
            // The budget's counts, before the decoder allocates: a vertex stream holds at most
            // the positions a model may place, an index stream three per triangle.
            let (limit, of) = match c.mode {
                Mode::Attributes => (MAX_PLACED_VERTICES as u64, "vertices"),
                _ => (3 * MAX_TRIANGLES as u64, "indices"),
            };
            if c.count > limit {
                return Err(format!(
                    "{what}: count {} is more than the {limit} {of} a model may have \
                     (MAX_SCENE_TRIANGLES)",
                    c.count
                ));
            }
            let most = c
                .byte_length
                .saturating_mul(MAX_EXPANSION)
                .saturating_add(64);
            if view.byte_length > most {
                return Err(format!(
                    "{what}: {} bytes cannot decode from a {}-byte stream (at most {MAX_EXPANSION} \
                     bytes per byte): the count lies",
                    view.byte_length, c.byte_length
                ));
            }
            if self.total.saturating_add(view.byte_length) > MAX_FILE_BYTES {
                return Err(format!(
                    "{what}: its {} decoded bytes would take the model's buffers past the limit \
                     of {MAX_FILE_BYTES} bytes (MAX_MODEL_FILE_BYTES)",
                    view.byte_length
                ));
            }
            let data = self.get(c.buffer, &what)?;
            let has = data.len() as u64;
            let stream = match c.byte_offset.checked_add(c.byte_length) {
                Some(end) if end <= has => &data[c.byte_offset as usize..end as usize],
                _ => {
                    return Err(format!(
                        "{what}: its stream is out of range: {} bytes from byte {} of buffer {}, \
                         which has {has}",
                        c.byte_length, c.byte_offset, c.buffer
                    ))
                }
            };
            let bytes = decode(c, stream, &what)?;
            self.count(bytes.len() as u64)?;
            self.decoded.insert(i, bytes);
        }
        Ok(self.decoded.get(&i).map(Vec::as_slice).unwrap_or(&[]))
    }

    fn read_uri(&self, index: usize, uri: &str) -> Result<Vec<u8>, String> {
        if let Some(rest) = uri.strip_prefix("data:") {
            let (_, data) = rest.split_once(";base64,").ok_or_else(|| {
                format!("buffer {index}: a data: URI must be base64 (`;base64,`)")
            })?;
            return decode_base64(data.as_bytes())
                .ok_or_else(|| format!("buffer {index}: the data: URI is not valid base64"));
        }
        let relative = percent_decode(uri)
            .ok_or_else(|| format!("buffer {index}: the uri is not valid percent-encoded UTF-8"))?;
        let rel = Path::new(&relative);
        let has_scheme = relative.split_once(':').is_some_and(|(s, _)| {
            !s.is_empty()
                && s.chars()
                    .all(|c| c.is_ascii_alphanumeric() || "+-.".contains(c))
        });
        let mut depth = 0i32;
        let mut escapes = false;
        for c in rel.components() {
            match c {
                Component::Normal(_) => depth += 1,
                Component::CurDir => {}
                Component::ParentDir => {
                    depth -= 1;
                    escapes |= depth < 0;
                }
                Component::RootDir | Component::Prefix(_) => escapes = true,
            }
        }
        if has_scheme || rel.is_absolute() || escapes {
            return Err(format!(
                "buffer {index}: the uri must be a relative path inside the model's folder \
                 (no scheme, no absolute path, no `..` leaving the folder)"
            ));
        }
        let Some(base) = self.base_dir else {
            return Err(format!(
                "buffer {index} is in a separate file, but the model was not read from a folder"
            ));
        };
        let path = base.join(rel);
        read_regular_file(&path, &crate::scene::shown(&path.display().to_string()))
            .map_err(|e| format!("buffer {index}: {e}"))
    }
}

/// Standard base64 (RFC 4648, `+/`, `=` padding optional, whitespace not allowed). The decoding
/// is the `base64` crate's; what it accepts is as lenient as glTF exporters need: up to two `=`
/// at the end, whether or not the length calls for them, and unused bits in the last symbol
/// ignored.
fn decode_base64(text: &[u8]) -> Option<Vec<u8>> {
    use base64::engine::{DecodePaddingMode, GeneralPurpose, GeneralPurposeConfig};
    const LENIENT: GeneralPurpose = GeneralPurpose::new(
        &base64::alphabet::STANDARD,
        GeneralPurposeConfig::new()
            .with_decode_allow_trailing_bits(true)
            .with_decode_padding_mode(DecodePaddingMode::RequireNone),
    );
    let text = match text.iter().position(|&b| b == b'=') {
        Some(p) if text[p..].iter().all(|&b| b == b'=') && text.len() - p <= 2 => &text[..p],
        Some(_) => return None,
        None => text,
    };
    base64::Engine::decode(&LENIENT, text).ok()
}

/// `%XX` sequences decoded; `None` if one is malformed or the result is not UTF-8.
fn percent_decode(text: &str) -> Option<String> {
    let bytes = text.as_bytes();
    let mut out = Vec::with_capacity(bytes.len());
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            let hex = std::str::from_utf8(bytes.get(i + 1..i + 3)?).ok()?;
            out.push(u8::from_str_radix(hex, 16).ok()?);
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trips_known_values() {
        assert_eq!(decode_base64(b"").unwrap(), b"");
        assert_eq!(decode_base64(b"Zg==").unwrap(), b"f");
        assert_eq!(decode_base64(b"Zm8=").unwrap(), b"fo");
        assert_eq!(decode_base64(b"Zm9v").unwrap(), b"foo");
        assert_eq!(decode_base64(b"Zm9vYmE").unwrap(), b"fooba");
        assert_eq!(decode_base64(b"AAEC/w==").unwrap(), [0, 1, 2, 255]);
        assert!(decode_base64(b"Zm9v!").is_none());
        assert!(decode_base64(b"Z").is_none());
        assert!(decode_base64(b"Zg=a").is_none());
        // As lenient as before the crate decoded it: `=` where none is needed, and unused bits
        // set in the last symbol; but never more than two `=`.
        assert_eq!(decode_base64(b"Zm9v=").unwrap(), b"foo");
        assert_eq!(decode_base64(b"Zm8==").unwrap(), b"fo");
        assert_eq!(decode_base64(b"Zh==").unwrap(), b"f");
        assert!(decode_base64(b"Zg===").is_none());
        assert!(decode_base64(b"Zm9vY").is_none());
    }

    #[test]
    fn percent_decoding() {
        assert_eq!(percent_decode("a%20b.bin").unwrap(), "a b.bin");
        assert_eq!(percent_decode("plain.bin").unwrap(), "plain.bin");
        assert!(percent_decode("bad%2").is_none());
        assert!(percent_decode("bad%zz").is_none());
    }
}
