//! The triangle surface [`TriMesh`]: geometry (area, signed volume, centroid, normals, bounding
//! box), topology (edges, adjacency, closedness, edge-manifoldness, orientation consistency),
//! rigid and affine transforms, and the icosphere generator.

use std::collections::HashMap;

use nalgebra::{Matrix4, Point3, Vector3};

use crate::{Error, Result};

/// Largest subdivision level accepted by [`TriMesh::icosphere`] (655,362 vertices).
pub const MAX_ICOSPHERE_SUBDIVISIONS: u32 = 8;

/// A triangle surface: shared vertices and counter-clockwise (outward, for a closed surface)
/// index triples.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TriMesh {
    /// Vertex positions.
    pub vertices: Vec<Point3<f64>>,
    /// Triangles as indices into `vertices`, counter-clockwise seen from outside.
    pub triangles: Vec<[u32; 3]>,
}

/// An axis-aligned bounding box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Aabb {
    /// Smallest corner.
    pub min: Point3<f64>,
    /// Largest corner.
    pub max: Point3<f64>,
}

impl Aabb {
    /// The empty box (min = +inf, max = -inf), neutral for [`Aabb::grow`].
    pub fn empty() -> Self {
        Aabb {
            min: Point3::new(f64::INFINITY, f64::INFINITY, f64::INFINITY),
            max: Point3::new(f64::NEG_INFINITY, f64::NEG_INFINITY, f64::NEG_INFINITY),
        }
    }

    /// Enlarges the box to contain `p`.
    pub fn grow(&mut self, p: &Point3<f64>) {
        self.min = self.min.inf(p);
        self.max = self.max.sup(p);
    }

    /// Enlarges the box to contain `other`.
    pub fn merge(&mut self, other: &Aabb) {
        self.min = self.min.inf(&other.min);
        self.max = self.max.sup(&other.max);
    }

    /// Whether the two boxes overlap (touching counts).
    pub fn intersects(&self, other: &Aabb) -> bool {
        (0..3).all(|k| self.min[k] <= other.max[k] && other.min[k] <= self.max[k])
    }

    /// Edge lengths of the box.
    pub fn extent(&self) -> Vector3<f64> {
        self.max - self.min
    }

    /// Centre of the box.
    pub fn center(&self) -> Point3<f64> {
        nalgebra::center(&self.min, &self.max)
    }

    /// Length of the diagonal.
    pub fn diagonal(&self) -> f64 {
        self.extent().norm()
    }

    /// Squared distance from `p` to the box (0 inside).
    pub fn distance_squared(&self, p: &Point3<f64>) -> f64 {
        let mut d = 0.0;
        for k in 0..3 {
            let e = (self.min[k] - p[k]).max(0.0).max(p[k] - self.max[k]);
            d += e * e;
        }
        d
    }
}

/// Topological summary of a surface, as returned by [`TriMesh::topology`].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize)]
pub struct Topology {
    /// Number of undirected edges.
    pub edges: usize,
    /// Edges with exactly one adjacent triangle.
    pub boundary_edges: usize,
    /// Edges with more than two adjacent triangles.
    pub non_manifold_edges: usize,
    /// Interior edges whose two triangles traverse them in the same direction.
    pub inconsistent_edges: usize,
    /// Triangles with a repeated vertex index.
    pub degenerate_triangles: usize,
    /// Vertices not referenced by any triangle.
    pub unreferenced_vertices: usize,
    /// Euler characteristic V - E + F over referenced vertices.
    pub euler_characteristic: i64,
}

impl Topology {
    /// Every edge has exactly two triangles (a closed 2-manifold along its edges).
    pub fn is_closed(&self) -> bool {
        self.boundary_edges == 0 && self.non_manifold_edges == 0
    }

    /// No edge has more than two triangles.
    pub fn is_edge_manifold(&self) -> bool {
        self.non_manifold_edges == 0
    }

    /// Neighbouring triangles traverse their shared edge in opposite directions.
    pub fn is_consistently_oriented(&self) -> bool {
        self.inconsistent_edges == 0
    }
}

/// Vertex and edge adjacency of a [`TriMesh`], built once by [`TriMesh::adjacency`].
#[derive(Debug, Clone)]
pub struct Adjacency {
    /// Triangles around each vertex.
    pub vertex_faces: Vec<Vec<u32>>,
    /// Vertices sharing an edge with each vertex (sorted, unique).
    pub vertex_neighbours: Vec<Vec<u32>>,
    /// Triangles around each undirected edge, keyed by `(min, max)` vertex index.
    pub edge_faces: HashMap<(u32, u32), Vec<u32>>,
}

impl Adjacency {
    /// Triangles sharing the undirected edge `(a, b)`.
    pub fn faces_of_edge(&self, a: u32, b: u32) -> &[u32] {
        self.edge_faces
            .get(&edge_key(a, b))
            .map(|v| v.as_slice())
            .unwrap_or(&[])
    }

    /// Triangles sharing an edge with triangle `t` of `mesh` (at most one per edge listed
    /// when the edge is manifold).
    pub fn face_neighbours(&self, mesh: &TriMesh, t: usize) -> Vec<u32> {
        let [a, b, c] = mesh.triangles[t];
        let mut out = Vec::with_capacity(3);
        for (u, v) in [(a, b), (b, c), (c, a)] {
            for &f in self.faces_of_edge(u, v) {
                if f as usize != t && !out.contains(&f) {
                    out.push(f);
                }
            }
        }
        out
    }

    /// Vertices on boundary edges (edges with a single triangle).
    pub fn boundary_vertices(&self) -> Vec<bool> {
        let mut b = vec![false; self.vertex_faces.len()];
        for (&(u, v), f) in &self.edge_faces {
            if f.len() == 1 {
                b[u as usize] = true;
                b[v as usize] = true;
            }
        }
        b
    }
}

/// The undirected key `(min, max)` of edge `(a, b)`.
pub fn edge_key(a: u32, b: u32) -> (u32, u32) {
    if a < b { (a, b) } else { (b, a) }
}

impl TriMesh {
    /// A mesh from vertices and triangles, checking that indices are in range and positions
    /// are finite.
    pub fn new(vertices: Vec<Point3<f64>>, triangles: Vec<[u32; 3]>) -> Result<Self> {
        let mesh = TriMesh {
            vertices,
            triangles,
        };
        mesh.validate()?;
        Ok(mesh)
    }

    /// Checks index ranges and finiteness of coordinates.
    pub fn validate(&self) -> Result<()> {
        if let Some(i) = self
            .vertices
            .iter()
            .position(|p| !p.coords.iter().all(|c| c.is_finite()))
        {
            return Err(Error::invalid(
                format!("vertices[{i}]"),
                format!("{:?}", self.vertices[i].coords.as_slice()),
                "finite coordinates",
            ));
        }
        let n = self.vertices.len();
        for (t, tri) in self.triangles.iter().enumerate() {
            for &i in tri {
                if i as usize >= n {
                    return Err(Error::invalid(
                        format!("triangles[{t}]"),
                        i,
                        format!("vertex index in [0, {})", n),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Number of vertices.
    pub fn num_vertices(&self) -> usize {
        self.vertices.len()
    }

    /// Number of triangles.
    pub fn num_triangles(&self) -> usize {
        self.triangles.len()
    }

    /// The three corner positions of triangle `t`.
    pub fn corners(&self, t: usize) -> [Point3<f64>; 3] {
        let [a, b, c] = self.triangles[t];
        [
            self.vertices[a as usize],
            self.vertices[b as usize],
            self.vertices[c as usize],
        ]
    }

    /// (b - a) x (c - a) of triangle `t`: normal times twice the area.
    pub fn face_cross(&self, t: usize) -> Vector3<f64> {
        let [a, b, c] = self.corners(t);
        (b - a).cross(&(c - a))
    }

    /// Unit normal of triangle `t` (zero for a degenerate triangle).
    pub fn face_normal(&self, t: usize) -> Vector3<f64> {
        self.face_cross(t)
            .try_normalize(0.0)
            .unwrap_or_else(Vector3::zeros)
    }

    /// Unit normals of all triangles.
    pub fn face_normals(&self) -> Vec<Vector3<f64>> {
        (0..self.triangles.len())
            .map(|t| self.face_normal(t))
            .collect()
    }

    /// Area of triangle `t`.
    pub fn face_area(&self, t: usize) -> f64 {
        0.5 * self.face_cross(t).norm()
    }

    /// Centroid of triangle `t`.
    pub fn face_centroid(&self, t: usize) -> Point3<f64> {
        let [a, b, c] = self.corners(t);
        Point3::from((a.coords + b.coords + c.coords) / 3.0)
    }

    /// Area-weighted unit vertex normals (sum of the adjacent triangles' (b-a)x(c-a)); a vertex
    /// with no triangle gets a zero normal.
    pub fn vertex_normals(&self) -> Vec<Vector3<f64>> {
        let mut n = vec![Vector3::zeros(); self.vertices.len()];
        for t in 0..self.triangles.len() {
            let c = self.face_cross(t);
            for &i in &self.triangles[t] {
                n[i as usize] += c;
            }
        }
        for v in &mut n {
            *v = v.try_normalize(0.0).unwrap_or_else(Vector3::zeros);
        }
        n
    }

    /// Total surface area.
    pub fn area(&self) -> f64 {
        (0..self.triangles.len()).map(|t| self.face_area(t)).sum()
    }

    /// Signed enclosed volume by the divergence theorem, V = (1/6) sum a . (b x c), positive
    /// for a closed surface with outward (counter-clockwise) triangles. Computed relative to
    /// the bounding-box centre to limit cancellation.
    pub fn volume(&self) -> f64 {
        let o = self.bounding_box().center();
        let mut v = 0.0;
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.corners(t);
            v += (a - o).dot(&(b - o).cross(&(c - o)));
        }
        v / 6.0
    }

    /// Centroid of the enclosed solid (divergence theorem, tetrahedra fanned from the box
    /// centre); falls back to the area-weighted surface centroid when the volume vanishes.
    pub fn centroid(&self) -> Point3<f64> {
        let o = self.bounding_box().center();
        let mut v6 = 0.0;
        let mut m = Vector3::zeros();
        for t in 0..self.triangles.len() {
            let [a, b, c] = self.corners(t);
            let (a, b, c) = (a - o, b - o, c - o);
            let d = a.dot(&b.cross(&c));
            v6 += d;
            m += d * (a + b + c) / 4.0;
        }
        if v6.abs() > 1e-300 {
            o + m / v6
        } else {
            self.surface_centroid()
        }
    }

    /// Area-weighted centroid of the surface itself.
    pub fn surface_centroid(&self) -> Point3<f64> {
        let mut a = 0.0;
        let mut m = Vector3::zeros();
        for t in 0..self.triangles.len() {
            let w = self.face_area(t);
            a += w;
            m += w * self.face_centroid(t).coords;
        }
        if a > 0.0 {
            Point3::from(m / a)
        } else {
            self.vertex_mean()
        }
    }

    /// Plain average of the vertex positions (Peeters & Pronost 2013, eq. 5).
    pub fn vertex_mean(&self) -> Point3<f64> {
        if self.vertices.is_empty() {
            return Point3::origin();
        }
        let s: Vector3<f64> = self.vertices.iter().map(|p| p.coords).sum();
        Point3::from(s / self.vertices.len() as f64)
    }

    /// Axis-aligned bounding box of the vertices ([`Aabb::empty`] for no vertex).
    pub fn bounding_box(&self) -> Aabb {
        let mut b = Aabb::empty();
        for p in &self.vertices {
            b.grow(p);
        }
        if self.vertices.is_empty() {
            Aabb {
                min: Point3::origin(),
                max: Point3::origin(),
            }
        } else {
            b
        }
    }

    /// Unique undirected edges `[a, b]` with `a < b`, sorted.
    pub fn edges(&self) -> Vec<[u32; 2]> {
        let mut e: Vec<[u32; 2]> = Vec::with_capacity(self.triangles.len() * 3);
        for &[a, b, c] in &self.triangles {
            for (u, v) in [(a, b), (b, c), (c, a)] {
                if u != v {
                    let (p, q) = edge_key(u, v);
                    e.push([p, q]);
                }
            }
        }
        e.sort_unstable();
        e.dedup();
        e
    }

    /// Mean edge length (0 for no edge).
    pub fn mean_edge_length(&self) -> f64 {
        let e = self.edges();
        if e.is_empty() {
            return 0.0;
        }
        e.iter()
            .map(|&[a, b]| (self.vertices[a as usize] - self.vertices[b as usize]).norm())
            .sum::<f64>()
            / e.len() as f64
    }

    /// Vertex-to-face, vertex-to-vertex and edge-to-face adjacency.
    pub fn adjacency(&self) -> Adjacency {
        let n = self.vertices.len();
        let mut vertex_faces = vec![Vec::new(); n];
        let mut vertex_neighbours: Vec<Vec<u32>> = vec![Vec::new(); n];
        let mut edge_faces: HashMap<(u32, u32), Vec<u32>> =
            HashMap::with_capacity(self.triangles.len() * 3 / 2);
        for (t, &[a, b, c]) in self.triangles.iter().enumerate() {
            for i in [a, b, c] {
                let f = &mut vertex_faces[i as usize];
                if f.last() != Some(&(t as u32)) {
                    f.push(t as u32);
                }
            }
            for (u, v) in [(a, b), (b, c), (c, a)] {
                if u == v {
                    continue;
                }
                edge_faces.entry(edge_key(u, v)).or_default().push(t as u32);
                vertex_neighbours[u as usize].push(v);
                vertex_neighbours[v as usize].push(u);
            }
        }
        for nb in &mut vertex_neighbours {
            nb.sort_unstable();
            nb.dedup();
        }
        Adjacency {
            vertex_faces,
            vertex_neighbours,
            edge_faces,
        }
    }

    /// Counts boundary, non-manifold and inconsistently oriented edges, degenerate triangles,
    /// unreferenced vertices and the Euler characteristic.
    pub fn topology(&self) -> Topology {
        let mut directed: HashMap<(u32, u32), (u32, u32)> =
            HashMap::with_capacity(self.triangles.len() * 3 / 2);
        let mut degenerate = 0;
        let mut used = vec![false; self.vertices.len()];
        for &[a, b, c] in &self.triangles {
            if a == b || b == c || c == a {
                degenerate += 1;
            }
            for i in [a, b, c] {
                used[i as usize] = true;
            }
            for (u, v) in [(a, b), (b, c), (c, a)] {
                if u == v {
                    continue;
                }
                let e = directed.entry(edge_key(u, v)).or_insert((0, 0));
                if u < v { e.0 += 1 } else { e.1 += 1 }
            }
        }
        let mut top = Topology {
            edges: directed.len(),
            boundary_edges: 0,
            non_manifold_edges: 0,
            inconsistent_edges: 0,
            degenerate_triangles: degenerate,
            unreferenced_vertices: used.iter().filter(|u| !**u).count(),
            euler_characteristic: 0,
        };
        for &(f, r) in directed.values() {
            match f + r {
                1 => top.boundary_edges += 1,
                2 => {
                    if f != 1 {
                        top.inconsistent_edges += 1
                    }
                }
                _ => top.non_manifold_edges += 1,
            }
        }
        let v = used.iter().filter(|u| **u).count() as i64;
        top.euler_characteristic = v - directed.len() as i64 + self.triangles.len() as i64;
        top
    }

    /// Every edge is shared by exactly two triangles.
    pub fn is_closed(&self) -> bool {
        self.topology().is_closed()
    }

    /// No edge is shared by more than two triangles.
    pub fn is_edge_manifold(&self) -> bool {
        self.topology().is_edge_manifold()
    }

    /// Neighbouring triangles traverse their shared edges in opposite directions.
    pub fn is_consistently_oriented(&self) -> bool {
        self.topology().is_consistently_oriented()
    }

    /// Applies a 4x4 homogeneous transform to every vertex. A transform with negative
    /// determinant (a reflection) also reverses the triangles so that they stay outward.
    pub fn transform(&mut self, m: &Matrix4<f64>) {
        for p in &mut self.vertices {
            *p = m.transform_point(p);
        }
        if m.fixed_view::<3, 3>(0, 0).determinant() < 0.0 {
            self.flip_orientation();
        }
    }

    /// Moves every vertex by `d`.
    pub fn translate(&mut self, d: &Vector3<f64>) {
        for p in &mut self.vertices {
            *p += d;
        }
    }

    /// Scales about `center` by per-axis factors `s` (reflections reverse the triangles).
    pub fn scale(&mut self, center: &Point3<f64>, s: &Vector3<f64>) {
        for p in &mut self.vertices {
            *p = center + (*p - center).component_mul(s);
        }
        if s.x * s.y * s.z < 0.0 {
            self.flip_orientation();
        }
    }

    /// Reverses every triangle.
    pub fn flip_orientation(&mut self) {
        for t in &mut self.triangles {
            t.swap(1, 2);
        }
    }

    /// Drops vertices no triangle uses and renumbers the triangles; returns the old-to-new
    /// index map (`u32::MAX` for dropped vertices).
    pub fn remove_unreferenced_vertices(&mut self) -> Vec<u32> {
        let mut map = vec![u32::MAX; self.vertices.len()];
        for t in &self.triangles {
            for &i in t {
                map[i as usize] = 0;
            }
        }
        let mut next = 0u32;
        let mut verts = Vec::with_capacity(self.vertices.len());
        for (i, m) in map.iter_mut().enumerate() {
            if *m == 0 {
                *m = next;
                next += 1;
                verts.push(self.vertices[i]);
            }
        }
        for t in &mut self.triangles {
            for i in t.iter_mut() {
                *i = map[*i as usize];
            }
        }
        self.vertices = verts;
        map
    }

    /// Appends `other`, offsetting its indices (the result holds both surfaces).
    pub fn append(&mut self, other: &TriMesh) {
        let off = self.vertices.len() as u32;
        self.vertices.extend_from_slice(&other.vertices);
        self.triangles.extend(
            other
                .triangles
                .iter()
                .map(|t| [t[0] + off, t[1] + off, t[2] + off]),
        );
    }

    /// Unit sphere centred at the origin made by `subdivisions` 1-to-4 splits of an
    /// icosahedron, vertices projected to the sphere: 10 * 4^s + 2 vertices (12, 42, 162, 642,
    /// 2562, ...), 20 * 4^s outward triangles.
    pub fn icosphere(subdivisions: u32) -> Result<TriMesh> {
        if subdivisions > MAX_ICOSPHERE_SUBDIVISIONS {
            return Err(Error::invalid(
                "subdivisions",
                subdivisions,
                format!("[0, {MAX_ICOSPHERE_SUBDIVISIONS}]"),
            ));
        }
        let p = (1.0 + 5f64.sqrt()) / 2.0;
        let raw = [
            [-1.0, p, 0.0],
            [1.0, p, 0.0],
            [-1.0, -p, 0.0],
            [1.0, -p, 0.0],
            [0.0, -1.0, p],
            [0.0, 1.0, p],
            [0.0, -1.0, -p],
            [0.0, 1.0, -p],
            [p, 0.0, -1.0],
            [p, 0.0, 1.0],
            [-p, 0.0, -1.0],
            [-p, 0.0, 1.0],
        ];
        let mut vertices: Vec<Point3<f64>> = raw
            .iter()
            .map(|r| Point3::from(Vector3::new(r[0], r[1], r[2]).normalize()))
            .collect();
        let mut triangles: Vec<[u32; 3]> = vec![
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
        for _ in 0..subdivisions {
            let mut mid: HashMap<(u32, u32), u32> = HashMap::with_capacity(triangles.len() * 3 / 2);
            let mut next = Vec::with_capacity(triangles.len() * 4);
            let mut midpoint = |a: u32, b: u32, vertices: &mut Vec<Point3<f64>>| -> u32 {
                *mid.entry(edge_key(a, b)).or_insert_with(|| {
                    let m = (vertices[a as usize].coords + vertices[b as usize].coords).normalize();
                    vertices.push(Point3::from(m));
                    (vertices.len() - 1) as u32
                })
            };
            for &[a, b, c] in &triangles {
                let ab = midpoint(a, b, &mut vertices);
                let bc = midpoint(b, c, &mut vertices);
                let ca = midpoint(c, a, &mut vertices);
                next.extend_from_slice(&[[a, ab, ca], [b, bc, ab], [c, ca, bc], [ab, bc, ca]]);
            }
            triangles = next;
        }
        Ok(TriMesh {
            vertices,
            triangles,
        })
    }

    /// Axis-aligned ellipsoid with semi-axes `r` centred at `c`, from an icosphere.
    pub fn ellipsoid(c: &Point3<f64>, r: &Vector3<f64>, subdivisions: u32) -> Result<TriMesh> {
        let mut m = TriMesh::icosphere(subdivisions)?;
        for p in &mut m.vertices {
            *p = c + p.coords.component_mul(r);
        }
        if r.x * r.y * r.z < 0.0 {
            m.flip_orientation();
        }
        Ok(m)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn icosphere_counts_and_closedness() {
        for (s, nv) in [(0, 12), (1, 42), (2, 162), (3, 642), (4, 2562)] {
            let m = TriMesh::icosphere(s).unwrap();
            assert_eq!(m.num_vertices(), nv);
            assert_eq!(m.num_triangles(), 20 * 4usize.pow(s));
            assert_eq!(m.edges().len(), 30 * 4usize.pow(s));
            let top = m.topology();
            assert!(top.is_closed() && top.is_consistently_oriented());
            assert_eq!(top.euler_characteristic, 2);
            assert!(m.volume() > 0.0);
        }
        assert!(TriMesh::icosphere(MAX_ICOSPHERE_SUBDIVISIONS + 1).is_err());
    }

    #[test]
    fn icosphere_converges_to_sphere() {
        let m = TriMesh::icosphere(5).unwrap();
        let v = 4.0 / 3.0 * std::f64::consts::PI;
        let a = 4.0 * std::f64::consts::PI;
        assert!((m.volume() - v).abs() / v < 2e-3, "{}", m.volume());
        assert!((m.area() - a).abs() / a < 2e-3, "{}", m.area());
        for (p, n) in m.vertices.iter().zip(m.vertex_normals()) {
            assert!((p.coords - n).norm() < 1e-2);
        }
        assert!(m.centroid().coords.norm() < 1e-12);
    }

    #[test]
    fn ellipsoid_volume_and_reflection() {
        let mut m =
            TriMesh::ellipsoid(&Point3::new(1.0, 2.0, 3.0), &Vector3::new(1.0, 2.0, 3.0), 3)
                .unwrap();
        let v0 = m.volume();
        m.scale(&Point3::origin(), &Vector3::new(-1.0, 1.0, 1.0));
        assert!((m.volume() - v0).abs() < 1e-9 * v0);
        assert!((m.centroid() - Point3::new(-1.0, 2.0, 3.0)).norm() < 1e-9);
    }
}
