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

/// A [`Bvh`] as flat arrays of four floats, for a traversal on the GPU (or any other that reads
/// plain memory): the same nodes, in the same order, and the same triangles in leaf order with
/// the same precomputed edges, so a port of [`Bvh::find_any_hit_tolerant`] runs the same tests
/// on the same numbers.
///
/// - `nodes`: two entries per node, `[min.x, min.y, min.z, first]` and `[max.x, max.y, max.z,
///   count]` (`first` and `count` are `u32`s stored as the floats' bits). An interior node has
///   `count == 0` and its children at `first` and `first + 1`; a leaf's triangles are
///   `first .. first + count` of `triangles`. The root is node 0.
/// - `triangles`: three entries per triangle in leaf order: `[v0, index]`, `[e1, 0]`, `[e2, 0]`,
///   with `index` the triangle's place in the order given to [`Bvh::build`] (as bits) and
///   `e1 = tri[1] − v0`, `e2 = tri[2] − v0` exactly as the CPU's test computes them.
///
/// A BVH without triangles has one leaf node and no triangle entries.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FlatBvh {
    pub nodes: Vec<[f32; 4]>,
    pub triangles: Vec<[f32; 4]>,
}

impl FlatBvh {
    /// Number of nodes.
    pub fn node_count(&self) -> usize {
        self.nodes.len() / 2
    }

    /// Number of triangles.
    pub fn triangle_count(&self) -> usize {
        self.triangles.len() / 3
    }
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

    /// The nodes and triangles as plain arrays ([`FlatBvh`]), for a traversal on the GPU.
    pub fn flatten(&self) -> FlatBvh {
        let nodes = self
            .nodes
            .iter()
            .flat_map(|n| [n.min.to_array(), n.max.to_array()])
            .collect();
        let triangles = self
            .pre
            .iter()
            .zip(&self.index)
            .flat_map(|(p, &i)| {
                [
                    p.v0.extend(f32::from_bits(i)).to_array(),
                    p.e1.extend(0.0).to_array(),
                    p.e2.extend(0.0).to_array(),
                ]
            })
            .collect();
        FlatBvh { nodes, triangles }
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
mod tests;
