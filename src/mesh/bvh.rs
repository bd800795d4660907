//! A bounding-volume hierarchy over the triangles of a [`TriMesh`] and the queries built on
//! it: box overlap, closest point (unsigned and signed distance), ray crossings for
//! point-in-mesh tests, and all pairs of intersecting triangles of one surface.

use nalgebra::{Point3, Vector3};

use super::geom::{closest_point_on_triangle, ray_triangle, triangles_intersect};
use super::{Aabb, TriMesh};

const LEAF_SIZE: usize = 4;

#[derive(Debug, Clone)]
struct Node {
    bbox: Aabb,
    /// Leaf: first index into `order`; inner: index of the left child (right = left + 1).
    start: u32,
    /// Number of triangles for a leaf, 0 for an inner node.
    count: u32,
}

/// A median-split AABB tree over a mesh's triangles; it holds a copy of the corner positions
/// so queries need no mesh.
#[derive(Debug, Clone)]
pub struct Bvh {
    nodes: Vec<Node>,
    order: Vec<u32>,
    tris: Vec<[Point3<f64>; 3]>,
    ids: Vec<[u32; 3]>,
}

/// The result of a closest-point query.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Closest {
    /// Triangle index.
    pub triangle: u32,
    /// The closest point on the surface.
    pub point: Point3<f64>,
    /// Distance to it.
    pub distance: f64,
}

impl Bvh {
    /// Builds the tree over every triangle of `mesh`.
    pub fn new(mesh: &TriMesh) -> Bvh {
        let tris: Vec<[Point3<f64>; 3]> =
            (0..mesh.triangles.len()).map(|t| mesh.corners(t)).collect();
        let boxes: Vec<Aabb> = tris.iter().map(tri_box).collect();
        let centers: Vec<Point3<f64>> = boxes.iter().map(|b| b.center()).collect();
        let mut order: Vec<u32> = (0..tris.len() as u32).collect();
        let mut nodes = vec![Node {
            bbox: Aabb::empty(),
            start: 0,
            count: 0,
        }];
        if !tris.is_empty() {
            let mut stack = vec![(0usize, 0usize, tris.len())];
            while let Some((node, lo, hi)) = stack.pop() {
                let mut bb = Aabb::empty();
                let mut cb = Aabb::empty();
                for &t in &order[lo..hi] {
                    bb.merge(&boxes[t as usize]);
                    cb.grow(&centers[t as usize]);
                }
                nodes[node].bbox = bb;
                if hi - lo <= LEAF_SIZE {
                    nodes[node].start = lo as u32;
                    nodes[node].count = (hi - lo) as u32;
                    continue;
                }
                let ext = cb.extent();
                let axis = if ext.x >= ext.y && ext.x >= ext.z {
                    0
                } else if ext.y >= ext.z {
                    1
                } else {
                    2
                };
                let mid = (lo + hi) / 2;
                order[lo..hi].select_nth_unstable_by(mid - lo, |&a, &b| {
                    centers[a as usize][axis].total_cmp(&centers[b as usize][axis])
                });
                let left = nodes.len();
                nodes.push(Node {
                    bbox: Aabb::empty(),
                    start: 0,
                    count: 0,
                });
                nodes.push(Node {
                    bbox: Aabb::empty(),
                    start: 0,
                    count: 0,
                });
                nodes[node].start = left as u32;
                nodes[node].count = 0;
                stack.push((left, lo, mid));
                stack.push((left + 1, mid, hi));
            }
        }
        Bvh {
            nodes,
            order,
            tris,
            ids: mesh.triangles.clone(),
        }
    }

    /// Corner positions of triangle `t` as stored in the tree.
    pub fn corners(&self, t: usize) -> [Point3<f64>; 3] {
        self.tris[t]
    }

    /// Number of triangles in the tree.
    pub fn len(&self) -> usize {
        self.tris.len()
    }

    /// Whether the tree holds no triangle.
    pub fn is_empty(&self) -> bool {
        self.tris.is_empty()
    }

    /// Calls `f` with every triangle whose box overlaps `query`.
    pub fn for_each_in_box(&self, query: &Aabb, mut f: impl FnMut(u32)) {
        if self.tris.is_empty() {
            return;
        }
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if !node.bbox.intersects(query) {
                continue;
            }
            if node.count > 0 {
                for &t in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    if tri_box(&self.tris[t as usize]).intersects(query) {
                        f(t);
                    }
                }
            } else {
                stack.push(node.start as usize);
                stack.push(node.start as usize + 1);
            }
        }
    }

    /// The closest point of the surface to `p` (None for an empty tree).
    pub fn closest(&self, p: &Point3<f64>) -> Option<Closest> {
        if self.tris.is_empty() {
            return None;
        }
        let mut best = Closest {
            triangle: 0,
            point: *p,
            distance: f64::INFINITY,
        };
        let mut best2 = f64::INFINITY;
        let mut stack = vec![(0usize, self.nodes[0].bbox.distance_squared(p))];
        while let Some((n, d2)) = stack.pop() {
            if d2 >= best2 {
                continue;
            }
            let node = &self.nodes[n];
            if node.count > 0 {
                for &t in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    let [a, b, c] = &self.tris[t as usize];
                    let q = closest_point_on_triangle(p, a, b, c);
                    let e2 = (q - p).norm_squared();
                    if e2 < best2 {
                        best2 = e2;
                        best = Closest {
                            triangle: t,
                            point: q,
                            distance: e2.sqrt(),
                        };
                    }
                }
            } else {
                let l = node.start as usize;
                let (dl, dr) = (
                    self.nodes[l].bbox.distance_squared(p),
                    self.nodes[l + 1].bbox.distance_squared(p),
                );
                // visit the nearer child first
                if dl < dr {
                    stack.push((l + 1, dr));
                    stack.push((l, dl));
                } else {
                    stack.push((l, dl));
                    stack.push((l + 1, dr));
                }
            }
        }
        Some(best)
    }

    /// Number of triangles crossed by the ray `o + t d`, t > 0.
    pub fn ray_crossings(&self, o: &Point3<f64>, d: &Vector3<f64>) -> usize {
        if self.tris.is_empty() {
            return 0;
        }
        let inv = Vector3::new(1.0 / d.x, 1.0 / d.y, 1.0 / d.z);
        let mut hits = 0;
        let mut stack = vec![0usize];
        while let Some(n) = stack.pop() {
            let node = &self.nodes[n];
            if !ray_box(o, &inv, &node.bbox) {
                continue;
            }
            if node.count > 0 {
                for &t in &self.order[node.start as usize..(node.start + node.count) as usize] {
                    let [a, b, c] = &self.tris[t as usize];
                    if ray_triangle(o, d, a, b, c).is_some_and(|s| s > 0.0) {
                        hits += 1;
                    }
                }
            } else {
                stack.push(node.start as usize);
                stack.push(node.start as usize + 1);
            }
        }
        hits
    }

    /// Whether `p` lies inside the closed surface: ray parity along three fixed, generic
    /// directions, decided by majority (robust to a ray grazing an edge or vertex).
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        const DIRS: [[f64; 3]; 3] = [
            [0.5773502691896258, 0.5773502691896258, 0.5773502691896258],
            [-0.2672612419124244, 0.5345224838248488, -0.8017837257372732],
            [0.8164965809277261, -0.4082482904638631, -0.4082482904638631],
        ];
        let mut inside = 0;
        for d in DIRS {
            // perturb slightly so rays avoid the lattice-aligned structure of generated meshes
            let d = Vector3::new(d[0] + 0.0123, d[1] - 0.0071, d[2] + 0.0037);
            if self.ray_crossings(p, &d) % 2 == 1 {
                inside += 1;
            }
        }
        inside >= 2
    }

    /// Signed distance to the closed surface: negative inside.
    pub fn signed_distance(&self, p: &Point3<f64>) -> f64 {
        match self.closest(p) {
            None => f64::INFINITY,
            Some(c) => {
                if self.contains(p) {
                    -c.distance
                } else {
                    c.distance
                }
            }
        }
    }

    /// All pairs `(s, t)`, `s < t`, of triangles of this surface that intersect, ignoring
    /// the contact of neighbours along their shared vertex or edge (see
    /// [`super::geom::triangles_intersect`]).
    pub fn self_intersections(&self) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        if self.tris.is_empty() {
            return out;
        }
        let mut stack = vec![(0usize, 0usize)];
        while let Some((a, b)) = stack.pop() {
            let (na, nb) = (&self.nodes[a], &self.nodes[b]);
            if !na.bbox.intersects(&nb.bbox) {
                continue;
            }
            match (na.count > 0, nb.count > 0) {
                (true, true) => {
                    for &s in &self.order[na.start as usize..(na.start + na.count) as usize] {
                        for &t in &self.order[nb.start as usize..(nb.start + nb.count) as usize] {
                            if (a == b && s >= t) || (a != b && s == t) {
                                continue;
                            }
                            if self.pair_intersects(s, t) {
                                out.push((s.min(t), s.max(t)));
                            }
                        }
                    }
                }
                (false, _) if a == b => {
                    let l = na.start as usize;
                    stack.push((l, l));
                    stack.push((l + 1, l + 1));
                    stack.push((l, l + 1));
                }
                (false, true) => {
                    stack.push((na.start as usize, b));
                    stack.push((na.start as usize + 1, b));
                }
                (true, false) => {
                    stack.push((a, nb.start as usize));
                    stack.push((a, nb.start as usize + 1));
                }
                (false, false) => {
                    let (l, r) = (na.start as usize, nb.start as usize);
                    stack.extend_from_slice(&[(l, r), (l, r + 1), (l + 1, r), (l + 1, r + 1)]);
                }
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    fn pair_intersects(&self, s: u32, t: u32) -> bool {
        let (ta, tb) = (&self.tris[s as usize], &self.tris[t as usize]);
        if !tri_box(ta).intersects(&tri_box(tb)) {
            return false;
        }
        triangles_intersect(ta, &self.ids[s as usize], tb, &self.ids[t as usize])
    }

    /// Pairs `(s, t)` with `s` a triangle of this tree and `t` one of `other` that intersect.
    pub fn intersections_with(&self, other: &Bvh) -> Vec<(u32, u32)> {
        let mut out = Vec::new();
        if self.tris.is_empty() || other.tris.is_empty() {
            return out;
        }
        let mut stack = vec![(0usize, 0usize)];
        while let Some((a, b)) = stack.pop() {
            let (na, nb) = (&self.nodes[a], &other.nodes[b]);
            if !na.bbox.intersects(&nb.bbox) {
                continue;
            }
            match (na.count > 0, nb.count > 0) {
                (true, true) => {
                    for &s in &self.order[na.start as usize..(na.start + na.count) as usize] {
                        for &t in &other.order[nb.start as usize..(nb.start + nb.count) as usize] {
                            let (ta, tb) = (&self.tris[s as usize], &other.tris[t as usize]);
                            if tri_box(ta).intersects(&tri_box(tb))
                                && triangles_intersect(ta, &[0, 1, 2], tb, &[3, 4, 5])
                            {
                                out.push((s, t));
                            }
                        }
                    }
                }
                (false, true) => {
                    stack.push((na.start as usize, b));
                    stack.push((na.start as usize + 1, b));
                }
                (true, false) => {
                    stack.push((a, nb.start as usize));
                    stack.push((a, nb.start as usize + 1));
                }
                (false, false) => {
                    let (l, r) = (na.start as usize, nb.start as usize);
                    stack.extend_from_slice(&[(l, r), (l, r + 1), (l + 1, r), (l + 1, r + 1)]);
                }
            }
        }
        out
    }
}

/// One-sided Hausdorff distance: the largest distance from a vertex of `a` to the surface
/// of `b` (vertex sampling of `a`).
pub fn hausdorff_one_sided(a: &TriMesh, b: &Bvh) -> f64 {
    a.vertices
        .iter()
        .filter_map(|p| b.closest(p))
        .map(|c| c.distance)
        .fold(0.0, f64::max)
}

/// Symmetric Hausdorff distance between two surfaces, sampled at their vertices.
pub fn hausdorff(a: &TriMesh, b: &TriMesh) -> f64 {
    hausdorff_one_sided(a, &Bvh::new(b)).max(hausdorff_one_sided(b, &Bvh::new(a)))
}

fn tri_box(c: &[Point3<f64>; 3]) -> Aabb {
    let mut b = Aabb::empty();
    for p in c {
        b.grow(p);
    }
    b
}

fn ray_box(o: &Point3<f64>, inv: &Vector3<f64>, b: &Aabb) -> bool {
    let mut t0: f64 = 0.0;
    let mut t1 = f64::INFINITY;
    for k in 0..3 {
        let a = (b.min[k] - o[k]) * inv[k];
        let c = (b.max[k] - o[k]) * inv[k];
        let (lo, hi) = if a < c { (a, c) } else { (c, a) };
        t0 = t0.max(lo);
        t1 = t1.min(hi);
        if t0 > t1 {
            return false;
        }
    }
    true
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sphere_queries() {
        let m = TriMesh::icosphere(4).unwrap();
        let bvh = Bvh::new(&m);
        assert!(bvh.self_intersections().is_empty());
        assert!(bvh.contains(&Point3::new(0.1, 0.2, -0.3)));
        assert!(!bvh.contains(&Point3::new(1.1, 0.0, 0.0)));
        let d = bvh.signed_distance(&Point3::new(0.0, 0.0, 0.5));
        assert!((d + 0.5).abs() < 5e-3, "{d}");
        let c = bvh.closest(&Point3::new(2.0, 0.0, 0.0)).unwrap();
        assert!((c.distance - 1.0).abs() < 1e-9);
        // a second, shifted sphere crosses the first
        let mut o = m.clone();
        o.translate(&Vector3::new(1.5, 0.0, 0.0));
        assert!(!bvh.intersections_with(&Bvh::new(&o)).is_empty());
        o.translate(&Vector3::new(1.0, 0.0, 0.0));
        assert!(bvh.intersections_with(&Bvh::new(&o)).is_empty());
    }
}
