//! Geometric queries on a triangle surface: closest points, ray and segment intersection,
//! inside/outside by ray parity, a uniform grid of triangles for local queries, a
//! self-intersection test and a closed-manifold check.

use nalgebra::{Point3, Vector3};
use std::collections::HashMap;

/// Closest point to `p` on a triangle (Ericson, "Real-Time Collision Detection", 5.1.5):
/// the mesh layer's implementation.
pub use crate::mesh::geom::closest_point_on_triangle;

/// Closest point to `p` on the segment [a, b].
pub fn closest_point_on_segment(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>) -> Point3<f64> {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 <= 0.0 {
        return *a;
    }
    let t = ((p - a).dot(&ab) / len2).clamp(0.0, 1.0);
    a + ab * t
}

/// Ray (origin `o`, direction `d`) against triangle (a, b, c), Moller-Trumbore 1997.
/// Returns `(t, u, v)` with the hit at `o + t d` and barycentric coordinates `(1-u-v, u, v)`.
pub fn ray_triangle(
    o: &Point3<f64>,
    d: &Vector3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> Option<(f64, f64, f64)> {
    let e1 = b - a;
    let e2 = c - a;
    let pvec = d.cross(&e2);
    let det = e1.dot(&pvec);
    let scale = e1.norm() * e2.norm() * d.norm();
    if det.abs() <= 1e-14 * scale {
        return None;
    }
    let inv = 1.0 / det;
    let tvec = o - a;
    let u = tvec.dot(&pvec) * inv;
    if !(0.0..=1.0).contains(&u) {
        return None;
    }
    let qvec = tvec.cross(&e1);
    let v = d.dot(&qvec) * inv;
    if v < 0.0 || u + v > 1.0 {
        return None;
    }
    Some((e2.dot(&qvec) * inv, u, v))
}

/// True when the segment [p, q] crosses the triangle (a, b, c).
pub fn segment_crosses_triangle(
    p: &Point3<f64>,
    q: &Point3<f64>,
    a: &Point3<f64>,
    b: &Point3<f64>,
    c: &Point3<f64>,
) -> bool {
    matches!(ray_triangle(p, &(q - p), a, b, c), Some((t, _, _)) if (0.0..=1.0).contains(&t))
}

/// True when two triangles that share no vertex intersect (non-coplanar case: some edge of
/// one crosses the other; coplanar overlaps are not detected).
pub fn triangles_intersect(t1: [&Point3<f64>; 3], t2: [&Point3<f64>; 3]) -> bool {
    for k in 0..3 {
        if segment_crosses_triangle(t1[k], t1[(k + 1) % 3], t2[0], t2[1], t2[2])
            || segment_crosses_triangle(t2[k], t2[(k + 1) % 3], t1[0], t1[1], t1[2])
        {
            return true;
        }
    }
    false
}

/// A uniform grid over a triangle surface: each cell lists the triangles whose bounding box
/// overlaps it. Queries visit only the cells a box overlaps.
#[derive(Clone, Debug)]
pub struct TriangleGrid {
    origin: Point3<f64>,
    cell: f64,
    dims: [usize; 3],
    start: Vec<u32>,
    items: Vec<u32>,
}

impl TriangleGrid {
    /// Builds the grid with cells of edge `cell` (metres; twice the mean edge length is a
    /// good choice).
    pub fn new(vertices: &[Point3<f64>], triangles: &[[u32; 3]], cell: f64) -> Self {
        let mut lo = Point3::new(f64::MAX, f64::MAX, f64::MAX);
        let mut hi = Point3::new(f64::MIN, f64::MIN, f64::MIN);
        for v in vertices {
            lo = lo.inf(v);
            hi = hi.sup(v);
        }
        if vertices.is_empty() {
            lo = Point3::origin();
            hi = Point3::origin();
        }
        let cell = cell.max(1e-6);
        let dims = [0, 1, 2].map(|k| (((hi[k] - lo[k]) / cell).floor() as usize + 1).min(512));
        let mut grid = TriangleGrid {
            origin: lo,
            cell,
            dims,
            start: vec![],
            items: vec![],
        };
        let ncell = dims[0] * dims[1] * dims[2];
        let mut count = vec![0u32; ncell + 1];
        let mut boxes = Vec::with_capacity(triangles.len());
        for t in triangles {
            let (a, b) = tri_box(vertices, t);
            let r = grid.cell_range(&a, &b);
            boxes.push(r);
            grid.for_cells(r, |c| count[c + 1] += 1);
        }
        for i in 0..ncell {
            count[i + 1] += count[i];
        }
        let mut fill = count.clone();
        let mut items = vec![0u32; count[ncell] as usize];
        for (ti, r) in boxes.iter().enumerate() {
            grid.for_cells(*r, |c| {
                items[fill[c] as usize] = ti as u32;
                fill[c] += 1;
            });
        }
        grid.start = count;
        grid.items = items;
        grid
    }

    fn cell_range(&self, a: &Point3<f64>, b: &Point3<f64>) -> [[usize; 2]; 3] {
        [0, 1, 2].map(|k| {
            let f = |x: f64| {
                (((x - self.origin[k]) / self.cell).floor().max(0.0) as usize).min(self.dims[k] - 1)
            };
            [f(a[k]), f(b[k])]
        })
    }

    fn for_cells(&self, r: [[usize; 2]; 3], mut f: impl FnMut(usize)) {
        for i in r[0][0]..=r[0][1] {
            for j in r[1][0]..=r[1][1] {
                for k in r[2][0]..=r[2][1] {
                    f((i * self.dims[1] + j) * self.dims[2] + k);
                }
            }
        }
    }

    /// Calls `f` once for every triangle whose cells overlap the box [a, b] (a triangle may
    /// be reported once per overlapped cell; `stamp` of length `triangles.len()` with a fresh
    /// `tag` dedupes).
    pub fn visit_box(
        &self,
        a: &Point3<f64>,
        b: &Point3<f64>,
        stamp: &mut [u32],
        tag: u32,
        mut f: impl FnMut(u32),
    ) {
        let r = self.cell_range(a, b);
        self.for_cells(r, |c| {
            for &t in &self.items[self.start[c] as usize..self.start[c + 1] as usize] {
                if stamp[t as usize] != tag {
                    stamp[t as usize] = tag;
                    f(t);
                }
            }
        });
    }
}

/// Axis-aligned bounding box of one triangle.
pub fn tri_box(vertices: &[Point3<f64>], t: &[u32; 3]) -> (Point3<f64>, Point3<f64>) {
    let (a, b, c) = (
        &vertices[t[0] as usize],
        &vertices[t[1] as usize],
        &vertices[t[2] as usize],
    );
    (a.inf(b).inf(c), a.sup(b).sup(c))
}

/// Mean edge length of a triangle surface.
pub fn mean_edge_length(vertices: &[Point3<f64>], triangles: &[[u32; 3]]) -> f64 {
    let mut sum = 0.0;
    for t in triangles {
        for k in 0..3 {
            sum += (vertices[t[k] as usize] - vertices[t[(k + 1) % 3] as usize]).norm();
        }
    }
    sum / (3 * triangles.len().max(1)) as f64
}

/// Pairs of triangles sharing no vertex that intersect each other (empty for a surface free
/// of self-intersections). Uses a [`TriangleGrid`], so the cost is about linear in the
/// number of triangles for an evenly meshed surface.
pub fn self_intersections(vertices: &[Point3<f64>], triangles: &[[u32; 3]]) -> Vec<(usize, usize)> {
    let grid = TriangleGrid::new(
        vertices,
        triangles,
        2.0 * mean_edge_length(vertices, triangles),
    );
    let mut stamp = vec![u32::MAX; triangles.len()];
    let mut found = Vec::new();
    for (i, t) in triangles.iter().enumerate() {
        let (a, b) = tri_box(vertices, t);
        let p = |k: usize| &vertices[t[k] as usize];
        grid.visit_box(&a, &b, &mut stamp, i as u32, |j| {
            let j = j as usize;
            if j <= i {
                return;
            }
            let u = &triangles[j];
            if t.iter().any(|x| u.contains(x)) {
                return;
            }
            let (c, d) = tri_box(vertices, u);
            if c.x > b.x || c.y > b.y || c.z > b.z || d.x < a.x || d.y < a.y || d.z < a.z {
                return;
            }
            let q = |k: usize| &vertices[u[k] as usize];
            if triangles_intersect([p(0), p(1), p(2)], [q(0), q(1), q(2)]) {
                found.push((i, j));
            }
        });
    }
    found
}

/// Checks that a triangle surface is a closed, consistently oriented 2-manifold: every
/// directed edge appears once and its reverse once, every vertex is used and its triangle
/// fan is a single cycle. Returns a description of the first defect found.
pub fn check_closed_manifold(
    n_vertices: usize,
    triangles: &[[u32; 3]],
) -> std::result::Result<(), String> {
    let mut directed: HashMap<(u32, u32), usize> = HashMap::with_capacity(3 * triangles.len());
    for (ti, t) in triangles.iter().enumerate() {
        if t[0] == t[1] || t[1] == t[2] || t[0] == t[2] {
            return Err(format!("triangle {ti} is degenerate: {t:?}"));
        }
        for k in 0..3 {
            let e = (t[k], t[(k + 1) % 3]);
            if e.0 as usize >= n_vertices || e.1 as usize >= n_vertices {
                return Err(format!("triangle {ti} indexes a missing vertex: {t:?}"));
            }
            if directed.insert(e, ti).is_some() {
                return Err(format!(
                    "directed edge {e:?} used twice (orientation or non-manifold edge)"
                ));
            }
        }
    }
    for (e, ti) in &directed {
        if !directed.contains_key(&(e.1, e.0)) {
            return Err(format!("edge {e:?} of triangle {ti} is a boundary edge"));
        }
    }
    // Each vertex: its outgoing edges form one cycle around it (a disc, not a pinch).
    let mut next: HashMap<(u32, u32), u32> = HashMap::with_capacity(directed.len());
    let mut out_count = vec![0usize; n_vertices];
    for t in triangles {
        for k in 0..3 {
            // around vertex t[k]: from neighbour t[k+1] to neighbour t[k+2]
            next.insert((t[k], t[(k + 1) % 3]), t[(k + 2) % 3]);
            out_count[t[k] as usize] += 1;
        }
    }
    let mut first: Vec<Option<u32>> = vec![None; n_vertices];
    for t in triangles {
        for k in 0..3 {
            first[t[k] as usize].get_or_insert(t[(k + 1) % 3]);
        }
    }
    for v in 0..n_vertices {
        let Some(start) = first[v] else {
            return Err(format!("vertex {v} is not used by any triangle"));
        };
        let mut cur = start;
        let mut steps = 0;
        loop {
            cur = match next.get(&(v as u32, cur)) {
                Some(&n) => n,
                None => return Err(format!("fan of vertex {v} is open")),
            };
            steps += 1;
            if cur == start || steps > out_count[v] {
                break;
            }
        }
        if steps != out_count[v] {
            return Err(format!(
                "vertex {v} is non-manifold ({steps} of {} triangles in its first fan)",
                out_count[v]
            ));
        }
    }
    Ok(())
}

/// True when `p` lies inside the closed surface (parity of crossings of a ray from `p`).
pub fn is_inside(p: &Point3<f64>, vertices: &[Point3<f64>], triangles: &[[u32; 3]]) -> bool {
    // A direction with irrational-looking components avoids grazing edges and vertices.
    let d = Vector3::new(0.8017837, 0.2672612, 0.5345225);
    let mut crossings = 0usize;
    for t in triangles {
        let (a, b, c) = (
            &vertices[t[0] as usize],
            &vertices[t[1] as usize],
            &vertices[t[2] as usize],
        );
        if let Some((s, _, _)) = ray_triangle(p, &d, a, b, c)
            && s > 0.0
        {
            crossings += 1;
        }
    }
    crossings % 2 == 1
}

/// Distance from `p` to the nearest point of the surface (brute force over triangles).
pub fn distance_to_surface(
    p: &Point3<f64>,
    vertices: &[Point3<f64>],
    triangles: &[[u32; 3]],
) -> f64 {
    let mut best = f64::MAX;
    for t in triangles {
        let (a, b, c) = (
            &vertices[t[0] as usize],
            &vertices[t[1] as usize],
            &vertices[t[2] as usize],
        );
        // Cheap reject by the distance to the bounding sphere of the triangle.
        let centre = Point3::from((a.coords + b.coords + c.coords) / 3.0);
        let radius = (a - centre)
            .norm()
            .max((b - centre).norm())
            .max((c - centre).norm());
        if (p - centre).norm() - radius >= best {
            continue;
        }
        best = best.min((p - closest_point_on_triangle(p, a, b, c)).norm());
    }
    best
}
