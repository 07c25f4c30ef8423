//! The scene's light: a one-sided planar light (a disk, a rectangle or a convex polygon) or a
//! linear light (a segment). The shape operations the methods share (support points, the area
//! beyond a chord, samples) are in `geometry::outline`; this module holds what a light *is*.

use glam::{DVec3, Vec3};

/// The most vertices a polygon light may have (docs/guide/scene-format.md): enough for any shape
/// a user draws by hand, few enough that every pass can keep them in a uniform.
pub const MAX_POLYGON_VERTICES: usize = 16;

/// A polygon light's non-planarity allowed, as a share of its diameter.
pub const POLYGON_PLANARITY: f64 = 1e-4;

/// The corners of a convex polygon light in world space, counter-clockwise seen from the side
/// it emits to. Kept in a fixed array so a light stays `Copy`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Polygon {
    points: [Vec3; MAX_POLYGON_VERTICES],
    len: u8,
}

impl Polygon {
    /// The first [`MAX_POLYGON_VERTICES`] of `points` (a caller checks the polygon first:
    /// [`check_polygon`]).
    pub fn new(points: &[Vec3]) -> Polygon {
        let mut p = Polygon {
            points: [Vec3::ZERO; MAX_POLYGON_VERTICES],
            len: points.len().min(MAX_POLYGON_VERTICES) as u8,
        };
        p.points[..p.len as usize].copy_from_slice(&points[..p.len as usize]);
        p
    }

    pub fn vertices(&self) -> &[Vec3] {
        &self.points[..self.len as usize]
    }

    pub fn len(&self) -> usize {
        self.len as usize
    }

    pub fn is_empty(&self) -> bool {
        self.len == 0
    }

    /// Newell's normal: twice the area times the unit normal by the right-hand rule.
    pub fn area_normal(&self) -> Vec3 {
        let v = self.vertices();
        let o = v.first().copied().unwrap_or(Vec3::ZERO);
        (0..v.len())
            .map(|i| (v[i] - o).cross(v[(i + 1) % v.len()] - o))
            .sum()
    }

    pub fn area(&self) -> f32 {
        0.5 * self.area_normal().length()
    }

    /// The centre of its area (the mean of the vertices where the area is zero).
    pub fn centroid(&self) -> Vec3 {
        let v = self.vertices();
        if v.is_empty() {
            return Vec3::ZERO;
        }
        let n = self.area_normal();
        let (mut sum, mut weight) = (Vec3::ZERO, 0.0);
        for i in 1..v.len().saturating_sub(1) {
            let w = (v[i] - v[0]).cross(v[i + 1] - v[0]).dot(n);
            sum += (v[0] + v[i] + v[i + 1]) / 3.0 * w;
            weight += w;
        }
        if weight.abs() > 0.0 {
            sum / weight
        } else {
            v.iter().sum::<Vec3>() / v.len() as f32
        }
    }

    fn map(&self, f: impl Fn(Vec3) -> Vec3) -> Polygon {
        let mut out = *self;
        for p in &mut out.points[..self.len as usize] {
            *p = f(*p);
        }
        out
    }
}

/// The outline of a planar light.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Outline {
    /// A disk of [`AreaLight::radius`] (Jakobsen et al. 2004).
    Disk,
    /// A rectangle `size = [w, h]` about the centre, `w` along `tangent` (a unit vector in the
    /// light's plane).
    Rect { tangent: Vec3, size: [f32; 2] },
    /// A convex polygon.
    Polygon(Polygon),
}

/// A one-sided planar light: centre `c` (a polygon's centroid), unit normal `n_c` (the side it
/// emits to), its outline, and `radius`: the disk's radius, or for a rectangle or polygon the
/// distance of its farthest corner from the centre (the disk it fits in: what bounds, fitted
/// frusta and default cameras use).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct AreaLight {
    pub center: Vec3,
    pub normal: Vec3,
    pub radius: f32,
    pub intensity: f32,
    pub outline: Outline,
}

impl AreaLight {
    /// A disk light of intensity 1.
    pub fn disk(center: Vec3, normal: Vec3, radius: f32) -> AreaLight {
        AreaLight {
            center,
            normal,
            radius,
            intensity: 1.0,
            outline: Outline::Disk,
        }
    }

    /// A rectangle light of intensity 1; `tangent` (the direction of `size[0]`) is projected
    /// onto the light's plane, and defaults to the world axis least parallel to the normal.
    pub fn rect(center: Vec3, normal: Vec3, size: [f32; 2], tangent: Option<Vec3>) -> AreaLight {
        let normal = normal.try_normalize().unwrap_or(Vec3::NEG_Y);
        let tangent = rect_tangent(normal, tangent);
        AreaLight {
            center,
            normal,
            radius: 0.5 * (size[0] * size[0] + size[1] * size[1]).sqrt(),
            intensity: 1.0,
            outline: Outline::Rect { tangent, size },
        }
    }

    /// A polygon light of intensity 1 through `points` (checked by [`check_polygon`]): centre
    /// at its centroid, normal by the right-hand rule.
    pub fn polygon(points: &[Vec3]) -> AreaLight {
        let polygon = Polygon::new(points);
        let center = polygon.centroid();
        let radius = polygon
            .vertices()
            .iter()
            .map(|p| p.distance(center))
            .fold(0.0, f32::max);
        AreaLight {
            center,
            normal: polygon.area_normal().try_normalize().unwrap_or(Vec3::NEG_Y),
            radius,
            intensity: 1.0,
            outline: Outline::Polygon(polygon),
        }
    }

    /// The regular `n`-gon inscribed in this light's disk (its first vertex along the first
    /// vector of [`AreaLight::basis`]); what the tests compare the polygon path with the disk's on.
    pub fn inscribed_polygon(&self, n: usize) -> AreaLight {
        let (u, w) = self.basis();
        let n = n.clamp(3, MAX_POLYGON_VERTICES);
        let points: Vec<Vec3> = (0..n)
            .map(|k| {
                let a = k as f32 / n as f32 * std::f32::consts::TAU;
                self.center + self.radius * (a.cos() * u + a.sin() * w)
            })
            .collect();
        AreaLight {
            intensity: self.intensity,
            ..AreaLight::polygon(&points)
        }
    }

    pub fn with_intensity(self, intensity: f32) -> AreaLight {
        AreaLight { intensity, ..self }
    }

    pub fn kind(&self) -> LightKind {
        match self.outline {
            Outline::Disk => LightKind::Disk,
            Outline::Rect { .. } => LightKind::Rect,
            Outline::Polygon(_) => LightKind::Polygon,
        }
    }

    pub fn is_disk(&self) -> bool {
        matches!(self.outline, Outline::Disk)
    }

    /// Signed distance of `p` in front of the light plane (positive on the emitting side).
    pub fn height_of(&self, p: Vec3) -> f32 {
        self.normal.dot(p - self.center)
    }

    /// Two unit vectors spanning the light's plane, orthogonal to each other and to the normal:
    /// a rectangle's tangent and `n × tangent` (the direction of its height), otherwise glam's
    /// `any_orthonormal_pair` of the normal (whose handedness is not promised).
    pub fn basis(&self) -> (Vec3, Vec3) {
        match self.outline {
            Outline::Rect { tangent, .. } => (tangent, self.normal.cross(tangent)),
            _ => self.normal.any_orthonormal_pair(),
        }
    }

    /// The corners of a rectangle or polygon, counter-clockwise seen from the emitting side;
    /// `None` for a disk.
    pub fn corners(&self) -> Option<Polygon> {
        match self.outline {
            Outline::Disk => None,
            Outline::Polygon(p) => Some(p),
            Outline::Rect { tangent, size } => {
                let b = self.normal.cross(tangent);
                let (hw, hh) = (0.5 * size[0], 0.5 * size[1]);
                let c = self.center;
                Some(Polygon::new(&[
                    c - tangent * hw - b * hh,
                    c + tangent * hw - b * hh,
                    c + tangent * hw + b * hh,
                    c - tangent * hw + b * hh,
                ]))
            }
        }
    }

    /// The light's area (m²).
    pub fn area(&self) -> f32 {
        match self.outline {
            Outline::Disk => std::f32::consts::PI * self.radius * self.radius,
            Outline::Rect { size, .. } => size[0] * size[1],
            Outline::Polygon(p) => p.area(),
        }
    }

    fn is_finite(&self) -> bool {
        let outline = match self.outline {
            Outline::Disk => true,
            Outline::Rect { tangent, size } => {
                tangent.is_finite() && size.iter().all(|s| s.is_finite())
            }
            Outline::Polygon(p) => p.vertices().iter().all(|v| v.is_finite()),
        };
        self.center.is_finite() && self.normal.is_finite() && self.radius.is_finite() && outline
    }

    /// The light moved rigidly: points by `point`, directions by `direction`.
    pub fn moved(&self, point: impl Fn(Vec3) -> Vec3, direction: impl Fn(Vec3) -> Vec3) -> Self {
        let normal = direction(self.normal).normalize_or(self.normal);
        let outline = match self.outline {
            Outline::Disk => Outline::Disk,
            Outline::Rect { tangent, size } => Outline::Rect {
                tangent: rect_tangent(normal, Some(direction(tangent))),
                size,
            },
            Outline::Polygon(p) => Outline::Polygon(p.map(&point)),
        };
        AreaLight {
            center: point(self.center),
            normal,
            outline,
            ..*self
        }
    }
}

/// A rectangle's tangent: `wanted` projected onto the plane of `normal`, or the world axis
/// least parallel to the normal, projected (and any direction in the plane if that fails).
pub fn rect_tangent(normal: Vec3, wanted: Option<Vec3>) -> Vec3 {
    let project = |t: Vec3| (t - normal * normal.dot(t)).try_normalize();
    wanted
        .and_then(project)
        .or_else(|| project(least_parallel_axis(normal)))
        .unwrap_or_else(|| normal.any_orthonormal_vector())
}

/// The world axis (+X, +Y or +Z) least parallel to `v` (the first of equals).
pub fn least_parallel_axis(v: Vec3) -> Vec3 {
    let a = v.abs();
    if a.x <= a.y && a.x <= a.z {
        Vec3::X
    } else if a.y <= a.z {
        Vec3::Y
    } else {
        Vec3::Z
    }
}

/// What is wrong with a polygon light's vertices, in words for a scene file's error (the
/// expectation, then what was found), or `None` when it is a light: 3 to
/// [`MAX_POLYGON_VERTICES`] finite points, no two the same, planar within
/// [`POLYGON_PLANARITY`] of its diameter, convex, of non-zero area. Counter-clockwise seen from
/// the side it emits to is not checked: it is what *defines* that side.
pub fn check_polygon(points: &[DVec3]) -> Option<(String, String)> {
    let n = points.len();
    let expected = |s: &str| Some((s.to_string(), String::new()));
    if n < 3 {
        return Some((
            format!("3 to {MAX_POLYGON_VERTICES} vertices [[x, y, z], ...]"),
            format!("{n} vertices"),
        ));
    }
    if n > MAX_POLYGON_VERTICES {
        return Some((
            format!("at most {MAX_POLYGON_VERTICES} vertices (the most a polygon light may have)"),
            format!("{n} vertices"),
        ));
    }
    if !points.iter().all(|p| p.is_finite()) {
        return expected("finite numbers (no nan or inf)");
    }
    let diameter = points
        .iter()
        .flat_map(|a| points.iter().map(move |b| a.distance(*b)))
        .fold(0.0, f64::max);
    for i in 0..n {
        for j in i + 1..n {
            if points[i].distance(points[j]) <= 1e-9 * diameter.max(1e-30) {
                return Some((
                    "distinct vertices".into(),
                    format!("vertex {j} repeats vertex {i}"),
                ));
            }
        }
    }
    let o = points[0];
    let newell: DVec3 = (0..n)
        .map(|i| (points[i] - o).cross(points[(i + 1) % n] - o))
        .sum();
    let area = 0.5 * newell.length();
    // f32 is what every method gets: an area that vanishes there is zero too.
    if area <= 1e-9 * diameter * diameter || (area as f32) <= 0.0 {
        return Some((
            "vertices enclosing a non-zero area".into(),
            "collinear vertices (zero area)".into(),
        ));
    }
    let normal = newell / newell.length();
    let centroid = points.iter().sum::<DVec3>() / n as f64;
    if let Some((i, off)) = points
        .iter()
        .map(|p| (p - centroid).dot(normal).abs())
        .enumerate()
        .max_by(|a, b| a.1.total_cmp(&b.1))
    {
        if off > POLYGON_PLANARITY * diameter {
            return Some((
                format!(
                    "coplanar vertices (within {POLYGON_PLANARITY:e} of the polygon's diameter)"
                ),
                format!("vertex {i} is {off:.3e} m off the polygon's plane"),
            ));
        }
    }
    // Convex: every corner turns the same way as the whole (collinear corners are allowed), and
    // the turns add up to one full turn (a star turns twice).
    let mut turning = 0.0;
    for i in 0..n {
        let (a, b, c) = (points[i], points[(i + 1) % n], points[(i + 2) % n]);
        let (e1, e2) = (b - a, c - b);
        let turn = e1.cross(e2).dot(normal);
        if turn < -1e-9 * e1.length() * e2.length() {
            return Some((
                "a convex polygon".into(),
                format!(
                    "the corner at vertex {} turns the other way (concave)",
                    (i + 1) % n
                ),
            ));
        }
        turning += turn.atan2(e1.dot(e2));
    }
    if turning > 3.0 * std::f64::consts::PI {
        return Some((
            "a convex polygon".into(),
            "a polygon that winds around more than once (a star)".into(),
        ));
    }
    None
}

/// A linear light (Heidrich, Brabec & Seidel 2000): the segment from `a` to `b`, emitting all around it. V at a point
/// is the fraction of the segment's length it sees.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LineLight {
    pub a: Vec3,
    pub b: Vec3,
    pub intensity: f32,
}

impl LineLight {
    /// The point at `s` ∈ [0, 1] along the segment (`a` at 0, `b` at 1).
    pub fn at(&self, s: f32) -> Vec3 {
        self.a + (self.b - self.a) * s
    }

    pub fn midpoint(&self) -> Vec3 {
        (self.a + self.b) * 0.5
    }

    pub fn length(&self) -> f32 {
        (self.b - self.a).length()
    }
}

/// The shortest line light a scene file may give (metres): below it the segment has no
/// direction worth the name and is refused as "zero length".
pub const MIN_LINE_LENGTH: f64 = 1e-4;

/// Which kind a light is (`[light] kind = "disk"`, `"rect"`, `"polygon"` or `"line"`; a disk by
/// default).
#[derive(
    Clone, Copy, Debug, Default, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize,
)]
#[serde(rename_all = "lowercase")]
pub enum LightKind {
    #[default]
    Disk,
    Rect,
    Polygon,
    Line,
}

impl LightKind {
    /// Every kind, in the order the lab's picker shows them.
    pub const ALL: [LightKind; 4] = [
        LightKind::Disk,
        LightKind::Rect,
        LightKind::Polygon,
        LightKind::Line,
    ];

    pub fn name(self) -> &'static str {
        match self {
            LightKind::Disk => "disk",
            LightKind::Rect => "rect",
            LightKind::Polygon => "polygon",
            LightKind::Line => "line",
        }
    }

    /// Kinds in words: "disk", "disk or line", "disk, rect or polygon".
    pub fn list_in_words(kinds: &[LightKind]) -> String {
        let names: Vec<&str> = kinds.iter().map(|k| k.name()).collect();
        match names.split_last() {
            Some((last, rest)) if !rest.is_empty() => format!("{} or {last}", rest.join(", ")),
            _ => names.join(""),
        }
    }

    /// A planar one-sided light (every kind but the line).
    pub fn is_area(self) -> bool {
        self != LightKind::Line
    }
}

impl std::fmt::Display for LightKind {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// The scene's light: a planar one-sided light (the disk of the D-buffer paper, a rectangle, a
/// convex polygon) or a linear light (docs/guide/scene-format.md). What every method shares goes
/// through [`Light::center`] (the point the hard methods use).
// A planar light holds its polygon inline (232 bytes) so a light stays `Copy`; there is one per
// scene, so the size a line light wastes is nothing.
#[allow(clippy::large_enum_variant)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Light {
    Area(AreaLight),
    Line(LineLight),
}

impl From<AreaLight> for Light {
    fn from(d: AreaLight) -> Light {
        Light::Area(d)
    }
}

impl From<LineLight> for Light {
    fn from(l: LineLight) -> Light {
        Light::Line(l)
    }
}

impl Light {
    pub fn kind(&self) -> LightKind {
        match self {
            Light::Area(a) => a.kind(),
            Light::Line(_) => LightKind::Line,
        }
    }

    pub fn as_area(&self) -> Option<&AreaLight> {
        match self {
            Light::Area(d) => Some(d),
            Light::Line(_) => None,
        }
    }

    /// The planar light, or for a line a zero-radius disk at its midpoint facing down: what the
    /// D-buffer's twins build from when a caller did not refuse the line first (they do; this
    /// keeps a wrong call from panicking).
    pub fn area_or_centre(&self) -> AreaLight {
        self.as_area().copied().unwrap_or(AreaLight {
            intensity: self.intensity(),
            ..AreaLight::disk(self.center(), Vec3::NEG_Y, 0.0)
        })
    }

    pub fn as_line(&self) -> Option<&LineLight> {
        match self {
            Light::Line(l) => Some(l),
            Light::Area(_) => None,
        }
    }

    /// The disk's centre, the rectangle's, the polygon's centroid or the segment's midpoint:
    /// the point the hard methods (a shadow map, a stencil volume) treat as the light, and what
    /// the light view looks from.
    pub fn center(&self) -> Vec3 {
        match self {
            Light::Area(d) => d.center,
            Light::Line(l) => l.midpoint(),
        }
    }

    pub fn intensity(&self) -> f32 {
        match self {
            Light::Area(d) => d.intensity,
            Light::Line(l) => l.intensity,
        }
    }

    /// Half the light's extent: the radius of the disk it fits in, half the segment's length.
    pub fn half_extent(&self) -> f32 {
        match self {
            Light::Area(d) => d.radius,
            Light::Line(l) => 0.5 * l.length(),
        }
    }

    /// Whether light can arrive at `x` at all: a planar light is one-sided (`x` strictly in
    /// front of its plane), a line emits all around (every finite point).
    pub fn reaches(&self, x: Vec3) -> bool {
        match self {
            Light::Area(d) => d.height_of(x) > 0.0,
            Light::Line(_) => x.is_finite(),
        }
    }

    /// Every coordinate finite (and a finite radius).
    pub fn is_finite(&self) -> bool {
        match self {
            Light::Area(d) => d.is_finite(),
            Light::Line(l) => l.a.is_finite() && l.b.is_finite(),
        }
    }

    /// The light moved: points by `point`, directions by `direction` (a rigid motion).
    pub fn moved(&self, point: impl Fn(Vec3) -> Vec3, direction: impl Fn(Vec3) -> Vec3) -> Light {
        match *self {
            Light::Area(d) => Light::Area(d.moved(point, direction)),
            Light::Line(l) => Light::Line(LineLight {
                a: point(l.a),
                b: point(l.b),
                ..l
            }),
        }
    }

    /// The same place as a light of `kind`, intensity kept:
    /// - a planar light to a disk: the disk of the same area about its centre;
    /// - to a rectangle: a disk becomes the square of the same area; a polygon the rectangle
    ///   bounding it along its first edge;
    /// - to a polygon: a disk becomes its inscribed regular hexagon, a rectangle its 4 corners;
    /// - to a line: the segment through the centre along the first vector of its plane's basis,
    ///   as long as the light is wide there;
    /// - a line to a planar light: a disk as wide as it is long (at least 1 cm), a strip
    ///   rectangle as long as it and a tenth as wide (at least 1 cm), or that strip's corners,
    ///   centred on its midpoint, facing down (sideways under a vertical segment).
    ///
    /// The bench times the methods of one kind on the other kind's scenes this way, and the
    /// lab's light picker converts in place.
    pub fn converted(&self, kind: LightKind) -> Light {
        if self.kind() == kind {
            return *self;
        }
        match *self {
            Light::Area(d) => {
                let (u, _) = d.basis();
                let extent_along = |dir: Vec3| match d.corners() {
                    None => (-d.radius, d.radius),
                    Some(p) => p
                        .vertices()
                        .iter()
                        .fold((f32::MAX, f32::MIN), |(lo, hi), v| {
                            let x = (*v - d.center).dot(dir);
                            (lo.min(x), hi.max(x))
                        }),
                };
                let keep = |a: AreaLight| Light::Area(a.with_intensity(d.intensity));
                match kind {
                    LightKind::Line => {
                        let (lo, hi) = extent_along(u);
                        Light::Line(LineLight {
                            a: d.center + u * lo,
                            b: d.center + u * hi,
                            intensity: d.intensity,
                        })
                    }
                    LightKind::Disk => keep(AreaLight::disk(
                        d.center,
                        d.normal,
                        (d.area() / std::f32::consts::PI).sqrt(),
                    )),
                    LightKind::Rect => match d.corners() {
                        None => {
                            let side = d.radius * std::f32::consts::PI.sqrt();
                            keep(AreaLight::rect(d.center, d.normal, [side, side], Some(u)))
                        }
                        Some(p) => {
                            let v = p.vertices();
                            let t = rect_tangent(d.normal, Some(v[1] - v[0]));
                            let b = d.normal.cross(t);
                            let ((t0, t1), (b0, b1)) = (extent_along(t), extent_along(b));
                            let mid = d.center + t * 0.5 * (t0 + t1) + b * 0.5 * (b0 + b1);
                            keep(AreaLight::rect(mid, d.normal, [t1 - t0, b1 - b0], Some(t)))
                        }
                    },
                    LightKind::Polygon => match d.corners() {
                        Some(p) => keep(AreaLight::polygon(p.vertices())),
                        None => keep(d.inscribed_polygon(6)),
                    },
                }
            }
            Light::Line(l) => {
                let along = (l.b - l.a).normalize_or_zero();
                let down = (Vec3::NEG_Y - along * along.dot(Vec3::NEG_Y))
                    .try_normalize()
                    .unwrap_or(Vec3::X);
                let length = l.length();
                let strip = AreaLight::rect(
                    l.midpoint(),
                    down,
                    [length.max(0.01), (0.1 * length).max(0.01)],
                    along.try_normalize(),
                );
                let light = match kind {
                    LightKind::Disk => {
                        AreaLight::disk(l.midpoint(), down, (0.5 * length).max(0.01))
                    }
                    LightKind::Rect => strip,
                    _ => {
                        let corners = strip.corners().unwrap_or(Polygon::new(&[]));
                        AreaLight::polygon(corners.vertices())
                    }
                };
                Light::Area(light.with_intensity(l.intensity))
            }
        }
    }

    /// The light translated so its [`Light::center`] is at `to`.
    pub fn with_center(&self, to: Vec3) -> Light {
        let d = to - self.center();
        self.moved(|p| p + d, |v| v)
    }
}
