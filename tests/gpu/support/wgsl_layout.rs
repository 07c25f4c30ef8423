//! WGSL struct layouts from naga, to test that a Rust `#[repr(C)]` GPU struct matches the WGSL
//! struct it is uploaded into (style item 5: a test, not a "keep in sync" comment).
//!
//! A module of the gpu test binary; a test module uses it with
//!
//! ```ignore
//! use crate::support::wgsl_layout;
//!
//! wgsl_layout::assert_layout::<Params>(
//!     &dbuffer::shader_source::load("penumbra.wgsl").unwrap(),
//!     "Params",
//!     &[("light", std::mem::offset_of!(Params, light)), ("radius", std::mem::offset_of!(Params, radius))],
//! );
//! ```
//!
//! or with the [`assert_wgsl_layout!`] shorthand, which takes field names once.
//!
//! Offsets are naga's (the WGSL layout rules, the same in every address space); whether a struct
//! may also be used as a uniform is the validator's business (`gpu::shaders`).
#![allow(dead_code)]

use naga::TypeInner;

/// `(size, [(member name, offset)])` of the WGSL struct `name` in `wgsl`, or `None` when `wgsl`
/// declares no struct of that name. Panics with naga's report when `wgsl` does not parse.
pub fn struct_layout(wgsl: &str, name: &str) -> Option<(u32, Vec<(String, u32)>)> {
    let module = match naga::front::wgsl::parse_str(wgsl) {
        Ok(module) => module,
        Err(e) => panic!("WGSL does not parse:\n{}", e.emit_to_string(wgsl)),
    };
    let layout = module.types.iter().find_map(|(_, ty)| match &ty.inner {
        TypeInner::Struct { members, span } if ty.name.as_deref() == Some(name) => Some((
            *span,
            members
                .iter()
                .map(|m| (m.name.clone().unwrap_or_default(), m.offset))
                .collect(),
        )),
        _ => None,
    });
    layout
}

/// Assert that the Rust type `T` has the layout of the WGSL struct `name`: the same size, and
/// `fields` (Rust field name, `std::mem::offset_of!`) are the WGSL members, with the same names,
/// in order, at the same offsets. Explicit Rust padding fields are left out of `fields`.
///
/// On a mismatch the message lists both layouts side by side.
pub fn assert_layout<T>(wgsl: &str, name: &str, fields: &[(&str, usize)]) {
    let rust_name = std::any::type_name::<T>();
    let Some((span, members)) = struct_layout(wgsl, name) else {
        panic!("the WGSL declares no struct `{name}` (checking the layout of {rust_name})");
    };
    let rust_size = std::mem::size_of::<T>();
    let same_size = usize::try_from(span).is_ok_and(|s| s == rust_size);
    let same_fields = members.len() == fields.len()
        && members
            .iter()
            .zip(fields)
            .all(|((wn, wo), (rn, ro))| wn == rn && usize::try_from(*wo).is_ok_and(|o| o == *ro));
    if same_size && same_fields {
        return;
    }

    let mut table = format!(
        "layout mismatch between WGSL struct `{name}` and Rust `{rust_name}`:\n\
         {:<24} {:>6}   {:<24} {:>6}\n",
        "WGSL member", "offset", "Rust field", "offset"
    );
    for i in 0..members.len().max(fields.len()) {
        let (wn, wo) = members
            .get(i)
            .map(|(n, o)| (n.as_str(), o.to_string()))
            .unwrap_or(("", String::new()));
        let (rn, ro) = fields
            .get(i)
            .map(|(n, o)| (*n, o.to_string()))
            .unwrap_or(("", String::new()));
        let differs = wn != rn || wo != ro;
        table.push_str(&format!(
            "{wn:<24} {wo:>6}   {rn:<24} {ro:>6}{}\n",
            if differs { "   <-- differs" } else { "" }
        ));
    }
    table.push_str(&format!(
        "{:<24} {span:>6}   {:<24} {rust_size:>6}{}\n",
        "(size)",
        "(size_of)",
        if same_size { "" } else { "   <-- differs" }
    ));
    panic!("{table}");
}

/// `assert_wgsl_layout!(RustType, wgsl, "WgslName", field_a, field_b, ..)`: [`assert_layout`]
/// with each field's offset taken by `std::mem::offset_of!` (Rust and WGSL names must agree).
macro_rules! assert_wgsl_layout {
    ($ty:ty, $wgsl:expr, $name:expr, $($field:ident),+ $(,)?) => {
        $crate::support::wgsl_layout::assert_layout::<$ty>(
            $wgsl,
            $name,
            &[$((stringify!($field), ::std::mem::offset_of!($ty, $field))),+],
        )
    };
}
pub(crate) use assert_wgsl_layout;

/// The value of the scalar WGSL `const` called `name` in `wgsl` (f32, u32, i32 or bool
/// literals), or `None` when there is none of that name.
pub fn const_value(wgsl: &str, name: &str) -> Option<f64> {
    let module = match naga::front::wgsl::parse_str(wgsl) {
        Ok(module) => module,
        Err(e) => panic!("WGSL does not parse:\n{}", e.emit_to_string(wgsl)),
    };
    let (_, c) = module
        .constants
        .iter()
        .find(|(_, c)| c.name.as_deref() == Some(name))?;
    match module.global_expressions[c.init] {
        naga::Expression::Literal(naga::Literal::F32(v)) => Some(f64::from(v)),
        naga::Expression::Literal(naga::Literal::U32(v)) => Some(f64::from(v)),
        naga::Expression::Literal(naga::Literal::I32(v)) => Some(f64::from(v)),
        naga::Expression::Literal(naga::Literal::Bool(v)) => Some(f64::from(u8::from(v))),
        naga::Expression::Literal(naga::Literal::AbstractInt(v)) => Some(v as f64),
        naga::Expression::Literal(naga::Literal::AbstractFloat(v)) => Some(v),
        ref other => panic!("`{name}` is not a scalar literal: {other:?}"),
    }
}

/// Assert that every `(WGSL const name, Rust value)` pair agrees.
pub fn assert_consts(wgsl: &str, file: &str, pairs: &[(&str, f64)]) {
    for &(name, rust) in pairs {
        match const_value(wgsl, name) {
            Some(v) => assert!(
                (v - rust).abs() <= 1e-9 * rust.abs().max(1.0),
                "{file}: const {name} is {v}, the Rust side says {rust}"
            ),
            None => panic!("{file} declares no const `{name}`"),
        }
    }
}

/// `(member name, type)` of the WGSL struct `name` in `wgsl`, each type as WGSL spells a scalar,
/// vector or matrix of 32-bit numbers (`u32`, `vec2<f32>`, `mat4x4<f32>`) and `?` for anything
/// else; `None` when `wgsl` declares no struct of that name.
pub fn member_types(wgsl: &str, name: &str) -> Option<Vec<(String, String)>> {
    let module = match naga::front::wgsl::parse_str(wgsl) {
        Ok(module) => module,
        Err(e) => panic!("WGSL does not parse:\n{}", e.emit_to_string(wgsl)),
    };
    let scalar = |s: &naga::Scalar| match (s.kind, s.width) {
        (naga::ScalarKind::Float, 4) => "f32",
        (naga::ScalarKind::Uint, 4) => "u32",
        (naga::ScalarKind::Sint, 4) => "i32",
        _ => "?",
    };
    let members = module.types.iter().find_map(|(_, ty)| match &ty.inner {
        TypeInner::Struct { members, .. } if ty.name.as_deref() == Some(name) => Some(members),
        _ => None,
    })?;
    Some(
        members
            .iter()
            .map(|m| {
                let ty = match &module.types[m.ty].inner {
                    TypeInner::Scalar(s) => scalar(s).to_owned(),
                    TypeInner::Vector { size, scalar: s } => {
                        format!("vec{}<{}>", *size as u8, scalar(s))
                    }
                    TypeInner::Matrix {
                        columns,
                        rows,
                        scalar: s,
                    } => format!("mat{}x{}<{}>", *columns as u8, *rows as u8, scalar(s)),
                    _ => "?".to_owned(),
                };
                (m.name.clone().unwrap_or_default(), ty)
            })
            .collect(),
    )
}

/// The WGSL type a Rust field of a GPU struct is uploaded as.
pub trait WgslType {
    fn wgsl() -> String;
}

impl WgslType for f32 {
    fn wgsl() -> String {
        "f32".to_owned()
    }
}

impl WgslType for u32 {
    fn wgsl() -> String {
        "u32".to_owned()
    }
}

impl WgslType for i32 {
    fn wgsl() -> String {
        "i32".to_owned()
    }
}

impl<T: WgslType, const N: usize> WgslType for [T; N] {
    fn wgsl() -> String {
        format!("vec{N}<{}>", T::wgsl())
    }
}

/// The WGSL type of the field `field` picks out of an `S`.
pub fn wgsl_type_of<S, T: WgslType>(_field: fn(&S) -> &T) -> String {
    T::wgsl()
}

/// Assert that the WGSL struct `name` has members `fields` (Rust field name, [`WgslType`]) with
/// those types, in order: a switch or count must be `u32` on both sides, a real number `f32`.
pub fn assert_types(wgsl: &str, name: &str, fields: &[(&str, String)]) {
    let Some(members) = member_types(wgsl, name) else {
        panic!("the WGSL declares no struct `{name}`");
    };
    let rust: Vec<(String, String)> = fields
        .iter()
        .map(|(n, t)| ((*n).to_owned(), t.clone()))
        .collect();
    assert_eq!(
        members, rust,
        "member types of WGSL struct `{name}` (left) and its Rust struct (right)"
    );
}

/// `assert_wgsl_params!(RustType, wgsl, "WgslName", field_a, ..)`: [`assert_wgsl_layout!`] with
/// every field listed (padding too), and [`assert_types`]: a method's parameters, whose fields
/// are all 32-bit scalars or vectors.
macro_rules! assert_wgsl_params {
    ($ty:ty, $wgsl:expr, $name:expr, $($field:ident),+ $(,)?) => {{
        $crate::support::wgsl_layout::assert_wgsl_layout!($ty, $wgsl, $name, $($field),+);
        $crate::support::wgsl_layout::assert_types(
            $wgsl,
            $name,
            &[$((
                stringify!($field),
                $crate::support::wgsl_layout::wgsl_type_of(|s: &$ty| &s.$field),
            )),+],
        );
    }};
}
pub(crate) use assert_wgsl_params;

/// A global `var<uniform>` of a WGSL module: its name, the name of its type (`None` for a type
/// without one, a bare `vec4<f32>`), and its group and binding.
#[derive(Clone, Debug, PartialEq)]
pub struct Uniform {
    pub var: String,
    pub ty: Option<String>,
    pub group: u32,
    pub binding: u32,
}

/// Every global `var<uniform>` of `wgsl`.
pub fn uniforms(wgsl: &str) -> Vec<Uniform> {
    let module = match naga::front::wgsl::parse_str(wgsl) {
        Ok(module) => module,
        Err(e) => panic!("WGSL does not parse:\n{}", e.emit_to_string(wgsl)),
    };
    let found = module
        .global_variables
        .iter()
        .filter(|(_, g)| g.space == naga::AddressSpace::Uniform)
        .map(|(_, g)| Uniform {
            var: g.name.clone().unwrap_or_default(),
            ty: module.types[g.ty].name.clone(),
            group: g.binding.as_ref().map_or(u32::MAX, |b| b.group),
            binding: g.binding.as_ref().map_or(u32::MAX, |b| b.binding),
        })
        .collect();
    found
}
