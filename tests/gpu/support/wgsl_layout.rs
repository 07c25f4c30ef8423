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
