//! A bounding volume hierarchy over triangles, for the ray-cast oracle.
//!
//! Binned SAH build, nodes flattened into one array (two children always adjacent, so a
//! traversal step reads both child boxes from neighbouring memory), triangles copied into leaf
//! order with their edges precomputed. Triangles are two-sided, like
//! [`intersect_triangle`], and the exact queries
//! ([`Bvh::closest_hit`], [`Bvh::any_hit`], [`Bvh::find_any_hit`], [`Bvh::for_each_hit`]) give
//! bit-for-bit the answer of running that function over all triangles: the BVH only skips work.
//! The `_tolerant` queries use
//! [`intersect_triangle_tolerant`] instead, which no
//! ray slips through between two triangles sharing an edge (shadow rays of the oracle).
//!
//! Queries take a ray `origin + t·dir` and accept hits with `t_min <= t <= t_max` (closed
//! interval). `dir` need not be unit length. Any input is safe: NaN or infinite coordinates, zero
//! `dir` and degenerate triangles give no hits (or the hits brute force gives), never a panic.

use glam::{Vec3, Vec3A, Vec4};

use super::ray::{
    intersect_edges, intersect_edges_tolerant, intersect_triangle, intersect_triangle_tolerant,
};

/// One hit along a ray: the ray parameter and the triangle's index in the order given to
/// [`Bvh::build`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    pub t: f32,
    pub triangle: u32,
}

/// Number of SAH bins per axis.
const BINS: usize = 16;
/// Leaves hold at most this many triangles, unless their centroids coincide or `MAX_DEPTH`
/// is reached (then they hold whatever is left).
const MAX_LEAF: usize = 8;
/// The build stops splitting at this depth, so the traversal stack below never overflows.
const MAX_DEPTH: usize = 48;
/// Traversal stack size (entries), more than `MAX_DEPTH` needs.
const STACK: usize = 64;
/// Relative cost of a box test against a triangle test, for the SAH.
const TRAVERSAL_COST: f32 = 1.0;
const TRIANGLE_COST: f32 = 1.0;

/// A flattened node, 32 bytes. For an interior node `count == 0` and the children are
/// `first` and `first + 1`; for a leaf the triangles are `first .. first + count` in leaf order.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct Node {
    min: Vec3,
    first: u32,
    max: Vec3,
    count: u32,
}

/// The traversal's copy of a [`Node`], 32 bytes, 16-aligned, so the slab test runs on SIMD
/// lanes: `xyz` of `min`/`max` are the box, the `w` lanes hold the bits of `first`/`count`.
#[derive(Clone, Copy, Debug)]
#[repr(C)]
struct PackedNode {
    min: Vec4,
    max: Vec4,
}

impl PackedNode {
    fn new(n: &Node) -> Self {
        Self {
            min: n.min.extend(f32::from_bits(n.first)),
            max: n.max.extend(f32::from_bits(n.count)),
        }
    }
    #[inline(always)]
    fn first(&self) -> u32 {
        self.min.w.to_bits()
    }
    #[inline(always)]
    fn count(&self) -> u32 {
        self.max.w.to_bits()
    }
}

/// A triangle in leaf order: first corner and the two edges from it, exactly as
/// [`intersect_triangle`] computes them.
#[derive(Clone, Copy, Debug)]
struct PreTri {
    v0: Vec3A,
    e1: Vec3A,
    e2: Vec3A,
}

/// A BVH over a triangle soup. See the module documentation.
#[derive(Clone, Debug)]
pub struct Bvh {
    nodes: Vec<PackedNode>,
    /// Triangles in leaf order.
    pre: Vec<PreTri>,
    /// Original index of each triangle in leaf order.
    index: Vec<u32>,
    /// Triangles in the original order.
    triangles: Vec<[Vec3; 3]>,
}

/// A ray with what the box test needs precomputed.
#[derive(Clone, Copy)]
struct Ray {
    origin_a: Vec3A,
    dir_a: Vec3A,
    inv: Vec3A,
}

impl Ray {
    fn new(origin: Vec3, dir: Vec3) -> Self {
        // 1/0 = ±inf is what the slab test wants; the min/max below ignore the NaN of 0·inf.
        Self {
            dir_a: dir.into(),
            origin_a: origin.into(),
            inv: Vec3A::from(dir).recip(),
        }
    }

    /// Entry parameter of the ray into the node's box clipped to `[t_min, t_max]`, or `None`.
    #[inline(always)]
    fn enter(&self, n: &PackedNode, t_min: f32, t_max: f32) -> Option<f32> {
        let t1 = (Vec3A::from_vec4(n.min) - self.origin_a) * self.inv;
        let t2 = (Vec3A::from_vec4(n.max) - self.origin_a) * self.inv;
        // A NaN lane (0·inf: the origin exactly on a face of a box the ray runs parallel to)
        // makes min/max pick the other operand; such a ray lies on the padded face, outside
        // the triangles' bounds, so whatever the test decides no hit is lost.
        let near = t1.min(t2).max_element().max(t_min);
        let far = t1.max(t2).min_element().min(t_max);
        (near <= far).then_some(near)
    }
}

/// Bounds of a set of points or boxes.
#[derive(Clone, Copy)]
struct Aabb {
    min: Vec3,
    max: Vec3,
}

impl Aabb {
    const EMPTY: Aabb = Aabb {
        min: Vec3::splat(f32::INFINITY),
        max: Vec3::splat(f32::NEG_INFINITY),
    };

    fn grow(&mut self, p: Vec3) {
        self.min = self.min.min(p);
        self.max = self.max.max(p);
    }

    fn merge(&mut self, o: &Aabb) {
        self.min = self.min.min(o.min);
        self.max = self.max.max(o.max);
    }

    fn half_area(&self) -> f32 {
        let e = self.max - self.min;
        if e.x < 0.0 || e.y < 0.0 || e.z < 0.0 || !e.is_finite() {
            return 0.0;
        }
        e.x * e.y + e.y * e.z + e.z * e.x
    }
}

/// What the build needs per triangle.
#[derive(Clone, Copy)]
struct BuildTri {
    bounds: Aabb,
    centroid: Vec3,
    index: u32,
}

impl Bvh {
    /// Builds the BVH. Works with any number of triangles, including none.
    pub fn build(triangles: Vec<[Vec3; 3]>) -> Bvh {
        let mut items: Vec<BuildTri> = triangles
            .iter()
            .enumerate()
            .map(|(i, t)| {
                let mut b = Aabb::EMPTY;
                for &p in t {
                    b.grow(p);
                }
                BuildTri {
                    bounds: b,
                    centroid: (b.min + b.max) * 0.5,
                    index: i as u32,
                }
            })
            .collect();
        let mut nodes = Vec::with_capacity(2 * items.len().max(1));
        nodes.push(Node {
            min: Vec3::ZERO,
            first: 0,
            max: Vec3::ZERO,
            count: 0,
        });
        if !items.is_empty() {
            let n = items.len();
            build_node(&mut nodes, &mut items, 0, 0, n, 0);
        } else {
            // An empty root leaf whose inverted box no ray enters.
            nodes[0].min = Vec3::splat(f32::INFINITY);
            nodes[0].max = Vec3::splat(f32::NEG_INFINITY);
        }
        let pre = items
            .iter()
            .map(|b| {
                let t = &triangles[b.index as usize];
                let v0 = Vec3A::from(t[0]);
                PreTri {
                    v0,
                    e1: Vec3A::from(t[1]) - v0,
                    e2: Vec3A::from(t[2]) - v0,
                }
            })
            .collect();
        let index = items.iter().map(|b| b.index).collect();
        Bvh {
            nodes: nodes.iter().map(PackedNode::new).collect(),
            pre,
            index,
            triangles,
        }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangles.len()
    }

    /// Whether there are no triangles.
    pub fn is_empty(&self) -> bool {
        self.triangles.is_empty()
    }

    /// Triangle `i` in the order given to [`Bvh::build`]. Panics when `i >= len()`, like slice
    /// indexing.
    pub fn triangle(&self, i: usize) -> &[Vec3; 3] {
        &self.triangles[i]
    }

    /// All triangles in the order given to [`Bvh::build`].
    pub fn triangles(&self) -> &[[Vec3; 3]] {
        &self.triangles
    }

    /// Number of nodes (for statistics).
    pub fn node_count(&self) -> usize {
        self.nodes.len()
    }

    /// The nearest hit with `t_min <= t <= t_max`. Among hits at exactly the same `t` the one
    /// with the lowest triangle index wins, so the answer does not depend on the tree.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        let mut v = Closest { best: None, t_max };
        self.traverse::<_, false>(&Ray::new(origin, dir), t_min, &mut v);
        v.best
    }

    /// Whether any triangle is hit with `t_min <= t <= t_max` (stops at the first one found).
    pub fn any_hit(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> bool {
        self.find_any_hit(origin, dir, t_min, t_max).is_some()
    }

    /// Some hit with `t_min <= t <= t_max`, not necessarily the closest: the first the traversal
    /// finds (it stops there). Shadow rays use the triangle as a cache for the next ray.
    pub fn find_any_hit(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        let mut v = Any { found: None, t_max };
        self.traverse::<_, false>(&Ray::new(origin, dir), t_min, &mut v);
        v.found
    }

    /// Whether triangle `i` (original order) is hit with `t_min <= t <= t_max`; `false` when
    /// `i` is out of range.
    #[inline]
    pub fn hits_triangle(&self, i: u32, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> bool {
        self.triangles.get(i as usize).is_some_and(|tri| {
            intersect_triangle(origin, dir, tri).is_some_and(|t| t >= t_min && t <= t_max)
        })
    }

    /// [`Bvh::find_any_hit`] with
    /// [`intersect_triangle_tolerant`]: no ray slips
    /// between two triangles that share an edge. For shadow rays against closed meshes.
    pub fn find_any_hit_tolerant(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> Option<Hit> {
        let mut v = Any { found: None, t_max };
        self.traverse::<_, true>(&Ray::new(origin, dir), t_min, &mut v);
        v.found
    }

    /// [`Bvh::hits_triangle`] with the tolerant test.
    #[inline]
    pub fn hits_triangle_tolerant(
        &self,
        i: u32,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
    ) -> bool {
        self.triangles.get(i as usize).is_some_and(|tri| {
            intersect_triangle_tolerant(origin, dir, tri).is_some_and(|t| t >= t_min && t <= t_max)
        })
    }

    /// Calls `f` once for every hit with `t_min <= t <= t_max`, in no particular order.
    pub fn for_each_hit(
        &self,
        origin: Vec3,
        dir: Vec3,
        t_min: f32,
        t_max: f32,
        f: impl FnMut(Hit),
    ) {
        let mut v = Every { f, t_max };
        self.traverse::<_, false>(&Ray::new(origin, dir), t_min, &mut v);
    }

    /// The one traversal loop, ordered front to back.
    #[inline(always)]
    fn traverse<V: Visitor, const TOLERANT: bool>(&self, ray: &Ray, t_min: f32, v: &mut V) {
        let Some(root) = self.nodes.first() else {
            return;
        };
        if self.pre.is_empty() {
            return;
        }
        if ray.enter(root, t_min, v.limit()).is_none() {
            return;
        }
        let mut stack = [0u32; STACK];
        let mut sp = 0usize;
        let mut node = root;
        loop {
            let count = node.count();
            if count > 0 {
                let first = node.first() as usize;
                let end = first + count as usize;
                for k in first..end {
                    // Indices come from the build and are in range; `get` keeps this panic-free.
                    let (Some(p), Some(&i)) = (self.pre.get(k), self.index.get(k)) else {
                        continue;
                    };
                    let hit = if TOLERANT {
                        intersect_edges_tolerant(ray.origin_a, ray.dir_a, p.v0, p.e1, p.e2)
                    } else {
                        intersect_edges(ray.origin_a, ray.dir_a, p.v0, p.e1, p.e2)
                    };
                    if let Some(t) = hit {
                        if t >= t_min && t <= v.limit() && v.hit(i, t) {
                            return;
                        }
                    }
                }
            } else {
                let l = node.first() as usize;
                if let (Some(a), Some(b)) = (self.nodes.get(l), self.nodes.get(l + 1)) {
                    let far = v.limit();
                    let ta = ray.enter(a, t_min, far);
                    let tb = ray.enter(b, t_min, far);
                    match (ta, tb) {
                        (Some(ta), Some(tb)) => {
                            let (near, other) = if ta <= tb { (a, l + 1) } else { (b, l) };
                            if sp < STACK {
                                stack[sp] = other as u32;
                                sp += 1;
                            }
                            node = near;
                            continue;
                        }
                        (Some(_), None) => {
                            node = a;
                            continue;
                        }
                        (None, Some(_)) => {
                            node = b;
                            continue;
                        }
                        (None, None) => {}
                    }
                }
            }
            // Pop the next node whose box still overlaps the (possibly shrunk) interval.
            loop {
                if sp == 0 {
                    return;
                }
                sp -= 1;
                let Some(n) = self.nodes.get(stack[sp] as usize) else {
                    continue;
                };
                if ray.enter(n, t_min, v.limit()).is_some() {
                    node = n;
                    break;
                }
            }
        }
    }
}

/// What a query does with the hits the traversal finds.
trait Visitor {
    /// The current far end of the search interval (shrinks as a closest hit is found).
    fn limit(&self) -> f32;
    /// Takes a hit with `t_min <= t <= limit()`; returns `true` to stop the traversal.
    fn hit(&mut self, triangle: u32, t: f32) -> bool;
}

struct Closest {
    best: Option<Hit>,
    t_max: f32,
}

impl Visitor for Closest {
    #[inline(always)]
    fn limit(&self) -> f32 {
        self.best.map_or(self.t_max, |b| b.t)
    }
    #[inline(always)]
    fn hit(&mut self, triangle: u32, t: f32) -> bool {
        let better = match self.best {
            None => true,
            Some(b) => t < b.t || (t == b.t && triangle < b.triangle),
        };
        if better {
            self.best = Some(Hit { t, triangle });
        }
        false
    }
}

struct Any {
    found: Option<Hit>,
    t_max: f32,
}

impl Visitor for Any {
    #[inline(always)]
    fn limit(&self) -> f32 {
        self.t_max
    }
    #[inline(always)]
    fn hit(&mut self, triangle: u32, t: f32) -> bool {
        self.found = Some(Hit { t, triangle });
        true
    }
}

struct Every<F> {
    f: F,
    t_max: f32,
}

impl<F: FnMut(Hit)> Visitor for Every<F> {
    #[inline(always)]
    fn limit(&self) -> f32 {
        self.t_max
    }
    #[inline(always)]
    fn hit(&mut self, triangle: u32, t: f32) -> bool {
        (self.f)(Hit { t, triangle });
        false
    }
}

/// Builds the subtree for `items[start..end]` into `nodes[at]`, reordering `items`.
fn build_node(
    nodes: &mut Vec<Node>,
    items: &mut [BuildTri],
    at: usize,
    start: usize,
    end: usize,
    depth: usize,
) {
    let slice = &items[start..end];
    let mut bounds = Aabb::EMPTY;
    let mut cbounds = Aabb::EMPTY;
    for b in slice {
        bounds.merge(&b.bounds);
        cbounds.grow(b.centroid);
    }
    // Pad the box a little so that rounding in the slab test never rejects a ray that the
    // triangle test (computed differently) says hits a triangle on the box's boundary.
    let pad = (bounds.max - bounds.min).abs().max_element() * 1e-5
        + bounds.min.abs().max(bounds.max.abs()).max_element() * 4.0 * f32::EPSILON;
    let pad = if pad.is_finite() { pad } else { 0.0 };
    nodes[at].min = bounds.min - Vec3::splat(pad);
    nodes[at].max = bounds.max + Vec3::splat(pad);
    let count = end - start;
    let make_leaf = |nodes: &mut Vec<Node>| {
        nodes[at].first = start as u32;
        nodes[at].count = count as u32;
    };
    if count <= 1 || depth >= MAX_DEPTH {
        make_leaf(nodes);
        return;
    }

    // Binned SAH over all three axes.
    let leaf_cost = TRIANGLE_COST * count as f32;
    let parent_area = bounds.half_area();
    let mut best: Option<(usize, usize, f32)> = None; // (axis, split bin, cost)
    let extent = cbounds.max - cbounds.min;
    for axis in 0..3 {
        let lo = cbounds.min[axis];
        let ext = extent[axis];
        if ext.is_nan() || ext <= 0.0 || !ext.is_finite() {
            continue;
        }
        let scale = BINS as f32 / ext;
        let mut bin_bounds = [Aabb::EMPTY; BINS];
        let mut bin_count = [0usize; BINS];
        for b in slice {
            let k = bin_of(b.centroid[axis], lo, scale);
            bin_bounds[k].merge(&b.bounds);
            bin_count[k] += 1;
        }
        // Sweep from the right to get the right-hand areas, then from the left.
        let mut right_area = [0.0f32; BINS];
        let mut right_count = [0usize; BINS];
        let mut acc = Aabb::EMPTY;
        let mut n = 0;
        for k in (1..BINS).rev() {
            acc.merge(&bin_bounds[k]);
            n += bin_count[k];
            right_area[k] = acc.half_area();
            right_count[k] = n;
        }
        let mut acc = Aabb::EMPTY;
        let mut n = 0;
        for k in 0..BINS - 1 {
            acc.merge(&bin_bounds[k]);
            n += bin_count[k];
            let nr = right_count[k + 1];
            if n == 0 || nr == 0 {
                continue;
            }
            let cost = TRAVERSAL_COST
                + TRIANGLE_COST * (acc.half_area() * n as f32 + right_area[k + 1] * nr as f32)
                    / parent_area.max(f32::MIN_POSITIVE);
            if cost.is_finite() && best.is_none_or(|(_, _, c)| cost < c) {
                best = Some((axis, k, cost));
            }
        }
    }
    let Some((axis, split, cost)) = best else {
        // All centroids coincide (or are not finite): nothing to split on.
        make_leaf(nodes);
        return;
    };
    if cost >= leaf_cost && count <= MAX_LEAF {
        make_leaf(nodes);
        return;
    }
    let lo = cbounds.min[axis];
    let scale = BINS as f32 / extent[axis];
    // Partition in place: bins 0..=split to the left.
    let slice = &mut items[start..end];
    let mut i = 0;
    let mut j = slice.len();
    while i < j {
        if bin_of(slice[i].centroid[axis], lo, scale) <= split {
            i += 1;
        } else {
            j -= 1;
            slice.swap(i, j);
        }
    }
    let mid = start + i;
    if mid == start || mid == end {
        make_leaf(nodes);
        return;
    }
    let left = nodes.len();
    let dummy = Node {
        min: Vec3::ZERO,
        first: 0,
        max: Vec3::ZERO,
        count: 0,
    };
    nodes.push(dummy);
    nodes.push(dummy);
    nodes[at].first = left as u32;
    nodes[at].count = 0;
    build_node(nodes, items, left, start, mid, depth + 1);
    build_node(nodes, items, left + 1, mid, end, depth + 1);
}

#[inline]
fn bin_of(c: f32, lo: f32, scale: f32) -> usize {
    // `as usize` saturates (NaN -> 0), and the min keeps the top edge in the last bin.
    (((c - lo) * scale) as usize).min(BINS - 1)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::ray::intersect_triangle;
    use proptest::prelude::*;

    fn brute_all(tris: &[[Vec3; 3]], o: Vec3, d: Vec3, t0: f32, t1: f32) -> Vec<(u32, u32)> {
        let mut v: Vec<(u32, u32)> = tris
            .iter()
            .enumerate()
            .filter_map(|(i, t)| {
                intersect_triangle(o, d, t)
                    .filter(|&t| t >= t0 && t <= t1)
                    .map(|t| (i as u32, t.to_bits()))
            })
            .collect();
        v.sort_unstable();
        v
    }

    fn brute_closest(tris: &[[Vec3; 3]], o: Vec3, d: Vec3, t0: f32, t1: f32) -> Option<Hit> {
        let mut best: Option<Hit> = None;
        for (i, t) in tris.iter().enumerate() {
            if let Some(t) = intersect_triangle(o, d, t).filter(|&t| t >= t0 && t <= t1) {
                if best.is_none_or(|b| t < b.t) {
                    best = Some(Hit {
                        t,
                        triangle: i as u32,
                    });
                }
            }
        }
        best
    }

    fn check(tris: &[[Vec3; 3]], bvh: &Bvh, o: Vec3, d: Vec3, t0: f32, t1: f32) {
        let all = brute_all(tris, o, d, t0, t1);
        let mut got = Vec::new();
        bvh.for_each_hit(o, d, t0, t1, |h| got.push((h.triangle, h.t.to_bits())));
        got.sort_unstable();
        assert_eq!(got, all, "all hits, ray {o} {d} [{t0}, {t1}]");
        assert_eq!(bvh.any_hit(o, d, t0, t1), !all.is_empty());
        if let Some(h) = bvh.find_any_hit(o, d, t0, t1) {
            assert!(all.contains(&(h.triangle, h.t.to_bits())));
            assert!(bvh.hits_triangle(h.triangle, o, d, t0, t1));
        }
        for &(i, _) in &all {
            assert!(bvh.hits_triangle(i, o, d, t0, t1));
        }
        let tolerant_any = tris.iter().any(|t| {
            crate::geometry::ray::intersect_triangle_tolerant(o, d, t)
                .is_some_and(|t| t >= t0 && t <= t1)
        });
        let found = bvh.find_any_hit_tolerant(o, d, t0, t1);
        assert_eq!(found.is_some(), tolerant_any);
        if let Some(h) = found {
            assert!(bvh.hits_triangle_tolerant(h.triangle, o, d, t0, t1));
        }
        let c = bvh.closest_hit(o, d, t0, t1);
        let b = brute_closest(tris, o, d, t0, t1);
        assert_eq!(
            c.map(|h| (h.triangle, h.t.to_bits())),
            b.map(|h| (h.triangle, h.t.to_bits()))
        );
    }

    /// A small deterministic generator for the seeded tests.
    struct Rng(u64);
    impl Rng {
        fn next(&mut self) -> f32 {
            self.0 = self
                .0
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((self.0 >> 40) as f32) / (1u64 << 24) as f32
        }
        fn v(&mut self, s: f32) -> Vec3 {
            Vec3::new(self.next(), self.next(), self.next()) * 2.0 * s - Vec3::splat(s)
        }
    }

    #[test]
    fn random_soups_match_brute_force() {
        let mut rng = Rng(7);
        for soup in 0..20 {
            let n = [0usize, 1, 2, 3, 17, 100, 500, 2000][soup % 8];
            let size = [0.05f32, 0.3, 1.5][soup % 3];
            let tris: Vec<[Vec3; 3]> = (0..n)
                .map(|_| {
                    let c = rng.v(5.0);
                    [c + rng.v(size), c + rng.v(size), c + rng.v(size)]
                })
                .collect();
            let bvh = Bvh::build(tris.clone());
            assert_eq!(bvh.len(), n);
            for (i, t) in tris.iter().enumerate() {
                assert_eq!(bvh.triangle(i), t);
            }
            for _ in 0..300 {
                let o = rng.v(7.0);
                // Aim at a triangle half of the time, so hits are common.
                let d = if n > 0 && rng.next() < 0.5 {
                    let t = &tris[(rng.next() * n as f32) as usize % n];
                    (t[0] + t[1] + t[2]) / 3.0 - o
                } else {
                    rng.v(1.0)
                };
                let t1 = [f32::INFINITY, 1.0, 0.5][(rng.next() * 3.0) as usize % 3];
                check(&tris, &bvh, o, d, 0.0, t1);
                check(&tris, &bvh, o, d, 0.3, t1);
            }
        }
    }

    #[test]
    fn degenerate_and_axis_aligned_inputs() {
        // Zero-area triangles, duplicates, a grid of axis-aligned triangles and axis rays.
        let mut tris = vec![
            [Vec3::ZERO; 3],
            [Vec3::ZERO, Vec3::X, Vec3::X * 2.0],
            [Vec3::ONE, Vec3::ONE, Vec3::new(1.0, 2.0, 1.0)],
        ];
        for i in 0..10 {
            for j in 0..10 {
                let p = Vec3::new(i as f32, j as f32, 0.0);
                tris.push([p, p + Vec3::X, p + Vec3::Y]);
                tris.push([p + Vec3::X, p + Vec3::X + Vec3::Y, p + Vec3::Y]);
            }
        }
        // Many copies of one triangle: centroids coincide, nothing to split.
        for _ in 0..40 {
            tris.push([
                Vec3::splat(3.0),
                Vec3::new(4.0, 3.0, 3.0),
                Vec3::new(3.0, 4.0, 3.0),
            ]);
        }
        let bvh = Bvh::build(tris.clone());
        for i in 0..=20 {
            for j in 0..=20 {
                let o = Vec3::new(i as f32 * 0.5, j as f32 * 0.5, -1.0);
                check(&tris, &bvh, o, Vec3::Z, 0.0, f32::INFINITY);
                check(&tris, &bvh, o, Vec3::Z * 3.0, 0.0, 1.0);
                check(&tris, &bvh, o, Vec3::X, 0.0, f32::INFINITY);
                check(&tris, &bvh, o, Vec3::new(0.3, 0.2, 1.0), 0.0, f32::INFINITY);
            }
        }
        // Odd rays: zero direction, NaN, infinities. No panic, and the same as brute force.
        for (o, d) in [
            (Vec3::ZERO, Vec3::ZERO),
            (Vec3::NAN, Vec3::Z),
            (Vec3::ZERO, Vec3::NAN),
            (Vec3::splat(f32::INFINITY), Vec3::Z),
            (
                Vec3::new(0.5, 0.5, -1.0),
                Vec3::new(0.0, 0.0, f32::INFINITY),
            ),
        ] {
            check(&tris, &bvh, o, d, 0.0, f32::INFINITY);
        }
    }

    #[test]
    fn nan_triangles_do_not_panic() {
        let tris = vec![
            [Vec3::NAN, Vec3::ZERO, Vec3::ONE],
            [Vec3::ZERO, Vec3::X, Vec3::Y],
            [Vec3::splat(f32::INFINITY), Vec3::ZERO, Vec3::Y],
        ];
        let bvh = Bvh::build(tris);
        let _ = bvh.closest_hit(Vec3::new(0.2, 0.2, -1.0), Vec3::Z, 0.0, f32::INFINITY);
        let _ = bvh.any_hit(Vec3::new(0.2, 0.2, -1.0), Vec3::Z, 0.0, f32::INFINITY);
    }

    #[test]
    fn empty_bvh_has_no_hits() {
        let bvh = Bvh::build(Vec::new());
        assert!(bvh.is_empty());
        assert!(!bvh.any_hit(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY));
        assert!(bvh
            .closest_hit(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY)
            .is_none());
    }

    fn vec3() -> impl Strategy<Value = Vec3> {
        (-4.0f32..4.0, -4.0f32..4.0, -4.0f32..4.0).prop_map(|(x, y, z)| Vec3::new(x, y, z))
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(64))]
        #[test]
        fn proptest_matches_brute_force(
            tris in prop::collection::vec((vec3(), vec3(), vec3()).prop_map(|(a, b, c)| [a, b, c]), 0..64),
            rays in prop::collection::vec((vec3(), vec3(), 0.0f32..2.0), 1..16),
        ) {
            let bvh = Bvh::build(tris.clone());
            for (o, d, t1) in rays {
                check(&tris, &bvh, o, d, 0.0, t1);
            }
        }
    }
}
