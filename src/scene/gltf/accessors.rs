//! An accessor's bytes, every range checked against its buffer view and the buffer read: the
//! positions (FLOAT VEC3) and the indices (unsigned byte, short or int) of a primitive.

use super::buffers::Buffers;
use super::MAX_TRIANGLES;
use glam::Vec3;

/// The bytes of an accessor's elements: (bytes, element size, stride, count), every range
/// checked against the view and the buffer actually read.
fn accessor_bytes<'b>(
    acc: &::gltf::Accessor,
    what: &str,
    buffers: &'b mut Buffers,
) -> Result<(&'b [u8], usize, usize, usize), String> {
    let i = acc.index();
    if acc.sparse().is_some() {
        return Err(format!(
            "accessor {i} ({what}) is sparse: sparse accessors are not supported"
        ));
    }
    let view = acc.view().ok_or_else(|| {
        format!("accessor {i} ({what}) has no bufferView: expected its data in a buffer view")
    })?;
    let elem = acc.size();
    let stride = view.stride().unwrap_or(elem);
    let count = acc.count();
    if stride < elem {
        return Err(format!(
            "buffer view {} has byteStride {stride}, smaller than accessor {i}'s {elem}-byte elements",
            view.index()
        ));
    }
    let needed = if count == 0 {
        Some(0u64)
    } else {
        (stride as u64)
            .checked_mul(count as u64 - 1)
            .and_then(|x| x.checked_add(elem as u64))
            .and_then(|x| x.checked_add(acc.offset() as u64))
    };
    let view_len = view.length() as u64;
    match needed {
        Some(n) if n <= view_len => {}
        _ => {
            return Err(format!(
                "accessor {i} ({what}) is out of range: {count} items of {elem} bytes \
                 (stride {stride}) from byte {} do not fit buffer view {}'s {view_len} bytes",
                acc.offset(),
                view.index()
            ))
        }
    }
    let buffer = view.buffer();
    let start = view.offset() as u64;
    let data = buffers.get(&buffer)?;
    let has = data.len().min(buffer.length()) as u64;
    // A byteOffset near 2^64 must not wrap around.
    let end = match start.checked_add(view_len) {
        Some(end) if end <= has => end,
        _ => {
            return Err(format!(
                "buffer view {} is out of range: {view_len} bytes from byte {start} of buffer {}, \
                 which has {has}",
                view.index(),
                buffer.index(),
            ))
        }
    };
    let bytes = &data[start as usize + acc.offset()..end as usize];
    Ok((bytes, elem, stride, count))
}

pub(super) fn read_positions(
    acc: &::gltf::Accessor,
    what: &str,
    buffers: &mut Buffers,
) -> Result<Vec<Vec3>, String> {
    use ::gltf::accessor::{DataType, Dimensions};
    if acc.data_type() != DataType::F32 || acc.dimensions() != Dimensions::Vec3 {
        return Err(format!(
            "accessor {} ({what}) is {:?} {:?}: expected FLOAT VEC3 positions",
            acc.index(),
            acc.data_type(),
            acc.dimensions()
        ));
    }
    let (bytes, _, stride, count) = accessor_bytes(acc, what, buffers)?;
    // Bounded by the bytes checked above (12 bytes a position).
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let at = k * stride;
        let f = |j: usize| {
            let b = &bytes[at + 4 * j..at + 4 * j + 4];
            f32::from_le_bytes([b[0], b[1], b[2], b[3]])
        };
        let p = Vec3::new(f(0), f(1), f(2));
        if !p.is_finite() {
            return Err(format!(
                "accessor {} ({what}): position {k} is not finite",
                acc.index()
            ));
        }
        out.push(p);
    }
    Ok(out)
}

pub(super) fn read_indices(
    acc: &::gltf::Accessor,
    what: &str,
    buffers: &mut Buffers,
    vertices: usize,
) -> Result<Vec<u32>, String> {
    use ::gltf::accessor::{DataType, Dimensions};
    let size = match acc.data_type() {
        DataType::U8 => 1,
        DataType::U16 => 2,
        DataType::U32 => 4,
        other => {
            return Err(format!(
                "accessor {} ({what}) has component type {other:?}: expected unsigned byte, \
                 short or int indices",
                acc.index()
            ))
        }
    };
    if acc.dimensions() != Dimensions::Scalar {
        return Err(format!(
            "accessor {} ({what}) is {:?}: expected SCALAR indices",
            acc.index(),
            acc.dimensions()
        ));
    }
    if acc.count() / 3 > MAX_TRIANGLES {
        return Err(format!(
            "accessor {} ({what}) has {} indices: more than {MAX_TRIANGLES} triangles (the \
             limit for one model)",
            acc.index(),
            acc.count()
        ));
    }
    let (bytes, _, stride, count) = accessor_bytes(acc, what, buffers)?;
    let mut out = Vec::with_capacity(count);
    for k in 0..count {
        let b = &bytes[k * stride..k * stride + size];
        let v = match size {
            1 => u32::from(b[0]),
            2 => u32::from(u16::from_le_bytes([b[0], b[1]])),
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        };
        if v as usize >= vertices {
            return Err(format!(
                "accessor {} ({what}): index {v} at item {k} is out of range: the primitive has \
                 {vertices} vertices",
                acc.index()
            ));
        }
        out.push(v);
    }
    Ok(out)
}
