//! Accessors: the positions (float, or integers with KHR_mesh_quantization, normalized or not)
//! and the indices (unsigned byte, short or int) of a primitive, from a buffer view, from
//! zeros (an accessor without `bufferView`), and with sparse substitutions; every range
//! checked against the view before a byte is read.

use super::buffers::{parse_view, Buffers, View};
use super::json::Doc;
use super::{MAX_PLACED_VERTICES, MAX_TRIANGLES};
use glam::Vec3;

/// A component type of an accessor.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Component {
    I8,
    U8,
    I16,
    U16,
    U32,
    F32,
}

impl Component {
    fn parse(code: u64) -> Option<Component> {
        Some(match code {
            5120 => Component::I8,
            5121 => Component::U8,
            5122 => Component::I16,
            5123 => Component::U16,
            5125 => Component::U32,
            5126 => Component::F32,
            _ => return None,
        })
    }

    pub(super) fn size(self) -> usize {
        match self {
            Component::I8 | Component::U8 => 1,
            Component::I16 | Component::U16 => 2,
            Component::U32 | Component::F32 => 4,
        }
    }

    fn name(self) -> &'static str {
        match self {
            Component::I8 => "BYTE",
            Component::U8 => "UNSIGNED_BYTE",
            Component::I16 => "SHORT",
            Component::U16 => "UNSIGNED_SHORT",
            Component::U32 => "UNSIGNED_INT",
            Component::F32 => "FLOAT",
        }
    }

    /// Component `b` (little-endian bytes, `size()` of them) as a number: a float as it is, an
    /// integer as its value, or with `normalized` mapped to −1..1 or 0..1 as glTF says.
    fn value(self, b: &[u8], normalized: bool) -> f32 {
        let (v, scale) = match self {
            Component::I8 => (f32::from(b[0] as i8), 127.0),
            Component::U8 => (f32::from(b[0]), 255.0),
            Component::I16 => (f32::from(i16::from_le_bytes([b[0], b[1]])), 32767.0),
            Component::U16 => (f32::from(u16::from_le_bytes([b[0], b[1]])), 65535.0),
            Component::U32 => (u32::from_le_bytes([b[0], b[1], b[2], b[3]]) as f32, 1.0),
            Component::F32 => return f32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        };
        if normalized {
            (v / scale).max(-1.0)
        } else {
            v
        }
    }

    fn index(self, b: &[u8]) -> u32 {
        match self {
            Component::U8 => u32::from(b[0]),
            Component::U16 => u32::from(u16::from_le_bytes([b[0], b[1]])),
            _ => u32::from_le_bytes([b[0], b[1], b[2], b[3]]),
        }
    }
}

/// Sparse substitutions of an accessor.
#[derive(Clone, Debug)]
struct Sparse {
    count: u64,
    indices_view: usize,
    indices_offset: u64,
    indices_component: Component,
    values_view: usize,
    values_offset: u64,
}

/// An accessor, as the JSON gives it.
#[derive(Clone, Debug)]
pub(super) struct Accessor {
    pub(super) index: usize,
    pub(super) component: Component,
    /// Components per element (1 for SCALAR, 3 for VEC3, ...).
    pub(super) components: usize,
    type_name: &'static str,
    pub(super) normalized: bool,
    pub(super) count: u64,
    byte_offset: u64,
    pub(super) view: Option<usize>,
    sparse: Option<Sparse>,
}

/// Accessor `i` of `doc`; `from` (e.g. `meshes[0].primitives[1].indices`) names who uses it.
pub(super) fn parse_accessor(doc: &Doc, i: usize, from: &str) -> Result<Accessor, String> {
    let a = doc.element("accessors", i, from)?;
    let code = a.uint("componentType")?;
    let component = Component::parse(code).ok_or_else(|| {
        format!(
            "invalid glTF: {} is {code}: not a glTF component type",
            a.at("componentType")
        )
    })?;
    let (components, type_name) = match a.opt_str("type")? {
        Some("SCALAR") => (1, "SCALAR"),
        Some("VEC2") => (2, "VEC2"),
        Some("VEC3") => (3, "VEC3"),
        Some("VEC4") => (4, "VEC4"),
        Some("MAT2") => (4, "MAT2"),
        Some("MAT3") => (9, "MAT3"),
        Some("MAT4") => (16, "MAT4"),
        Some(_) => {
            return Err(format!(
                "invalid glTF: {} is not SCALAR, VEC2, VEC3, VEC4, MAT2, MAT3 or MAT4",
                a.at("type")
            ))
        }
        None => return Err(format!("invalid glTF: {} is missing", a.at("type"))),
    };
    let sparse = match a.opt_obj("sparse")? {
        None => None,
        Some(s) => {
            let indices = s
                .opt_obj("indices")?
                .ok_or_else(|| format!("invalid glTF: {} is missing", s.at("indices")))?;
            let values = s
                .opt_obj("values")?
                .ok_or_else(|| format!("invalid glTF: {} is missing", s.at("values")))?;
            let code = indices.uint("componentType")?;
            let indices_component = match Component::parse(code) {
                Some(c @ (Component::U8 | Component::U16 | Component::U32)) => c,
                _ => {
                    return Err(format!(
                        "invalid glTF: {} is {code}: expected unsigned byte, short or int",
                        indices.at("componentType")
                    ))
                }
            };
            let view_of = |o: &super::json::Obj| -> Result<usize, String> {
                o.opt_index("bufferView")?
                    .ok_or_else(|| format!("invalid glTF: {} is missing", o.at("bufferView")))
            };
            Some(Sparse {
                count: s.uint("count")?,
                indices_view: view_of(&indices)?,
                indices_offset: indices.opt_uint("byteOffset")?.unwrap_or(0),
                indices_component,
                values_view: view_of(&values)?,
                values_offset: values.opt_uint("byteOffset")?.unwrap_or(0),
            })
        }
    };
    Ok(Accessor {
        index: i,
        component,
        components,
        type_name,
        normalized: a.opt_bool("normalized")?.unwrap_or(false),
        count: a.uint("count")?,
        byte_offset: a.opt_uint("byteOffset")?.unwrap_or(0),
        view: a.opt_index("bufferView")?,
        sparse,
    })
}

impl Accessor {
    fn elem(&self) -> usize {
        self.component.size() * self.components
    }

    /// At most how many of its elements are read, before reading: its count, but no more than
    /// its view's declared length holds (a larger count is refused when it is read, with the
    /// range error).
    pub(super) fn readable_count(&self, doc: &Doc) -> u64 {
        match self.view.and_then(|v| parse_view(doc, v, "").ok()) {
            Some(view) => {
                let stride = view.byte_stride.unwrap_or(self.elem() as u64).max(1);
                self.count
                    .min((view.byte_length / stride).saturating_add(1))
            }
            None => self.count,
        }
    }

    /// Whether every element is zero: no buffer view and no sparse values.
    pub(super) fn all_zeros(&self) -> bool {
        self.view.is_none() && self.sparse.is_none()
    }

    fn describe(&self, what: &str) -> String {
        format!("accessor {} ({what})", self.index)
    }
}

/// Checks that the accessor's elements fit its view (if it has one), from the JSON alone.
fn check_range(acc: &Accessor, what: &str, doc: &Doc) -> Result<(), String> {
    let who = acc.describe(what);
    if let Some(v) = acc.view {
        let view = parse_view(doc, v, &format!("{who}.bufferView"))?;
        let elem = acc.elem();
        let stride = view.byte_stride.map_or(elem, |s| s as usize);
        fits(&view, acc.byte_offset, acc.count, elem, stride, &who)?;
    }
    Ok(())
}

/// Whether `count` elements of `elem` bytes every `stride` bytes from `offset` fit `view`.
fn fits(
    view: &View,
    offset: u64,
    count: u64,
    elem: usize,
    stride: usize,
    who: &str,
) -> Result<(), String> {
    if stride < elem {
        return Err(format!(
            "buffer view {} has byteStride {stride}, smaller than {who}'s {elem}-byte elements",
            view.index
        ));
    }
    // Even no element must start inside the view.
    let needed = if count == 0 {
        Some(offset)
    } else {
        (stride as u64)
            .checked_mul(count - 1)
            .and_then(|x| x.checked_add(elem as u64))
            .and_then(|x| x.checked_add(offset))
    };
    match needed {
        Some(n) if n <= view.byte_length => {}
        _ => {
            return Err(format!(
                "{who} is out of range: {count} items of {elem} bytes (stride {stride}) from byte \
                 {offset} do not fit buffer view {}'s {} bytes",
                view.index, view.byte_length
            ))
        }
    }
    Ok(())
}

/// `count` elements of `elem` bytes every `stride` bytes from `offset` of `view`: the view's
/// bytes from `offset`, checked to hold them all. `who` names the reader in errors.
fn strided<'b>(
    buffers: &'b mut Buffers,
    view: &View,
    offset: u64,
    count: u64,
    elem: usize,
    stride: usize,
    who: &str,
) -> Result<&'b [u8], String> {
    fits(view, offset, count, elem, stride, who)?;
    let bytes = buffers.view(view)?;
    Ok(&bytes[offset as usize..])
}

/// The accessor's elements as `elem`-byte slices handed to `each(k, bytes)`: from its view, or
/// nothing (zeros: the caller starts from them) when it has none; then its sparse values
/// handed the same way. Every range is checked first.
fn for_each_element(
    acc: &Accessor,
    what: &str,
    buffers: &mut Buffers,
    mut each: impl FnMut(usize, &[u8]) -> Result<(), String>,
) -> Result<(), String> {
    let who = acc.describe(what);
    let elem = acc.elem();
    if let Some(v) = acc.view {
        let view = parse_view(buffers.doc, v, &format!("{who}.bufferView"))?;
        let stride = view.byte_stride.map_or(elem, |s| s as usize);
        if view.compressed.is_none() && buffers.absent(view.buffer) {
            // No data: zeros, as without a view (the ranges still checked).
            fits(&view, acc.byte_offset, acc.count, elem, stride, &who)?;
        } else {
            let bytes = strided(
                buffers,
                &view,
                acc.byte_offset,
                acc.count,
                elem,
                stride,
                &who,
            )?;
            for k in 0..acc.count as usize {
                each(k, &bytes[k * stride..k * stride + elem])?;
            }
        }
    }
    if let Some(s) = &acc.sparse {
        if s.count > acc.count {
            return Err(format!(
                "{who} has {} sparse values, more than its count {}",
                s.count, acc.count
            ));
        }
        let isize = s.indices_component.size();
        let iview = parse_view(
            buffers.doc,
            s.indices_view,
            &format!("{who}.sparse.indices"),
        )?;
        let vview = parse_view(buffers.doc, s.values_view, &format!("{who}.sparse.values"))?;
        let absent = |b: &mut Buffers, v: &View| v.compressed.is_none() && b.absent(v.buffer);
        if absent(buffers, &iview) || absent(buffers, &vview) {
            // Values or their places with no data: zeros put on zeros, nothing changes.
            fits(&iview, s.indices_offset, s.count, isize, isize, &who)?;
            fits(&vview, s.values_offset, s.count, elem, elem, &who)?;
            return Ok(());
        }
        let indices: Vec<u32> = {
            let bytes = strided(
                buffers,
                &iview,
                s.indices_offset,
                s.count,
                isize,
                isize,
                &format!("{who}'s sparse indices"),
            )?;
            (0..s.count as usize)
                .map(|k| s.indices_component.index(&bytes[k * isize..]))
                .collect()
        };
        let bytes = strided(
            buffers,
            &vview,
            s.values_offset,
            s.count,
            elem,
            elem,
            &format!("{who}'s sparse values"),
        )?;
        for (k, &target) in indices.iter().enumerate() {
            if u64::from(target) >= acc.count {
                return Err(format!(
                    "{who}: sparse index {target} at item {k} is out of range: the accessor has \
                     {} elements",
                    acc.count
                ));
            }
            each(target as usize, &bytes[k * elem..(k + 1) * elem])?;
        }
    }
    Ok(())
}

/// The positions of a POSITION accessor: FLOAT VEC3, or (KHR_mesh_quantization) BYTE, SHORT,
/// UNSIGNED_BYTE or UNSIGNED_SHORT VEC3, normalized or not; the node transforms that place them
/// carry the dequantization.
pub(super) fn read_positions(
    acc: &Accessor,
    what: &str,
    buffers: &mut Buffers,
) -> Result<Vec<Vec3>, String> {
    if acc.components != 3 || acc.component == Component::U32 {
        return Err(format!(
            "{} is {} {}: expected VEC3 positions of FLOAT, or of BYTE, UNSIGNED_BYTE, SHORT or \
             UNSIGNED_SHORT (KHR_mesh_quantization)",
            acc.describe(what),
            acc.component.name(),
            acc.type_name
        ));
    }
    check_range(acc, what, buffers.doc)?;
    if acc.count > MAX_PLACED_VERTICES as u64 {
        return Err(format!(
            "{} has {} positions: more than {MAX_PLACED_VERTICES}, the most one model may place",
            acc.describe(what),
            acc.count
        ));
    }
    // Bounded by the budget (checked above); zeros where the accessor has no view.
    let mut out = vec![Vec3::ZERO; acc.count as usize];
    let (c, size, normalized) = (acc.component, acc.component.size(), acc.normalized);
    for_each_element(acc, what, buffers, |k, b| {
        let p = Vec3::new(
            c.value(b, normalized),
            c.value(&b[size..], normalized),
            c.value(&b[2 * size..], normalized),
        );
        if !p.is_finite() {
            return Err(format!(
                "{}: position {k} is not finite",
                acc.describe(what)
            ));
        }
        out[k] = p;
        Ok(())
    })?;
    Ok(out)
}

/// The indices of an indices accessor (unsigned byte, short or int SCALAR), each checked to
/// name one of the primitive's `vertices`.
pub(super) fn read_indices(
    acc: &Accessor,
    what: &str,
    buffers: &mut Buffers,
    vertices: usize,
) -> Result<Vec<u32>, String> {
    if !matches!(
        acc.component,
        Component::U8 | Component::U16 | Component::U32
    ) || acc.components != 1
    {
        return Err(format!(
            "{} is {} {}: expected unsigned byte, short or int SCALAR indices",
            acc.describe(what),
            acc.component.name(),
            acc.type_name
        ));
    }
    if acc.count / 3 > MAX_TRIANGLES as u64 {
        return Err(format!(
            "{} has {} indices: more than {MAX_TRIANGLES} triangles (the limit for one model)",
            acc.describe(what),
            acc.count
        ));
    }
    check_range(acc, what, buffers.doc)?;
    let mut out = vec![0u32; acc.count as usize];
    let c = acc.component;
    for_each_element(acc, what, buffers, |k, b| {
        out[k] = c.index(b);
        Ok(())
    })?;
    if let Some((k, &v)) = out
        .iter()
        .enumerate()
        .find(|(_, &v)| v as usize >= vertices)
    {
        return Err(format!(
            "{}: index {v} at item {k} is out of range: the primitive has {vertices} vertices",
            acc.describe(what)
        ));
    }
    Ok(out)
}

/// The elements of an accessor of `components` numbers each (VEC4 joints or weights, MAT4
/// inverse bind matrices), flattened, as numbers (integers as their values, or normalized);
/// `allowed` lists the component types glTF allows there. At most `most` elements.
pub(super) fn read_numbers(
    acc: &Accessor,
    what: &str,
    buffers: &mut Buffers,
    components: usize,
    allowed: &[Component],
    most: u64,
) -> Result<Vec<f32>, String> {
    if acc.components != components || !allowed.contains(&acc.component) {
        return Err(format!(
            "{} is {} {}: expected {} of {}",
            acc.describe(what),
            acc.component.name(),
            acc.type_name,
            match components {
                4 => "VEC4",
                16 => "MAT4",
                _ => "SCALAR",
            },
            allowed
                .iter()
                .map(|c| c.name())
                .collect::<Vec<_>>()
                .join(", ")
        ));
    }
    check_range(acc, what, buffers.doc)?;
    if acc.count > most {
        return Err(format!(
            "{} has {} elements: more than the {most} it may have here",
            acc.describe(what),
            acc.count
        ));
    }
    let mut out = vec![0f32; acc.count as usize * components];
    let (c, size, normalized) = (acc.component, acc.component.size(), acc.normalized);
    for_each_element(acc, what, buffers, |k, b| {
        for j in 0..components {
            out[k * components + j] = c.value(&b[j * size..], normalized);
        }
        Ok(())
    })?;
    Ok(out)
}
