//! The bytes behind each buffer a mesh uses: the GLB's BIN chunk, a base64 `data:` URI, or a
//! file beside the model, read once, within the byte budget.

use super::{read_regular_file, MAX_FILE_BYTES};
use std::collections::HashMap;
use std::path::{Component, Path};

/// The buffers read so far, by index.
pub(super) struct Buffers<'a> {
    pub(super) base_dir: Option<&'a Path>,
    pub(super) bin: Option<&'a [u8]>,
    pub(super) loaded: HashMap<usize, Vec<u8>>,
    pub(super) total: u64,
}

impl Buffers<'_> {
    /// The bytes of `buffer`, at least its declared `byteLength` long (checked), read on first use.
    pub(super) fn get(&mut self, buffer: &::gltf::Buffer) -> Result<&[u8], String> {
        let index = buffer.index();
        let declared = buffer.length();
        if !self.loaded.contains_key(&index) {
            let bytes = match buffer.source() {
                ::gltf::buffer::Source::Bin => {
                    let bin = self.bin.ok_or_else(|| {
                        format!("buffer {index} has no uri and the file has no GLB BIN chunk")
                    })?;
                    if bin.len() < declared {
                        return Err(format!(
                            "buffer {index} says {declared} bytes but the GLB BIN chunk has {}",
                            bin.len()
                        ));
                    }
                    bin[..declared].to_vec()
                }
                ::gltf::buffer::Source::Uri(uri) => self.read_uri(index, uri)?,
            };
            if bytes.len() < declared {
                return Err(format!(
                    "buffer {index} says {declared} bytes but its data has {}",
                    bytes.len()
                ));
            }
            self.total += bytes.len() as u64;
            if self.total > MAX_FILE_BYTES {
                return Err(format!(
                    "its buffers add up to more than the limit of {MAX_FILE_BYTES} bytes"
                ));
            }
            self.loaded.insert(index, bytes);
        }
        Ok(self.loaded.get(&index).map(Vec::as_slice).unwrap_or(&[]))
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
