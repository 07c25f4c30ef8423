//! Built-in shapes, addressed by name from scene files.
//!
//! # Mesh-name syntax
//!
//! `NAME` or `NAME:PARAMS`, where `PARAMS` is one integer `N` or two integers `AxB`:
//!
//! | name          | parameters (default)          | size (before `scale`)                         | triangles        |
//! |---------------|-------------------------------|-----------------------------------------------|------------------|
//! | `plane`       | none                          | 1×1 in XZ at y = 0, facing +Y (open)           | 2                |
//! | `cube`        | none                          | unit cube centred at the origin                | 12               |
//! | `sphere`      | `SxK` slices × stacks (`32x16`) | radius 0.5; single pole vertices             | 2·S·(K−1)        |
//! | `icosphere`   | `N` subdivision level (`2`)   | radius 0.5                                     | 20·4ᴺ            |
//! | `torus`       | `MxN` ring × tube segments (`32x16`) | major radius 0.35, tube radius 0.15, in XZ | 2·M·N        |
//! | `cylinder`    | `S` segments (`32`)           | radius 0.5, height 1 along Y, capped, centred  | 4·S              |
//! | `cone`        | `S` segments (`32`)           | base radius 0.5 at y = −0.5, apex at y = 0.5   | 2·S              |
//! | `l-prism`     | none                          | L-shaped footprint 1×1 in XZ (concave), height 0.5 along Y, centred | 20 |
//! | `wedge`       | none                          | right-triangle footprint in XZ with a 15° corner, 1 long, height 0.5 along Y, centred | 8 |
//! | `rounded-box` | `SxK` like `sphere` (`32x16`) | convex superellipsoid (exponent 0.3) in the unit cube | 2·S·(K−1) |
//! | `torus-knot`  | `TxR` tubular × radial segments (`240x12`) | (2,3) knot in XZ, about 0.95 across | 2·T·R |
//! | `links`       | `MxN` like `torus` (`32x8`)   | two interlocked rings (major radius 0.35, tube radius 0.08), one in XZ and one in XY, 0.35 apart along X: one mesh of two closed parts | 4·M·N |
//! | `bunny`       | none                          | the Stanford bunny (`assets/bunny.obj`, embedded), ~10 units tall, feet at y ≈ 0; a decimated scan, closed (see `assets/README.md`) | 3674 |
//! | `bunny-open`  | none                          | `bunny` opened at its base: the triangles in the bottom 3 % of its height removed, as a range scan leaves them | fewer |
//!
//! Examples: `"sphere"`, `"sphere:16x8"`, `"torus:24x20"`, `"torus-knot:240x12"`, `"icosphere:3"`.
//!
//! Every shape except `plane` and `bunny-open` (and `bunny`, which is not generated) is closed, 2-manifold, welded (seams
//! share vertex indices; no two vertices have the same position) and wound counter-clockwise seen
//! from outside.

use super::Mesh;
use glam::{Vec2, Vec3};
use std::collections::HashMap;
use std::f32::consts::{PI, TAU};

/// The names of the built-in shapes, in the order the error messages list them.
pub const NAMES: &[&str] = &[
    "plane",
    "cube",
    "sphere",
    "icosphere",
    "torus",
    "cylinder",
    "cone",
    "l-prism",
    "wedge",
    "rounded-box",
    "torus-knot",
    "bunny",
    "bunny-open",
    "links",
];

pub use crate::budget::{
    MAX_ICOSPHERE_LEVEL, MAX_SHAPE_QUADS as MAX_QUADS, MAX_SHAPE_SEGMENTS as MAX_SEGMENTS,
};

/// Triangles of the embedded Stanford bunny (`bunny`); `bunny-open` has fewer.
pub const BUNNY_TRIANGLES: u64 = 3674;
/// Vertices of the embedded Stanford bunny.
pub const BUNNY_VERTICES: u64 = 1839;

/// Why a mesh name could not be turned into a shape.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum ShapeError {
    /// The part before `:` is not a built-in shape name.
    Unknown(String),
    /// The shape is known but its parameters are not valid; the string says what was expected.
    BadParams(String),
}

impl std::fmt::Display for ShapeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ShapeError::Unknown(name) => write!(
                f,
                "unknown shape {name:?}: expected one of {}",
                NAMES.join(", ")
            ),
            ShapeError::BadParams(expected) => f.write_str(expected),
        }
    }
}

impl std::error::Error for ShapeError {}

/// True if `name` (the part before any `:`) is a built-in shape name.
pub fn is_shape_name(name: &str) -> bool {
    let base = name.split(':').next().unwrap_or(name);
    NAMES.contains(&base)
}

/// Builds the built-in shape `name` (see the module documentation for the syntax).
pub fn build(name: &str) -> Result<Mesh, ShapeError> {
    Shape::parse(name)?.build()
}

/// The number of triangles `build(name)` makes, from the parameters alone (nothing is built):
/// exact for every shape but `bunny-open`, for which it is the bunny's count, an upper bound.
pub fn triangle_count(name: &str) -> Result<u64, ShapeError> {
    Shape::parse(name).map(Shape::triangles)
}

/// A built-in shape and its parameters, parsed from a mesh name and checked against the budget
/// ([`MAX_SEGMENTS`], [`MAX_QUADS`], [`MAX_ICOSPHERE_LEVEL`]); nothing is built yet.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    Plane,
    Cube,
    LPrism,
    Wedge,
    Bunny,
    BunnyOpen,
    Sphere(u32, u32),
    RoundedBox(u32, u32),
    Torus(u32, u32),
    TorusKnot(u32, u32),
    Links(u32, u32),
    Cylinder(u32),
    Cone(u32),
    Icosphere(u32),
}

impl Shape {
    /// Parses `NAME` or `NAME:PARAMS` (see the module documentation).
    pub fn parse(name: &str) -> Result<Shape, ShapeError> {
        let (base, params) = match name.split_once(':') {
            Some((b, p)) => (b, Some(p)),
            None => (name, None),
        };
        Ok(match base {
            "plane" => none(base, params).map(|()| Shape::Plane)?,
            "cube" => none(base, params).map(|()| Shape::Cube)?,
            "l-prism" => none(base, params).map(|()| Shape::LPrism)?,
            "wedge" => none(base, params).map(|()| Shape::Wedge)?,
            "bunny" => none(base, params).map(|()| Shape::Bunny)?,
            "bunny-open" => none(base, params).map(|()| Shape::BunnyOpen)?,
            "sphere" => {
                let (s, k) = two(base, params, (32, 16), (3, 2))?;
                Shape::Sphere(s, k)
            }
            "rounded-box" => {
                let (s, k) = two(base, params, (32, 16), (3, 2))?;
                Shape::RoundedBox(s, k)
            }
            "torus" => {
                let (m, n) = two(base, params, (32, 16), (3, 3))?;
                Shape::Torus(m, n)
            }
            "torus-knot" => {
                let (t, r) = two(base, params, (240, 12), (8, 3))?;
                Shape::TorusKnot(t, r)
            }
            "links" => {
                let (m, n) = two(base, params, (32, 8), (3, 3))?;
                Shape::Links(m, n)
            }
            "cylinder" => Shape::Cylinder(one(base, params, 32, 3, MAX_SEGMENTS)?),
            "cone" => Shape::Cone(one(base, params, 32, 3, MAX_SEGMENTS)?),
            "icosphere" => Shape::Icosphere(one(base, params, 2, 0, MAX_ICOSPHERE_LEVEL)?),
            _ => return Err(ShapeError::Unknown(base.to_string())),
        })
    }

    /// The number of triangles [`Shape::build`] makes (for `bunny-open`, an upper bound).
    pub fn triangles(self) -> u64 {
        let w = u64::from;
        match self {
            Shape::Plane => 2,
            Shape::Cube => 12,
            Shape::LPrism => 20,
            Shape::Wedge => 8,
            Shape::Bunny | Shape::BunnyOpen => BUNNY_TRIANGLES,
            Shape::Sphere(s, k) | Shape::RoundedBox(s, k) => 2 * w(s) * (w(k) - 1),
            Shape::Torus(m, n) | Shape::TorusKnot(m, n) => 2 * w(m) * w(n),
            Shape::Links(m, n) => 4 * w(m) * w(n),
            Shape::Cylinder(s) => 4 * w(s),
            Shape::Cone(s) => 2 * w(s),
            Shape::Icosphere(level) => 20 << (2 * level),
        }
    }

    /// The number of vertices [`Shape::build`] makes (for `bunny-open`, an upper bound).
    pub fn vertices(self) -> u64 {
        let w = u64::from;
        match self {
            Shape::Plane => 4,
            Shape::Cube => 8,
            Shape::LPrism => 12,
            Shape::Wedge => 6,
            Shape::Bunny | Shape::BunnyOpen => BUNNY_VERTICES,
            Shape::Sphere(s, k) | Shape::RoundedBox(s, k) => w(s) * (w(k) - 1) + 2,
            Shape::Torus(m, n) | Shape::TorusKnot(m, n) => w(m) * w(n),
            Shape::Links(m, n) => 2 * w(m) * w(n),
            Shape::Cylinder(s) => 2 * w(s) + 2,
            Shape::Cone(s) => w(s) + 2,
            Shape::Icosphere(level) => 10 * (1 << (2 * level)) + 2,
        }
    }

    /// Builds the mesh.
    pub fn build(self) -> Result<Mesh, ShapeError> {
        let embedded = |e: super::SceneError| ShapeError::BadParams(format!("embedded bunny: {e}"));
        Ok(match self {
            Shape::Plane => plane(),
            Shape::Cube => cube(),
            Shape::LPrism => l_prism(),
            Shape::Wedge => wedge(),
            Shape::Bunny => bunny().map_err(embedded)?,
            Shape::BunnyOpen => open_base(&bunny().map_err(embedded)?, BUNNY_OPEN_BASE),
            Shape::Sphere(s, k) => sphere(s, k),
            Shape::RoundedBox(s, k) => rounded_box(s, k),
            Shape::Torus(m, n) => torus(m, n),
            Shape::TorusKnot(t, r) => torus_knot(t, r),
            Shape::Links(m, n) => links(m, n),
            Shape::Cylinder(s) => cylinder(s),
            Shape::Cone(s) => cone(s),
            Shape::Icosphere(level) => icosphere(level),
        })
    }
}

fn none(base: &str, params: Option<&str>) -> Result<(), ShapeError> {
    match params {
        None => Ok(()),
        Some(p) => Err(ShapeError::BadParams(format!(
            "`{base}` takes no parameters, found `:{}`",
            super::shown(p)
        ))),
    }
}

fn one(
    base: &str,
    params: Option<&str>,
    default: u32,
    min: u32,
    max: u32,
) -> Result<u32, ShapeError> {
    let Some(p) = params else { return Ok(default) };
    match p.trim().parse::<u32>() {
        Ok(n) if (min..=max).contains(&n) => Ok(n),
        _ => Err(ShapeError::BadParams(format!(
            "`{base}:N` expects an integer N in {min}..={max}, found `{}`",
            super::shown(p)
        ))),
    }
}

fn two(
    base: &str,
    params: Option<&str>,
    default: (u32, u32),
    min: (u32, u32),
) -> Result<(u32, u32), ShapeError> {
    let Some(p) = params else { return Ok(default) };
    let bad = || {
        ShapeError::BadParams(format!(
            "`{base}:AxB` expects two integers A in {}..={MAX_SEGMENTS} and B in \
             {}..={MAX_SEGMENTS} (MAX_SHAPE_SEGMENTS), found `{}`",
            min.0,
            min.1,
            super::shown(p)
        ))
    };
    let (a, b) = p.split_once(['x', 'X']).ok_or_else(bad)?;
    let a: u32 = a.trim().parse().map_err(|_| bad())?;
    let b: u32 = b.trim().parse().map_err(|_| bad())?;
    if a < min.0 || b < min.1 || a > MAX_SEGMENTS || b > MAX_SEGMENTS {
        return Err(bad());
    }
    if a as u64 * b as u64 > MAX_QUADS {
        return Err(ShapeError::BadParams(format!(
            "`{base}:{a}x{b}` would have {} triangles: expected A·B at most {MAX_QUADS} \
             (MAX_SHAPE_QUADS, the budget of one shape)",
            2 * a as u64 * b as u64
        )));
    }
    Ok((a, b))
}

/// Share of the bunny's height whose triangles `bunny-open` removes.
pub const BUNNY_OPEN_BASE: f32 = 0.03;

/// `mesh` without the triangles that lie entirely in the bottom `share` of its height: the mesh
/// opened at its base, as range scans are (the scanner cannot see under the object). The npm
/// bunny is the scan with its holes filled; `bunny-open` gives the lab an open boundary of the
/// kind users' scanned meshes have.
pub fn open_base(mesh: &Mesh, share: f32) -> Mesh {
    let Some((lo, hi)) = mesh.bounds() else {
        return mesh.clone();
    };
    let cut = lo.y + share * (hi.y - lo.y);
    let triangles = mesh
        .triangles
        .iter()
        .copied()
        .filter(|t| t.iter().any(|&k| mesh.positions[k as usize].y > cut))
        .collect();
    Mesh::new(mesh.positions.clone(), triangles)
}

/// The embedded Stanford bunny, as the npm package `bunny` has it (any holes kept as they are).
pub fn bunny() -> Result<Mesh, super::SceneError> {
    super::obj::parse_obj_str(include_str!("../../assets/bunny.obj"), "built-in bunny.obj")
}

/// 1×1 square in XZ at y = 0, facing +Y: 4 vertices, 2 triangles (open).
pub fn plane() -> Mesh {
    let positions = vec![
        Vec3::new(-0.5, 0.0, -0.5),
        Vec3::new(0.5, 0.0, -0.5),
        Vec3::new(0.5, 0.0, 0.5),
        Vec3::new(-0.5, 0.0, 0.5),
    ];
    // Counter-clockwise seen from +Y: (p2 - p0) × (p1 - p0) = (1,0,1) × (1,0,0) = (0,1,0).
    Mesh::new(positions, vec![[0, 2, 1], [0, 3, 2]])
}

/// Unit cube centred at the origin: 8 vertices, 12 triangles.
pub fn cube() -> Mesh {
    let mut positions = Vec::with_capacity(8);
    for i in 0..8u32 {
        let c = |bit: u32| if i & bit != 0 { 0.5 } else { -0.5 };
        positions.push(Vec3::new(c(1), c(2), c(4)));
    }
    // Each face as a quad, counter-clockwise seen from outside.
    let quads = [
        [0, 4, 6, 2], // -X
        [1, 3, 7, 5], // +X
        [0, 1, 5, 4], // -Y
        [2, 6, 7, 3], // +Y
        [0, 2, 3, 1], // -Z
        [4, 5, 7, 6], // +Z
    ];
    let mut triangles = Vec::with_capacity(12);
    for q in quads {
        push_quad(&mut triangles, q);
    }
    Mesh::new(positions, triangles)
}

/// Pushes quad `a b c d` (counter-clockwise from outside) as triangles `a b c`, `a c d`.
fn push_quad(tris: &mut Vec<[u32; 3]>, [a, b, c, d]: [u32; 4]) {
    tris.push([a, b, c]);
    tris.push([a, c, d]);
}

/// A closed surface with UV topology and single pole vertices: `point(theta, phi)` with
/// `phi = 0` the north pole (+Y), `phi = π` the south pole, theta around +Y such that
/// ∂/∂θ × ∂/∂φ points outward. `slices × (stacks − 1)` ring vertices plus 2 poles,
/// `2·slices·(stacks − 1)` triangles. The seam closes by index wrap-around.
fn uv_closed(slices: u32, stacks: u32, point: impl Fn(f32, f32) -> Vec3) -> Mesh {
    let s = slices;
    let k = stacks;
    let mut positions = Vec::with_capacity((s * (k - 1) + 2) as usize);
    positions.push(point(0.0, 0.0));
    for i in 1..k {
        let phi = PI * i as f32 / k as f32;
        for j in 0..s {
            positions.push(point(TAU * j as f32 / s as f32, phi));
        }
    }
    positions.push(point(0.0, PI));
    let north = 0;
    let south = s * (k - 1) + 1;
    let ring = |i: u32, j: u32| 1 + (i - 1) * s + j % s;
    let mut tris = Vec::with_capacity((2 * s * (k - 1)) as usize);
    for j in 0..s {
        tris.push([north, ring(1, j + 1), ring(1, j)]);
    }
    for i in 1..k - 1 {
        for j in 0..s {
            push_quad(
                &mut tris,
                [
                    ring(i, j),
                    ring(i, j + 1),
                    ring(i + 1, j + 1),
                    ring(i + 1, j),
                ],
            );
        }
    }
    for j in 0..s {
        tris.push([ring(k - 1, j), ring(k - 1, j + 1), south]);
    }
    // The loop above wound with ∂θ then ∂φ; flip if that turned out inward for this `point`.
    let mut mesh = Mesh::new(positions, tris);
    orient_outward(&mut mesh);
    mesh
}

/// UV sphere of radius 0.5: `2·slices·(stacks − 1)` triangles.
pub fn sphere(slices: u32, stacks: u32) -> Mesh {
    uv_closed(slices, stacks, |theta, phi| {
        // Exact poles: cos/sin of π are not exactly -1/0 in floating point.
        if phi == 0.0 {
            return Vec3::new(0.0, 0.5, 0.0);
        }
        if phi == PI {
            return Vec3::new(0.0, -0.5, 0.0);
        }
        0.5 * Vec3::new(phi.sin() * theta.cos(), phi.cos(), phi.sin() * theta.sin())
    })
}

/// `sign(x)·|x|^e`.
fn spow(x: f32, e: f32) -> f32 {
    x.signum() * x.abs().powf(e)
}

/// Superellipsoid exponent of `rounded-box`: < 1 is box-like, 1 a sphere; ≤ 1 keeps it convex.
const ROUNDED_BOX_EXPONENT: f32 = 0.3;

/// A convex superellipsoid filling the unit cube, with the sphere's UV topology:
/// `2·slices·(stacks − 1)` triangles. Every ring is a scaled copy of one convex superellipse and
/// the profile is convex too, so every quad is a planar trapezoid and the polyhedron is convex.
pub fn rounded_box(slices: u32, stacks: u32) -> Mesh {
    let e = ROUNDED_BOX_EXPONENT;
    uv_closed(slices, stacks, |theta, phi| {
        if phi == 0.0 {
            return Vec3::new(0.0, 0.5, 0.0);
        }
        if phi == PI {
            return Vec3::new(0.0, -0.5, 0.0);
        }
        let r = spow(phi.sin(), e);
        0.5 * Vec3::new(
            r * spow(theta.cos(), e),
            spow(phi.cos(), e),
            r * spow(theta.sin(), e),
        )
    })
}

/// Icosahedron of circumradius 0.5 subdivided `level` times, projected to the sphere:
/// `20·4^level` triangles.
pub fn icosphere(level: u32) -> Mesh {
    let t = (1.0 + 5f32.sqrt()) / 2.0;
    let mut positions: Vec<Vec3> = [
        [-1.0, t, 0.0],
        [1.0, t, 0.0],
        [-1.0, -t, 0.0],
        [1.0, -t, 0.0],
        [0.0, -1.0, t],
        [0.0, 1.0, t],
        [0.0, -1.0, -t],
        [0.0, 1.0, -t],
        [t, 0.0, -1.0],
        [t, 0.0, 1.0],
        [-t, 0.0, -1.0],
        [-t, 0.0, 1.0],
    ]
    .iter()
    .map(|&p| Vec3::from_array(p).normalize() * 0.5)
    .collect();
    let mut tris: Vec<[u32; 3]> = vec![
        [0, 11, 5],
        [0, 5, 1],
        [0, 1, 7],
        [0, 7, 10],
        [0, 10, 11],
        [1, 5, 9],
        [5, 11, 4],
        [11, 10, 2],
        [10, 7, 6],
        [7, 1, 8],
        [3, 9, 4],
        [3, 4, 2],
        [3, 2, 6],
        [3, 6, 8],
        [3, 8, 9],
        [4, 9, 5],
        [2, 4, 11],
        [6, 2, 10],
        [8, 6, 7],
        [9, 8, 1],
    ];
    for _ in 0..level {
        let mut mid: HashMap<(u32, u32), u32> = HashMap::new();
        let mut midpoint = |a: u32, b: u32, positions: &mut Vec<Vec3>| -> u32 {
            let key = (a.min(b), a.max(b));
            *mid.entry(key).or_insert_with(|| {
                let p = (positions[a as usize] + positions[b as usize]).normalize() * 0.5;
                positions.push(p);
                (positions.len() - 1) as u32
            })
        };
        let mut next = Vec::with_capacity(tris.len() * 4);
        for [a, b, c] in tris {
            let ab = midpoint(a, b, &mut positions);
            let bc = midpoint(b, c, &mut positions);
            let ca = midpoint(c, a, &mut positions);
            next.extend([[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
        }
        tris = next;
    }
    let mut mesh = Mesh::new(positions, tris);
    orient_outward(&mut mesh);
    mesh
}

/// A closed surface with torus topology: `point(u, v)` for u, v in [0, 2π), both seams closed by
/// index wrap-around. `2·nu·nv` triangles.
fn torus_grid(nu: u32, nv: u32, point: impl Fn(f32, f32) -> Vec3) -> Mesh {
    let mut positions = Vec::with_capacity((nu * nv) as usize);
    for i in 0..nu {
        let u = TAU * i as f32 / nu as f32;
        for j in 0..nv {
            positions.push(point(u, TAU * j as f32 / nv as f32));
        }
    }
    let idx = |i: u32, j: u32| (i % nu) * nv + j % nv;
    let mut tris = Vec::with_capacity((2 * nu * nv) as usize);
    for i in 0..nu {
        for j in 0..nv {
            push_quad(
                &mut tris,
                [idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)],
            );
        }
    }
    let mut mesh = Mesh::new(positions, tris);
    orient_outward(&mut mesh);
    mesh
}

/// Torus in XZ around +Y: major radius 0.35, tube radius 0.15; `2·ring·tube` triangles.
pub fn torus(ring: u32, tube: u32) -> Mesh {
    let (big, small) = (0.35, 0.15);
    torus_grid(ring, tube, |u, v| {
        let w = big + small * v.cos();
        Vec3::new(w * u.cos(), small * v.sin(), w * u.sin())
    })
}

/// Two interlocked rings as one mesh (a chain's two links): major radius 0.35, tube radius 0.08;
/// one in XZ centred at x = −0.175, the other in XY centred at x = +0.175, so each passes
/// through the middle of the other's hole (0.27 wide around it) without touching: `4·ring·tube`
/// triangles, two closed parts.
pub fn links(ring: u32, tube: u32) -> Mesh {
    let (big, small, apart) = (0.35, 0.08, 0.175);
    let flat = torus_grid(ring, tube, |u, v| {
        let w = big + small * v.cos();
        Vec3::new(w * u.cos() - apart, small * v.sin(), w * u.sin())
    });
    let upright = torus_grid(ring, tube, |u, v| {
        let w = big + small * v.cos();
        Vec3::new(w * u.cos() + apart, w * u.sin(), small * v.sin())
    });
    let offset = flat.positions.len() as u32;
    let mut positions = flat.positions;
    positions.extend(upright.positions);
    let mut triangles = flat.triangles;
    triangles.extend(upright.triangles.iter().map(|t| t.map(|k| k + offset)));
    Mesh::new(positions, triangles)
}

/// A (2,3) torus knot tube, about 0.95 across in XZ: `2·tubular·radial` triangles.
pub fn torus_knot(tubular: u32, radial: u32) -> Mesh {
    const P: f32 = 2.0;
    const Q: f32 = 3.0;
    const SCALE: f32 = 0.25;
    let (big, small, tube) = (1.0 * SCALE, 0.5 * SCALE, 0.3 * SCALE);
    let curve = |t: f32| {
        let w = big + small * (Q * t).cos();
        Vec3::new(w * (P * t).cos(), small * (Q * t).sin(), w * (P * t).sin())
    };
    let tangent = |t: f32| {
        let w = big + small * (Q * t).cos();
        let dw = -small * Q * (Q * t).sin();
        Vec3::new(
            dw * (P * t).cos() - w * P * (P * t).sin(),
            small * Q * (Q * t).cos(),
            dw * (P * t).sin() + w * P * (P * t).cos(),
        )
    };
    torus_grid(tubular, radial, |u, v| {
        let c = curve(u);
        let t = tangent(u).normalize();
        // A frame that is a periodic function of u, so the tube closes without a twist seam:
        // the binormal is perpendicular to the tangent and to the (never parallel) radius vector.
        let b = t.cross(c).normalize();
        let n = b.cross(t);
        c + tube * (v.cos() * n + v.sin() * b)
    })
}

/// Capped cylinder, radius 0.5, y in [-0.5, 0.5]: `4·segments` triangles.
pub fn cylinder(segments: u32) -> Mesh {
    let s = segments;
    let mut positions = vec![Vec3::new(0.0, 0.5, 0.0), Vec3::new(0.0, -0.5, 0.0)];
    for y in [0.5, -0.5] {
        for j in 0..s {
            let a = TAU * j as f32 / s as f32;
            positions.push(Vec3::new(0.5 * a.cos(), y, 0.5 * a.sin()));
        }
    }
    let top = |j: u32| 2 + j % s;
    let bot = |j: u32| 2 + s + j % s;
    let mut tris = Vec::with_capacity((4 * s) as usize);
    for j in 0..s {
        tris.push([0, top(j + 1), top(j)]);
        tris.push([1, bot(j), bot(j + 1)]);
        push_quad(&mut tris, [top(j), top(j + 1), bot(j + 1), bot(j)]);
    }
    let mut mesh = Mesh::new(positions, tris);
    orient_outward(&mut mesh);
    mesh
}

/// Capped cone, base radius 0.5 at y = -0.5, apex at y = 0.5: `2·segments` triangles.
pub fn cone(segments: u32) -> Mesh {
    let s = segments;
    let mut positions = vec![Vec3::new(0.0, 0.5, 0.0), Vec3::new(0.0, -0.5, 0.0)];
    for j in 0..s {
        let a = TAU * j as f32 / s as f32;
        positions.push(Vec3::new(0.5 * a.cos(), -0.5, 0.5 * a.sin()));
    }
    let rim = |j: u32| 2 + j % s;
    let mut tris = Vec::with_capacity((2 * s) as usize);
    for j in 0..s {
        tris.push([0, rim(j + 1), rim(j)]);
        tris.push([1, rim(j), rim(j + 1)]);
    }
    let mut mesh = Mesh::new(positions, tris);
    orient_outward(&mut mesh);
    mesh
}

/// A prism: the simple polygon `outline` (in the XZ plane, any orientation) triangulated by
/// `caps` (indices into `outline`), extruded over y in [-height/2, height/2].
fn prism(outline: &[Vec2], caps: &[[u32; 3]], height: f32) -> Mesh {
    let n = outline.len() as u32;
    let h = height / 2.0;
    let mut positions = Vec::with_capacity(2 * outline.len());
    for y in [h, -h] {
        positions.extend(outline.iter().map(|p| Vec3::new(p.x, y, p.y)));
    }
    // Cap triangles wound so their normal is +Y on top (bottom reversed).
    let up = |[a, b, c]: [u32; 3]| {
        let p = |i: u32| positions[i as usize];
        (p(b) - p(a)).cross(p(c) - p(a)).y > 0.0
    };
    let mut tris = Vec::with_capacity(2 * caps.len() + 2 * outline.len());
    for &[a, b, c] in caps {
        let t = if up([a, b, c]) { [a, b, c] } else { [a, c, b] };
        tris.push(t);
        tris.push([t[0] + n, t[2] + n, t[1] + n]);
    }
    // Side quads: orientation follows the caps' (checked by the polygon's signed area).
    let area: f32 = (0..outline.len())
        .map(|i| outline[i].perp_dot(outline[(i + 1) % outline.len()]))
        .sum();
    for i in 0..n {
        let j = (i + 1) % n;
        // With +Y up (right-handed), an outline counter-clockwise in (x, z) runs clockwise seen
        // from above, so the +Y top cap traverses its edges j -> i and the side quad i -> j.
        let q = if area > 0.0 {
            [i, j, j + n, i + n]
        } else {
            [j, i, i + n, j + n]
        };
        push_quad(&mut tris, q);
    }
    let mut mesh = Mesh::new(positions, tris);
    orient_outward(&mut mesh);
    mesh
}

/// L-shaped prism: a 1×1 footprint with a 0.6×0.6 square cut from one corner (concave),
/// height 0.5, centred at the origin: 12 vertices, 20 triangles.
pub fn l_prism() -> Mesh {
    let outline: Vec<Vec2> = [
        [0.0, 0.0],
        [1.0, 0.0],
        [1.0, 0.4],
        [0.4, 0.4],
        [0.4, 1.0],
        [0.0, 1.0],
    ]
    .iter()
    .map(|&p| Vec2::from_array(p) - Vec2::splat(0.5))
    .collect();
    // A fan from the outer corner 0, which sees every other vertex of the L.
    prism(&outline, &[[0, 1, 2], [0, 2, 3], [0, 3, 4], [0, 4, 5]], 0.5)
}

/// The acute angle of `wedge`, in degrees.
pub const WEDGE_ANGLE_DEG: f32 = 15.0;

/// Triangular prism whose footprint (XZ) is a right triangle with a 15° corner and legs 1 and
/// tan 15°, height 0.5, centred on its bounding box: 6 vertices, 8 triangles.
pub fn wedge() -> Mesh {
    let t = WEDGE_ANGLE_DEG.to_radians().tan();
    let outline: Vec<Vec2> = [[0.0, 0.0], [1.0, 0.0], [1.0, t]]
        .iter()
        .map(|&p| Vec2::from_array(p) - Vec2::new(0.5, t / 2.0))
        .collect();
    prism(&outline, &[[0, 1, 2]], 0.5)
}

/// Signed volume enclosed by the mesh (positive when closed and wound outward).
pub fn signed_volume(mesh: &Mesh) -> f32 {
    mesh.triangle_corners()
        .map(|[a, b, c]| a.dot(b.cross(c)) as f64)
        .sum::<f64>() as f32
        / 6.0
}

/// Reverses every triangle if the enclosed volume is negative (for closed, consistently wound
/// meshes this makes them face outward).
fn orient_outward(mesh: &mut Mesh) {
    if signed_volume(mesh) < 0.0 {
        for t in &mut mesh.triangles {
            t.swap(1, 2);
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_and_counts() {
        assert_eq!(build("sphere:16x8").unwrap().triangles.len(), 224);
        assert_eq!(build("sphere").unwrap().triangles.len(), 2 * 32 * 15);
        assert_eq!(build("icosphere:3").unwrap().triangles.len(), 20 * 64);
        assert_eq!(build("torus:24x20").unwrap().triangles.len(), 2 * 24 * 20);
        assert_eq!(build("torus-knot:240x12").unwrap().triangles.len(), 5760);
        assert_eq!(build("rounded-box:48x16").unwrap().triangles.len(), 1440);
        assert_eq!(build("cylinder:10").unwrap().triangles.len(), 40);
        assert_eq!(build("cone:10").unwrap().triangles.len(), 20);
    }

    /// Each ring of `links` passes through the other's hole without touching it: every vertex of
    /// one lies farther than the tube radius from the other's core circle.
    #[test]
    fn links_interlock_without_touching() {
        let m = links(48, 8);
        let half = m.positions.len() / 2;
        let (big, small, apart) = (0.35f32, 0.08f32, 0.175f32);
        // Distance from p to the core circle of the flat ring (XZ, centre x = −apart).
        let to_flat = |p: Vec3| {
            let q = p + Vec3::X * apart;
            let radial = Vec2::new(q.x, q.z).length() - big;
            (radial * radial + q.y * q.y).sqrt()
        };
        let to_upright = |p: Vec3| {
            let q = p - Vec3::X * apart;
            let radial = Vec2::new(q.x, q.y).length() - big;
            (radial * radial + q.z * q.z).sqrt()
        };
        let gap = m.positions[half..]
            .iter()
            .map(|&p| to_flat(p))
            .chain(m.positions[..half].iter().map(|&p| to_upright(p)))
            .fold(f32::INFINITY, f32::min);
        assert!(gap > small * 1.2, "closest approach {gap}");
        // Linked: the upright ring crosses the flat ring's plane inside its hole.
        let inside = m.positions[half..]
            .iter()
            .filter(|p| p.y.abs() < 0.02)
            .filter(|p| Vec2::new(p.x + apart, p.z).length() < big - small)
            .count();
        assert!(
            inside > 0,
            "the upright ring passes through the flat one's hole"
        );
    }

    #[test]
    fn triangle_count_is_known_before_building() {
        for name in [
            "plane",
            "cube",
            "l-prism",
            "wedge",
            "bunny",
            "sphere",
            "sphere:3x2",
            "sphere:17x9",
            "rounded-box:5x4",
            "torus:3x3",
            "torus:7x5",
            "torus-knot:8x3",
            "torus-knot",
            "cylinder:3",
            "cylinder:31",
            "cone:7",
            "icosphere:0",
            "icosphere:3",
        ] {
            let mesh = build(name).unwrap();
            assert_eq!(
                triangle_count(name).unwrap(),
                mesh.triangles.len() as u64,
                "{name}"
            );
            let shape = Shape::parse(name).unwrap();
            assert_eq!(shape.vertices(), mesh.positions.len() as u64, "{name}");
        }
        let open = build("bunny-open").unwrap().triangles.len() as u64;
        assert!(open <= triangle_count("bunny-open").unwrap());
        // The largest shapes are counted, not built.
        assert_eq!(triangle_count("sphere:2000x1000").unwrap(), 3_996_000);
        assert_eq!(triangle_count("torus:2000x1000").unwrap(), 4_000_000);
        assert_eq!(triangle_count("icosphere:7").unwrap(), 20 * 4u64.pow(7));
        assert!(triangle_count("sphere:2001x1000").is_err());
    }

    #[test]
    fn bad_names_and_params() {
        assert_eq!(build("blob"), Err(ShapeError::Unknown("blob".into())));
        let msg = build("blob:3").unwrap_err().to_string();
        assert!(
            msg.contains("\"blob\"") && msg.contains("torus-knot, bunny"),
            "{msg}"
        );
        for bad in [
            "sphere:2x8",
            "sphere:16",
            "sphere:axb",
            "cube:3",
            "icosphere:9",
            "cone:-1",
        ] {
            assert!(matches!(build(bad), Err(ShapeError::BadParams(_))), "{bad}");
        }
        assert!(matches!(
            build("sphere:99999x8"),
            Err(ShapeError::BadParams(_))
        ));
    }

    #[test]
    fn plane_faces_up() {
        let m = plane();
        for [a, b, c] in m.triangle_corners() {
            assert!((b - a).cross(c - a).y > 0.0);
        }
    }

    #[test]
    fn huge_meshes_are_refused() {
        assert!(matches!(
            build("torus-knot:4096x4096"),
            Err(ShapeError::BadParams(_))
        ));
        assert!(build("sphere:2000x1000").is_ok());
    }

    /// The knot's tube never meets itself: points of the centre curve farther apart along the
    /// curve than the tube's diameter are farther apart in space than the diameter.
    #[test]
    fn torus_knot_tube_does_not_self_intersect() {
        let m = torus_knot(480, 3);
        // Ring centres: the mean of each ring of `radial` vertices.
        let centres: Vec<Vec3> = m
            .positions
            .chunks(3)
            .map(|r| (r[0] + r[1] + r[2]) / 3.0)
            .collect();
        let tube = (m.positions[0] - centres[0]).length();
        let n = centres.len();
        let mut along = vec![0.0f32; n + 1];
        for i in 0..n {
            along[i + 1] = along[i] + (centres[(i + 1) % n] - centres[i]).length();
        }
        let total = along[n];
        for i in 0..n {
            for j in i + 1..n {
                let arc = (along[j] - along[i]).min(total - (along[j] - along[i]));
                if arc > 4.0 * tube {
                    let d = (centres[i] - centres[j]).length();
                    assert!(
                        d > 2.2 * tube,
                        "rings {i} and {j}: {d} apart, tube radius {tube}"
                    );
                }
            }
        }
    }

    #[test]
    fn wedge_has_the_acute_angle() {
        let m = wedge();
        let p = |i: usize| m.positions[i];
        let angle = (p(1) - p(0)).angle_between(p(2) - p(0)).to_degrees();
        assert!((angle - 15.0).abs() < 1e-3, "{angle}");
    }
}
