//! The GLB container: magic, version 2, declared length, and its JSON and BIN chunks, every
//! length checked before it is used.

pub(super) fn describe_magic(bytes: &[u8]) -> String {
    if bytes.len() < 4 {
        format!("a file of {} bytes", bytes.len())
    } else {
        let hex: Vec<String> = bytes[..4].iter().map(|b| format!("{b:02x}")).collect();
        format!("bytes {}", hex.join(" "))
    }
}

fn u32_at(bytes: &[u8], at: usize) -> Option<u32> {
    let b = bytes.get(at..at.checked_add(4)?)?;
    Some(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
}

/// The JSON chunk and the BIN chunk (if any) of a GLB file, every length checked.
pub fn split_glb(bytes: &[u8]) -> Result<(&[u8], Option<&[u8]>), String> {
    const JSON: u32 = 0x4E4F_534A;
    const BIN: u32 = 0x004E_4942;
    if !bytes.starts_with(b"glTF") {
        return Err(format!(
            "not a binary glTF file: expected the magic `glTF`, found {}",
            describe_magic(bytes)
        ));
    }
    let (Some(version), Some(length)) = (u32_at(bytes, 4), u32_at(bytes, 8)) else {
        return Err(format!(
            "truncated: the 12-byte GLB header is cut off after {} bytes",
            bytes.len()
        ));
    };
    if version != 2 {
        return Err(format!(
            "GLB version {version}: expected version 2 (glTF 2.0)"
        ));
    }
    let length = length as usize;
    if length > bytes.len() {
        return Err(format!(
            "truncated: the GLB header says {length} bytes, the file has {}",
            bytes.len()
        ));
    }
    if length < 20 {
        return Err(format!(
            "the GLB header says {length} bytes: too short for a header and a JSON chunk (20 bytes at least)"
        ));
    }
    let body = &bytes[..length];
    let chunk = |at: usize, what: &str| -> Result<(u32, &[u8]), String> {
        let (Some(len), Some(kind)) = (u32_at(body, at), u32_at(body, at + 4)) else {
            return Err(format!(
                "truncated: the {what} chunk header at byte {at} is cut off (the GLB has {length} bytes)"
            ));
        };
        let start = at + 8;
        let end = start
            .checked_add(len as usize)
            .filter(|&end| end <= body.len())
            .ok_or_else(|| {
                format!(
                    "truncated: the {what} chunk at byte {at} says {len} bytes, only {} follow",
                    body.len() - start
                )
            })?;
        Ok((kind, &body[start..end]))
    };
    let (kind, json) = chunk(12, "first")?;
    if kind != JSON {
        return Err(format!(
            "the first GLB chunk has type 0x{kind:08x}: expected JSON (0x{JSON:08x})"
        ));
    }
    let next = (12 + 8 + json.len()).next_multiple_of(4);
    let bin = if next + 8 <= body.len() {
        let (kind, data) = chunk(next, "second")?;
        (kind == BIN).then_some(data)
    } else {
        None
    };
    Ok((json, bin))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn glb_header_lengths_are_checked() {
        assert!(split_glb(b"glTF").unwrap_err().contains("truncated"));
        let mut h = b"glTF".to_vec();
        h.extend(2u32.to_le_bytes());
        h.extend(4u32.to_le_bytes());
        assert!(
            split_glb(&h).unwrap_err().contains("too short"),
            "a length under 12 must not underflow"
        );
        let mut h = b"glTF".to_vec();
        h.extend(1u32.to_le_bytes());
        h.extend(12u32.to_le_bytes());
        assert!(split_glb(&h).unwrap_err().contains("version 1"));
    }
}
