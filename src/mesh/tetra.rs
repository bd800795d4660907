//! Tetrahedral volume meshes of a closed surface by isosurface stuffing (Labelle & Shewchuk
//! 2007, "Isosurface stuffing: fast tetrahedral meshes with good dihedral angles", uniform
//! variant): a body-centred cubic (BCC) lattice is laid over the surface, the signed distance
//! to the surface (BVH closest point, ray-parity sign) is sampled at its vertices, lattice
//! vertices too close to a cut point are warped onto it (warp parameters alpha_long = 0.24999,
//! alpha_short = 0.41189 of the paper), and every lattice tetrahedron is filled by the stencil
//! of its sign pattern. Output as [`TetMesh`] with a quality report, VTK UnstructuredGrid and
//! Gmsh 2.2 writers.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::path::Path;

use nalgebra::{Point3, Vector3};

use super::{Bvh, TriMesh};
use crate::{Error, Result};

/// Warp threshold on long (axis-parallel) lattice edges (Labelle & Shewchuk 2007, Table 1).
pub const ALPHA_LONG: f64 = 0.24999;
/// Warp threshold on short (diagonal) lattice edges (Labelle & Shewchuk 2007, Table 1).
pub const ALPHA_SHORT: f64 = 0.41189;

/// A tetrahedral mesh.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct TetMesh {
    /// Vertex positions.
    pub vertices: Vec<Point3<f64>>,
    /// Positively oriented tetrahedra ((b - a) x (c - a) . (d - a) > 0).
    pub tets: Vec<[u32; 4]>,
}

/// Quality figures of a [`TetMesh`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize)]
pub struct TetQuality {
    /// Number of tetrahedra.
    pub tets: usize,
    /// Number of vertices.
    pub vertices: usize,
    /// Smallest dihedral angle (degrees).
    pub min_dihedral_deg: f64,
    /// Largest dihedral angle (degrees).
    pub max_dihedral_deg: f64,
    /// Largest radius-edge ratio (circumradius / shortest edge; 0.612 for a regular tet).
    pub max_radius_edge: f64,
    /// Mean radius-edge ratio.
    pub mean_radius_edge: f64,
    /// Total volume.
    pub volume: f64,
}

/// Options of [`stuff`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StuffOptions {
    /// Lattice spacing h (edge length of the cubes), in mesh units.
    pub spacing: f64,
    /// Warp threshold on long edges.
    pub alpha_long: f64,
    /// Warp threshold on short edges.
    pub alpha_short: f64,
}

impl StuffOptions {
    /// Spacing chosen so that the bounding box's longest side spans `cells` cubes, with the
    /// paper's warp parameters.
    pub fn with_cells(surface: &TriMesh, cells: usize) -> StuffOptions {
        let ext = surface.bounding_box().extent();
        StuffOptions {
            spacing: ext.max() / cells.max(1) as f64,
            alpha_long: ALPHA_LONG,
            alpha_short: ALPHA_SHORT,
        }
    }
}

/// Largest lattice accepted by [`stuff`] (vertices), to fail clearly instead of exhausting
/// memory.
pub const MAX_LATTICE_VERTICES: usize = 40_000_000;

struct Lattice {
    origin: Point3<f64>,
    h: f64,
    n: [usize; 3],
}

impl Lattice {
    fn black_count(&self) -> usize {
        (self.n[0] + 1) * (self.n[1] + 1) * (self.n[2] + 1)
    }
    fn black(&self, i: usize, j: usize, k: usize) -> u32 {
        ((k * (self.n[1] + 1) + j) * (self.n[0] + 1) + i) as u32
    }
    fn red(&self, i: usize, j: usize, k: usize) -> u32 {
        (self.black_count() + (k * self.n[1] + j) * self.n[0] + i) as u32
    }
    fn count(&self) -> usize {
        self.black_count() + self.n[0] * self.n[1] * self.n[2]
    }
    fn position(&self, v: u32) -> Point3<f64> {
        let v = v as usize;
        let nb = self.black_count();
        if v < nb {
            let i = v % (self.n[0] + 1);
            let j = (v / (self.n[0] + 1)) % (self.n[1] + 1);
            let k = v / ((self.n[0] + 1) * (self.n[1] + 1));
            self.origin + Vector3::new(i as f64, j as f64, k as f64) * self.h
        } else {
            let r = v - nb;
            let i = r % self.n[0];
            let j = (r / self.n[0]) % self.n[1];
            let k = r / (self.n[0] * self.n[1]);
            self.origin + Vector3::new(i as f64 + 0.5, j as f64 + 0.5, k as f64 + 0.5) * self.h
        }
    }
    /// Every BCC tetrahedron as (red, red, black, black): two face-adjacent cube centres and
    /// an edge of their shared face.
    fn for_each_tet(&self, mut f: impl FnMut([u32; 4])) {
        let [nx, ny, nz] = self.n;
        for k in 0..nz {
            for j in 0..ny {
                for i in 0..nx {
                    let r0 = self.red(i, j, k);
                    for axis in 0..3 {
                        let (ni, nj, nk) = match axis {
                            0 => (i + 1, j, k),
                            1 => (i, j + 1, k),
                            _ => (i, j, k + 1),
                        };
                        if ni >= nx || nj >= ny || nk >= nz {
                            continue;
                        }
                        let r1 = self.red(ni, nj, nk);
                        // corners of the shared face, in cyclic order
                        let c = match axis {
                            0 => [
                                (ni, j, k),
                                (ni, j + 1, k),
                                (ni, j + 1, k + 1),
                                (ni, j, k + 1),
                            ],
                            1 => [
                                (i, nj, k),
                                (i + 1, nj, k),
                                (i + 1, nj, k + 1),
                                (i, nj, k + 1),
                            ],
                            _ => [
                                (i, j, nk),
                                (i + 1, j, nk),
                                (i + 1, j + 1, nk),
                                (i, j + 1, nk),
                            ],
                        };
                        let b = c.map(|(a, b, c)| self.black(a, b, c));
                        for e in 0..4 {
                            f([r0, r1, b[e], b[(e + 1) % 4]]);
                        }
                    }
                }
            }
        }
    }
}

/// Fills the closed surface with tetrahedra by isosurface stuffing.
pub fn stuff(surface: &TriMesh, opts: &StuffOptions) -> Result<TetMesh> {
    surface.validate()?;
    let h = opts.spacing;
    if !(h.is_finite() && h > 0.0) {
        return Err(Error::invalid("spacing", h, "(0, inf)"));
    }
    for (name, a) in [
        ("alpha_long", opts.alpha_long),
        ("alpha_short", opts.alpha_short),
    ] {
        if !(0.0..0.5).contains(&a) {
            return Err(Error::invalid(name, a, "[0, 0.5)"));
        }
    }
    let top = surface.topology();
    if !top.is_closed() || surface.triangles.is_empty() {
        return Err(Error::invalid(
            "surface",
            format!(
                "{} boundary and {} non-manifold edges",
                top.boundary_edges, top.non_manifold_edges
            ),
            "a closed surface",
        ));
    }
    let bb = surface.bounding_box();
    let origin = bb.min - Vector3::repeat(1.5 * h);
    let ext = bb.extent() + Vector3::repeat(3.0 * h);
    let n = [0, 1, 2].map(|a| ((ext[a] / h).ceil() as usize).max(1));
    let lat = Lattice { origin, h, n };
    let total = (n[0] + 1) as f64 * (n[1] + 1) as f64 * (n[2] + 1) as f64 * 2.0;
    if total > MAX_LATTICE_VERTICES as f64 {
        return Err(Error::invalid(
            "spacing",
            h,
            format!(
                "a spacing giving at most {MAX_LATTICE_VERTICES} lattice vertices (this one gives {total:.0})"
            ),
        ));
    }
    let bvh = Bvh::new(surface);
    let mut pos: Vec<Point3<f64>> = (0..lat.count() as u32).map(|v| lat.position(v)).collect();
    let mut f: Vec<f64> = pos.iter().map(|p| bvh.signed_distance(p)).collect();
    // sign-changing edges and their cut points, t measured from the smaller index
    let black_count = lat.black_count() as u32;
    let is_long = |a: u32, b: u32| (a < black_count) == (b < black_count);
    let mut cuts: HashMap<(u32, u32), f64> = HashMap::new();
    lat.for_each_tet(|t| {
        if t.iter().any(|&v| f[v as usize] < 0.0) && t.iter().any(|&v| f[v as usize] > 0.0) {
            for (a, b) in tet_edges(&t) {
                let (a, b) = if a < b { (a, b) } else { (b, a) };
                if (f[a as usize] < 0.0) != (f[b as usize] < 0.0)
                    && f[a as usize] != 0.0
                    && f[b as usize] != 0.0
                {
                    cuts.entry((a, b)).or_insert(f64::NAN);
                }
            }
        }
    });
    for (&(a, b), t) in cuts.iter_mut() {
        *t = cut_parameter(
            &bvh,
            &pos[a as usize],
            &pos[b as usize],
            f[a as usize],
            f[b as usize],
        );
    }
    // warping: a vertex with a violating cut point moves onto the nearest one and becomes zero
    let mut incident: Vec<(u32, u32, f64, f64)> = Vec::with_capacity(cuts.len() * 2);
    for (&(a, b), &t) in &cuts {
        let alpha = if is_long(a, b) {
            opts.alpha_long
        } else {
            opts.alpha_short
        };
        if t < alpha {
            incident.push((a, b, t, t));
        }
        if 1.0 - t < alpha {
            incident.push((b, a, t, 1.0 - t));
        }
    }
    incident.sort_by(|x, y| x.0.cmp(&y.0).then(x.3.total_cmp(&y.3)));
    let mut warped = vec![false; pos.len()];
    for &(v, other, t, _) in &incident {
        if warped[v as usize] || warped[other as usize] || f[v as usize] == 0.0 {
            continue;
        }
        let (a, b) = if v < other { (v, other) } else { (other, v) };
        let p = pos[a as usize] + (pos[b as usize] - pos[a as usize]) * t;
        pos[v as usize] = p;
        f[v as usize] = 0.0;
        warped[v as usize] = true;
    }
    // stencils
    let mut out = Builder {
        map: HashMap::new(),
        vertices: Vec::new(),
        tets: Vec::new(),
        cuts: &cuts,
    };
    lat.for_each_tet(|t| {
        let s = t.map(|v| sign(f[v as usize]));
        let neg = s.iter().filter(|x| **x < 0).count();
        let posn = s.iter().filter(|x| **x > 0).count();
        if neg == 0 && posn > 0 {
            return;
        }
        if neg == 0 {
            // all four on the surface: keep when the centre is inside
            let c = Point3::from(
                t.iter()
                    .map(|&v| pos[v as usize].coords)
                    .sum::<Vector3<f64>>()
                    / 4.0,
            );
            if !bvh.contains(&c) {
                return;
            }
        }
        out.stencil(&t, &s, &pos, &f);
    });
    let mut mesh = TetMesh {
        vertices: out.vertices,
        tets: Vec::with_capacity(out.tets.len()),
    };
    for mut t in out.tets {
        let v = signed_volume(&mesh.vertices, &t);
        if v < 0.0 {
            t.swap(2, 3);
        }
        if v.abs() > 1e-12 * h * h * h {
            mesh.tets.push(t);
        }
    }
    Ok(mesh)
}

fn sign(x: f64) -> i8 {
    if x < 0.0 {
        -1
    } else if x > 0.0 {
        1
    } else {
        0
    }
}

fn tet_edges(t: &[u32; 4]) -> [(u32, u32); 6] {
    [
        (t[0], t[1]),
        (t[0], t[2]),
        (t[0], t[3]),
        (t[1], t[2]),
        (t[1], t[3]),
        (t[2], t[3]),
    ]
}

/// Zero of the signed distance on segment a-b: linear interpolation refined by two secant
/// steps on the true distance. Returns t in (0, 1) measured from a.
fn cut_parameter(bvh: &Bvh, a: &Point3<f64>, b: &Point3<f64>, fa: f64, fb: f64) -> f64 {
    let (mut t0, mut f0, mut t1, mut f1) = (0.0, fa, 1.0, fb);
    let mut t = f0 / (f0 - f1);
    for _ in 0..2 {
        let ft = bvh.signed_distance(&(a + (b - a) * t));
        if ft == 0.0 {
            break;
        }
        if (ft < 0.0) == (f0 < 0.0) {
            t0 = t;
            f0 = ft;
        } else {
            t1 = t;
            f1 = ft;
        }
        t = t0 + (t1 - t0) * f0 / (f0 - f1);
    }
    t.clamp(1e-6, 1.0 - 1e-6)
}

fn signed_volume(v: &[Point3<f64>], t: &[u32; 4]) -> f64 {
    let [a, b, c, d] = t.map(|i| v[i as usize]);
    (b - a).cross(&(c - a)).dot(&(d - a)) / 6.0
}

/// A vertex of the output: a lattice vertex or a cut point on a lattice edge.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
enum Key {
    Lattice(u32),
    Cut(u32, u32),
}

struct Builder<'a> {
    cuts: &'a HashMap<(u32, u32), f64>,
    map: HashMap<Key, u32>,
    vertices: Vec<Point3<f64>>,
    tets: Vec<[u32; 4]>,
}

impl Builder<'_> {
    fn vertex(&mut self, key: Key, pos: &[Point3<f64>], f: &[f64]) -> u32 {
        if let Some(&i) = self.map.get(&key) {
            return i;
        }
        let p = match key {
            Key::Lattice(v) => pos[v as usize],
            Key::Cut(a, b) => {
                let t = self.cuts.get(&(a, b)).copied().unwrap_or_else(|| {
                    let (fa, fb) = (f[a as usize], f[b as usize]);
                    fa / (fa - fb)
                });
                pos[a as usize] + (pos[b as usize] - pos[a as usize]) * t
            }
        };
        self.vertices.push(p);
        let i = (self.vertices.len() - 1) as u32;
        self.map.insert(key, i);
        i
    }

    fn cut(a: u32, b: u32) -> Key {
        if a < b {
            Key::Cut(a, b)
        } else {
            Key::Cut(b, a)
        }
    }

    fn stencil(&mut self, t: &[u32; 4], s: &[i8; 4], pos: &[Point3<f64>], f: &[f64]) {
        let idx = |c: i8| -> Vec<u32> { (0..4).filter(|&k| s[k] == c).map(|k| t[k]).collect() };
        let (neg, zero, plus) = (idx(-1), idx(0), idx(1));
        let l = Key::Lattice;
        let emit = |b: &mut Builder, keys: &[Key]| {
            let v: Vec<u32> = keys.iter().map(|k| b.vertex(*k, pos, f)).collect();
            b.tets.push([v[0], v[1], v[2], v[3]]);
        };
        match (neg.len(), zero.len(), plus.len()) {
            (_, _, 0) => emit(self, &t.map(l)),
            (1, z, p) => {
                let mut keys = vec![l(neg[0])];
                keys.extend(zero.iter().map(|&v| l(v)));
                keys.extend(plus.iter().map(|&q| Builder::cut(neg[0], q)));
                debug_assert_eq!(1 + z + p, 4);
                emit(self, &keys);
            }
            (2, 1, 1) => {
                // pyramid: base (a, b, cut bp, cut ap), apex the zero vertex
                let (a, b, p) = (neg[0], neg[1], plus[0]);
                let quad = [l(a), l(b), Builder::cut(b, p), Builder::cut(a, p)];
                self.pyramid(quad, l(zero[0]), pos, f);
            }
            (2, 0, 2) => {
                let (a, b, p, q) = (neg[0], neg[1], plus[0], plus[1]);
                let prism = [
                    l(a),
                    Builder::cut(a, p),
                    Builder::cut(a, q),
                    l(b),
                    Builder::cut(b, p),
                    Builder::cut(b, q),
                ];
                self.prism(prism, pos, f);
            }
            (3, 0, 1) => {
                let p = plus[0];
                let prism = [
                    l(neg[0]),
                    l(neg[1]),
                    l(neg[2]),
                    Builder::cut(neg[0], p),
                    Builder::cut(neg[1], p),
                    Builder::cut(neg[2], p),
                ];
                self.prism(prism, pos, f);
            }
            _ => {}
        }
    }

    /// Splits a pyramid along the quad diagonal through its smallest key, so that the
    /// neighbour sharing the quad splits it the same way.
    fn pyramid(&mut self, q: [Key; 4], apex: Key, pos: &[Point3<f64>], f: &[f64]) {
        let m = (0..4).min_by_key(|&k| q[k]).unwrap_or(0);
        let (a, b, c, d) = (q[m], q[(m + 1) % 4], q[(m + 2) % 4], q[(m + 3) % 4]);
        for keys in [[a, b, c, apex], [a, c, d, apex]] {
            let v = keys.map(|k| self.vertex(k, pos, f));
            self.tets.push(v);
        }
    }

    /// Splits a prism (v0 v1 v2 / v3 v4 v5, v_i joined to v_i+3) into three tetrahedra whose
    /// quad diagonals all start at their quad's smallest key (Dompierre et al. 1999), so that
    /// neighbours agree.
    fn prism(&mut self, v: [Key; 6], pos: &[Point3<f64>], f: &[f64]) {
        // rotate/reflect so that the smallest key is v0
        const MAPS: [[usize; 6]; 6] = [
            [0, 1, 2, 3, 4, 5],
            [1, 2, 0, 4, 5, 3],
            [2, 0, 1, 5, 3, 4],
            [3, 5, 4, 0, 2, 1],
            [4, 3, 5, 1, 0, 2],
            [5, 4, 3, 2, 1, 0],
        ];
        let m = (0..6).min_by_key(|&k| v[k]).unwrap_or(0);
        let w = MAPS[m].map(|k| v[k]);
        let tets = if w[1].min(w[5]) < w[2].min(w[4]) {
            [
                [w[0], w[1], w[2], w[5]],
                [w[0], w[1], w[5], w[4]],
                [w[0], w[4], w[5], w[3]],
            ]
        } else {
            [
                [w[0], w[1], w[2], w[4]],
                [w[0], w[4], w[2], w[5]],
                [w[0], w[4], w[5], w[3]],
            ]
        };
        for keys in tets {
            let ids = keys.map(|k| self.vertex(k, pos, f));
            self.tets.push(ids);
        }
    }
}

impl TetMesh {
    /// Total volume.
    pub fn volume(&self) -> f64 {
        self.tets
            .iter()
            .map(|t| signed_volume(&self.vertices, t))
            .sum()
    }

    /// The boundary: faces that belong to one tetrahedron only, oriented outward.
    pub fn boundary(&self) -> TriMesh {
        let mut count: HashMap<[u32; 3], ([u32; 3], u32)> = HashMap::new();
        for t in &self.tets {
            for f in [
                [t[1], t[2], t[3]],
                [t[0], t[3], t[2]],
                [t[0], t[1], t[3]],
                [t[0], t[2], t[1]],
            ] {
                let mut k = f;
                k.sort_unstable();
                count.entry(k).or_insert((f, 0)).1 += 1;
            }
        }
        let mut tris: Vec<[u32; 3]> = count
            .into_values()
            .filter(|(_, n)| *n == 1)
            .map(|(f, _)| f)
            .collect();
        tris.sort_unstable();
        let mut m = TriMesh {
            vertices: self.vertices.clone(),
            triangles: tris,
        };
        m.remove_unreferenced_vertices();
        m
    }

    /// Dihedral angles and radius-edge ratios over all tetrahedra.
    pub fn quality(&self) -> TetQuality {
        let mut q = TetQuality {
            tets: self.tets.len(),
            vertices: self.vertices.len(),
            min_dihedral_deg: f64::INFINITY,
            max_dihedral_deg: 0.0,
            max_radius_edge: 0.0,
            mean_radius_edge: 0.0,
            volume: self.volume(),
        };
        for t in &self.tets {
            let p = t.map(|i| self.vertices[i as usize]);
            for (lo, hi) in dihedral_angles(&p).into_iter().map(|a| (a, a)) {
                q.min_dihedral_deg = q.min_dihedral_deg.min(lo);
                q.max_dihedral_deg = q.max_dihedral_deg.max(hi);
            }
            let re = radius_edge(&p);
            q.max_radius_edge = q.max_radius_edge.max(re);
            q.mean_radius_edge += re;
        }
        if !self.tets.is_empty() {
            q.mean_radius_edge /= self.tets.len() as f64;
        } else {
            q.min_dihedral_deg = 0.0;
        }
        q
    }

    /// Legacy ASCII VTK UnstructuredGrid text (cell type 10, tetra).
    pub fn to_vtk(&self) -> String {
        let mut s = format!(
            "# vtk DataFile Version 3.0\nbreathing-torso volume mesh\nASCII\nDATASET UNSTRUCTURED_GRID\nPOINTS {} double\n",
            self.vertices.len()
        );
        for p in &self.vertices {
            let _ = writeln!(s, "{} {} {}", p.x, p.y, p.z);
        }
        let _ = writeln!(s, "CELLS {} {}", self.tets.len(), 5 * self.tets.len());
        for t in &self.tets {
            let _ = writeln!(s, "4 {} {} {} {}", t[0], t[1], t[2], t[3]);
        }
        let _ = writeln!(s, "CELL_TYPES {}", self.tets.len());
        for _ in &self.tets {
            s.push_str("10\n");
        }
        s
    }

    /// Gmsh MSH 2.2 ASCII text (element type 4, physical and elementary tag 1).
    pub fn to_msh(&self) -> String {
        let mut s = String::from("$MeshFormat\n2.2 0 8\n$EndMeshFormat\n");
        let _ = writeln!(s, "$Nodes\n{}", self.vertices.len());
        for (i, p) in self.vertices.iter().enumerate() {
            let _ = writeln!(s, "{} {} {} {}", i + 1, p.x, p.y, p.z);
        }
        let _ = writeln!(s, "$EndNodes\n$Elements\n{}", self.tets.len());
        for (i, t) in self.tets.iter().enumerate() {
            let _ = writeln!(
                s,
                "{} 4 2 1 1 {} {} {} {}",
                i + 1,
                t[0] + 1,
                t[1] + 1,
                t[2] + 1,
                t[3] + 1
            );
        }
        s.push_str("$EndElements\n");
        s
    }

    /// Writes the mesh as VTK (`.vtk`) or Gmsh (`.msh`), by extension.
    pub fn write(&self, path: impl AsRef<Path>) -> Result<()> {
        let path = path.as_ref();
        let ext = path
            .extension()
            .and_then(|e| e.to_str())
            .unwrap_or("")
            .to_ascii_lowercase();
        let text = match ext.as_str() {
            "vtk" => self.to_vtk(),
            "msh" => self.to_msh(),
            _ => {
                return Err(Error::invalid(
                    format!("extension of {}", path.display()),
                    format!("{ext:?}"),
                    "vtk or msh",
                ));
            }
        };
        std::fs::write(path, text).map_err(|e| Error::io(path, e))
    }
}

/// The six interior dihedral angles of a tetrahedron (degrees).
pub fn dihedral_angles(p: &[Point3<f64>; 4]) -> [f64; 6] {
    // face normals (outward-agnostic): the face opposite vertex k
    let n = |a: usize, b: usize, c: usize| (p[b] - p[a]).cross(&(p[c] - p[a]));
    let faces = [n(1, 2, 3), n(0, 2, 3), n(0, 1, 3), n(0, 1, 2)];
    let centroid = Point3::from((p[0].coords + p[1].coords + p[2].coords + p[3].coords) / 4.0);
    let out: Vec<Vector3<f64>> = (0..4)
        .map(|k| {
            let a = (k + 1) % 4;
            let v = faces[k];
            if v.dot(&(p[a] - centroid)) < 0.0 {
                -v
            } else {
                v
            }
        })
        .collect();
    let mut ang = [0.0; 6];
    let mut m = 0;
    for i in 0..4 {
        for j in i + 1..4 {
            let c = out[i].dot(&out[j]) / (out[i].norm() * out[j].norm()).max(1e-300);
            ang[m] = 180.0 - c.clamp(-1.0, 1.0).acos().to_degrees();
            m += 1;
        }
    }
    ang
}

/// Circumradius divided by the shortest edge.
pub fn radius_edge(p: &[Point3<f64>; 4]) -> f64 {
    let (a, b, c) = (p[1] - p[0], p[2] - p[0], p[3] - p[0]);
    let det = 2.0 * a.dot(&b.cross(&c));
    let num = b.cross(&c) * a.norm_squared()
        + c.cross(&a) * b.norm_squared()
        + a.cross(&b) * c.norm_squared();
    let r = if det.abs() > 1e-300 {
        num.norm() / det.abs()
    } else {
        f64::INFINITY
    };
    let mut lmin = f64::INFINITY;
    for i in 0..4 {
        for j in i + 1..4 {
            lmin = lmin.min((p[i] - p[j]).norm());
        }
    }
    r / lmin
}
