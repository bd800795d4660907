//! Geometric predicates on triangles: closest point, ray and segment crossings, and the
//! triangle-triangle intersection test of Moller (1997, "A fast triangle-triangle
//! intersection test", interval overlap on the line where the two planes meet), with the
//! contact of mesh neighbours along a shared vertex or edge not counted as an intersection.

use nalgebra::{Point2, Point3, Vector3};

type P = Point3<f64>;

/// Closest point to `p` on triangle `(a, b, c)`, by the Voronoi regions of its vertices,
/// edges and face (Ericson, Real-Time Collision Detection, 5.1.5).
pub fn closest_point_on_triangle(p: &P, a: &P, b: &P, c: &P) -> P {
    let ab = b - a;
    let ac = c - a;
    let ap = p - a;
    let d1 = ab.dot(&ap);
    let d2 = ac.dot(&ap);
    if d1 <= 0.0 && d2 <= 0.0 {
        return *a;
    }
    let bp = p - b;
    let d3 = ab.dot(&bp);
    let d4 = ac.dot(&bp);
    if d3 >= 0.0 && d4 <= d3 {
        return *b;
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        let v = d1 / (d1 - d3);
        return a + ab * v;
    }
    let cp = p - c;
    let d5 = ab.dot(&cp);
    let d6 = ac.dot(&cp);
    if d6 >= 0.0 && d5 <= d6 {
        return *c;
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        let w = d2 / (d2 - d6);
        return a + ac * w;
    }
    let va = d3 * d6 - d5 * d4;
    if va <= 0.0 && (d4 - d3) >= 0.0 && (d5 - d6) >= 0.0 {
        let w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return b + (c - b) * w;
    }
    let denom = va + vb + vc;
    if denom.abs() < f64::MIN_POSITIVE {
        return *a;
    }
    let v = vb / denom;
    let w = vc / denom;
    a + ab * v + ac * w
}

/// Parameter `t` where the line `o + t d` crosses the closed triangle `(a, b, c)` (Moller &
/// Trumbore 1997), edges and corners included with barycentric tolerance `eps`, so that a ray
/// through a vertex of a surface is not lost between its triangles; None when it misses or
/// runs parallel to the plane. [`ray_triangle`] is the half-open variant for parity counts.
pub fn ray_triangle_closed(o: &P, d: &Vector3<f64>, a: &P, b: &P, c: &P, eps: f64) -> Option<f64> {
    let (e1, e2) = (b - a, c - a);
    let h = d.cross(&e2);
    let det = e1.dot(&h);
    if det.abs() < 1e-300 {
        return None;
    }
    let f = 1.0 / det;
    let s = o - a;
    let u = f * s.dot(&h);
    let q = s.cross(&e1);
    let v = f * d.dot(&q);
    if u < -eps || v < -eps || u + v > 1.0 + eps {
        return None;
    }
    Some(f * e2.dot(&q))
}

/// Parameter `t` where the line `o + t d` crosses triangle `(a, b, c)` (Moller & Trumbore
/// 1997), None when it misses or runs parallel to the plane. Edges count as hits on one side
/// only (half-open barycentric test) so that a ray through a shared edge is counted once.
pub fn ray_triangle(o: &P, d: &Vector3<f64>, a: &P, b: &P, c: &P) -> Option<f64> {
    let e1 = b - a;
    let e2 = c - a;
    let h = d.cross(&e2);
    let det = e1.dot(&h);
    if det.abs() < 1e-300 {
        return None;
    }
    let f = 1.0 / det;
    let s = o - a;
    let u = f * s.dot(&h);
    if !(0.0..1.0).contains(&u) {
        return None;
    }
    let q = s.cross(&e1);
    let v = f * d.dot(&q);
    if v < 0.0 || u + v >= 1.0 {
        return None;
    }
    Some(f * e2.dot(&q))
}

/// Whether the segment `p q` crosses triangle `(a, b, c)` at a parameter in `(t_min, 1]`
/// (coplanar segments are not counted).
fn segment_hits(p: &P, q: &P, a: &P, b: &P, c: &P, t_min: f64) -> bool {
    let d = q - p;
    let e1 = b - a;
    let e2 = c - a;
    let h = d.cross(&e2);
    let det = e1.dot(&h);
    let scale = d.norm() * e1.norm() * e2.norm();
    if det.abs() <= 1e-12 * scale {
        return false;
    }
    let f = 1.0 / det;
    let s = p - a;
    let u = f * s.dot(&h);
    if !(0.0..=1.0).contains(&u) {
        return false;
    }
    let qv = s.cross(&e1);
    let v = f * d.dot(&qv);
    if v < 0.0 || u + v > 1.0 {
        return false;
    }
    let t = f * e2.dot(&qv);
    t > t_min && t <= 1.0
}

/// Whether two triangles of a mesh intersect, given their corners and vertex indices.
/// Neighbours are not reported for touching along what they share: two triangles sharing an
/// edge intersect only when folded flat onto each other; two sharing a vertex intersect when
/// an edge of one crosses the other away from that vertex; others use Moller's test.
pub fn triangles_intersect(a: &[P; 3], ia: &[u32; 3], b: &[P; 3], ib: &[u32; 3]) -> bool {
    let shared: Vec<(usize, usize)> = (0..3)
        .flat_map(|i| (0..3).filter(move |&j| ia[i] == ib[j]).map(move |j| (i, j)))
        .collect();
    match shared.len() {
        0 => tri_tri(a, b),
        1 => {
            let (i, j) = shared[0];
            let tol = 1e-9;
            let (a1, a2) = (a[(i + 1) % 3], a[(i + 2) % 3]);
            let (b1, b2) = (b[(j + 1) % 3], b[(j + 2) % 3]);
            segment_hits(&a1, &a2, &b[0], &b[1], &b[2], -1.0)
                || segment_hits(&b1, &b2, &a[0], &a[1], &a[2], -1.0)
                || segment_hits(&a[i], &a1, &b[0], &b[1], &b[2], tol)
                || segment_hits(&a[i], &a2, &b[0], &b[1], &b[2], tol)
                || segment_hits(&b[j], &b1, &a[0], &a[1], &a[2], tol)
                || segment_hits(&b[j], &b2, &a[0], &a[1], &a[2], tol)
        }
        2 => {
            // folded flat: the far vertex of b lies in a's plane on a's side of the edge
            let ka = (0..3)
                .find(|&k| !shared.iter().any(|s| s.0 == k))
                .unwrap_or(0);
            let kb = (0..3)
                .find(|&k| !shared.iter().any(|s| s.1 == k))
                .unwrap_or(0);
            let n = (a[1] - a[0]).cross(&(a[2] - a[0]));
            let len = (a[shared[0].0] - a[shared[1].0]).norm();
            let off = b[kb] - a[shared[0].0];
            if n.norm() == 0.0 || n.normalize().dot(&off).abs() > 1e-9 * len {
                return false;
            }
            let e = a[shared[1].0] - a[shared[0].0];
            let sa = e.cross(&(a[ka] - a[shared[0].0]));
            let sb = e.cross(&off);
            sa.dot(&sb) > 0.0
        }
        _ => true,
    }
}

/// Moller's interval test for two triangles sharing no vertex.
pub fn tri_tri(a: &[P; 3], b: &[P; 3]) -> bool {
    let n2 = (b[1] - b[0]).cross(&(b[2] - b[0]));
    let n1 = (a[1] - a[0]).cross(&(a[2] - a[0]));
    let scale = (a[1] - a[0])
        .norm()
        .max((b[1] - b[0]).norm())
        .max((b[2] - b[0]).norm());
    let da = plane_distances(&n2, &b[0], a, scale);
    if same_side(&da) {
        return false;
    }
    let db = plane_distances(&n1, &a[0], b, scale);
    if same_side(&db) {
        return false;
    }
    if da.iter().all(|d| *d == 0.0) {
        return coplanar(&n1, a, b);
    }
    let dir = n1.cross(&n2);
    let axis = dir.iamax();
    let pa = [a[0][axis], a[1][axis], a[2][axis]];
    let pb = [b[0][axis], b[1][axis], b[2][axis]];
    let (Some(ia), Some(ib)) = (interval(&pa, &da), interval(&pb, &db)) else {
        return coplanar(&n1, a, b);
    };
    ia.0 <= ib.1 && ib.0 <= ia.1
}

fn plane_distances(n: &Vector3<f64>, o: &P, t: &[P; 3], scale: f64) -> [f64; 3] {
    let eps = 1e-12 * n.norm() * scale;
    let mut d = [0.0; 3];
    for k in 0..3 {
        let v = n.dot(&(t[k] - o));
        d[k] = if v.abs() <= eps { 0.0 } else { v };
    }
    d
}

fn same_side(d: &[f64; 3]) -> bool {
    (d[0] > 0.0 && d[1] > 0.0 && d[2] > 0.0) || (d[0] < 0.0 && d[1] < 0.0 && d[2] < 0.0)
}

fn interval(p: &[f64; 3], d: &[f64; 3]) -> Option<(f64, f64)> {
    let k = if d[0] * d[1] > 0.0 {
        2
    } else if d[0] * d[2] > 0.0 {
        1
    } else if d[1] * d[2] > 0.0 || d[0] != 0.0 {
        0
    } else if d[1] != 0.0 {
        1
    } else if d[2] != 0.0 {
        2
    } else {
        return None;
    };
    let (i, j) = ((k + 1) % 3, (k + 2) % 3);
    let ti = p[k] + (p[i] - p[k]) * d[k] / (d[k] - d[i]);
    let tj = p[k] + (p[j] - p[k]) * d[k] / (d[k] - d[j]);
    Some((ti.min(tj), ti.max(tj)))
}

fn coplanar(n: &Vector3<f64>, a: &[P; 3], b: &[P; 3]) -> bool {
    let axis = n.iamax();
    let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
    let pa: Vec<Point2<f64>> = a.iter().map(|p| Point2::new(p[u], p[v])).collect();
    let pb: Vec<Point2<f64>> = b.iter().map(|p| Point2::new(p[u], p[v])).collect();
    for i in 0..3 {
        for j in 0..3 {
            if segments_cross(&pa[i], &pa[(i + 1) % 3], &pb[j], &pb[(j + 1) % 3]) {
                return true;
            }
        }
    }
    in_triangle_2d(&pa[0], &pb) || in_triangle_2d(&pb[0], &pa)
}

fn orient(a: &Point2<f64>, b: &Point2<f64>, c: &Point2<f64>) -> f64 {
    (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x)
}

fn segments_cross(a: &Point2<f64>, b: &Point2<f64>, c: &Point2<f64>, d: &Point2<f64>) -> bool {
    let (o1, o2) = (orient(a, b, c), orient(a, b, d));
    let (o3, o4) = (orient(c, d, a), orient(c, d, b));
    o1 * o2 < 0.0 && o3 * o4 < 0.0
}

fn in_triangle_2d(p: &Point2<f64>, t: &[Point2<f64>]) -> bool {
    let s = [
        orient(&t[0], &t[1], p),
        orient(&t[1], &t[2], p),
        orient(&t[2], &t[0], p),
    ];
    (s.iter().all(|x| *x > 0.0)) || (s.iter().all(|x| *x < 0.0))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(x: f64, y: f64, z: f64) -> P {
        P::new(x, y, z)
    }

    #[test]
    fn crossing_and_separate_triangles() {
        let a = [p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0)];
        let b = [p(0.2, 0.2, -0.5), p(0.2, 0.2, 0.5), p(0.8, 0.9, 0.0)];
        assert!(tri_tri(&a, &b));
        let c = [p(0.2, 0.2, 0.1), p(0.2, 0.3, 0.5), p(0.8, 0.9, 0.2)];
        assert!(!tri_tri(&a, &c));
        // coplanar overlapping and coplanar disjoint
        let d = [p(0.1, 0.1, 0.0), p(2.0, 0.1, 0.0), p(0.1, 2.0, 0.0)];
        assert!(tri_tri(&a, &d));
        let e = [p(2.0, 2.0, 0.0), p(3.0, 2.0, 0.0), p(2.0, 3.0, 0.0)];
        assert!(!tri_tri(&a, &e));
    }

    #[test]
    fn neighbours_touching_do_not_count() {
        let a = [p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0)];
        let b = [p(0.0, 0.0, 0.0), p(0.0, 1.0, 0.0), p(-1.0, 0.0, 0.3)];
        assert!(!triangles_intersect(&a, &[0, 1, 2], &b, &[0, 2, 3]));
        // folded flat onto a
        let f = [p(0.0, 0.0, 0.0), p(0.0, 1.0, 0.0), p(0.5, 0.2, 0.0)];
        assert!(triangles_intersect(&a, &[0, 1, 2], &f, &[0, 2, 3]));
        // sharing one vertex, the other piercing through a
        let g = [p(0.0, 0.0, 0.0), p(0.5, 0.3, -1.0), p(0.3, 0.5, 1.0)];
        assert!(triangles_intersect(&a, &[0, 1, 2], &g, &[0, 5, 6]));
        let h = [p(0.0, 0.0, 0.0), p(-0.5, -0.3, -1.0), p(-0.3, -0.5, 1.0)];
        assert!(!triangles_intersect(&a, &[0, 1, 2], &h, &[0, 5, 6]));
    }

    #[test]
    fn closest_point_regions() {
        let (a, b, c) = (p(0.0, 0.0, 0.0), p(1.0, 0.0, 0.0), p(0.0, 1.0, 0.0));
        let q = closest_point_on_triangle(&p(0.2, 0.2, 3.0), &a, &b, &c);
        assert!((q - p(0.2, 0.2, 0.0)).norm() < 1e-15);
        assert_eq!(
            closest_point_on_triangle(&p(-1.0, -1.0, 0.0), &a, &b, &c),
            a
        );
        assert_eq!(
            closest_point_on_triangle(&p(0.5, -1.0, 1.0), &a, &b, &c),
            p(0.5, 0.0, 0.0)
        );
        let q = closest_point_on_triangle(&p(1.0, 1.0, 0.0), &a, &b, &c);
        assert!((q - p(0.5, 0.5, 0.0)).norm() < 1e-15);
    }
}
