//! Attachments defined by geometry (Peeters & Pronost 2013, section 3.8) and the generation
//! of missing attachments by extrusion (section 3.4, the tendon generator). An attachment
//! area is stored as a set of points with a radius, or as a convex hull, never as vertex
//! indices, so that the vertices it covers can be found again after any re-meshing.

use std::collections::{HashMap, HashSet};

use nalgebra::{Point3, Vector3};

use super::{Taubin, TriMesh};
use crate::{Error, Result};

/// The geometric area of an attachment.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum Region {
    /// Union of balls of one radius around points.
    Balls {
        /// Ball centres.
        points: Vec<Point3<f64>>,
        /// Common radius (> 0).
        radius: f64,
    },
    /// Convex hull, as outward half-spaces n . x <= d, grown by a tolerance.
    Hull {
        /// Outward unit normals and offsets of the hull's faces.
        planes: Vec<(Vector3<f64>, f64)>,
        /// Distance outside the hull still counted as inside.
        tolerance: f64,
    },
}

/// A named attachment area.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct Attachment {
    /// Name (e.g. the muscle and bone it joins).
    pub name: String,
    /// The area.
    pub region: Region,
}

impl Attachment {
    /// An attachment covering `points` with balls of `radius`.
    pub fn from_points(
        name: impl Into<String>,
        points: Vec<Point3<f64>>,
        radius: f64,
    ) -> Result<Attachment> {
        if !(radius.is_finite() && radius > 0.0) {
            return Err(Error::invalid("radius", radius, "(0, inf)"));
        }
        if points.is_empty() {
            return Err(Error::invalid("points", 0, "at least 1 point"));
        }
        Ok(Attachment {
            name: name.into(),
            region: Region::Balls { points, radius },
        })
    }

    /// The convex hull of `points`, grown by `tolerance`. A flat or thin set (a patch of
    /// surface) is thickened by `tolerance` on both sides of its best-fit plane before the
    /// hull is taken, so the hull has volume.
    pub fn hull(
        name: impl Into<String>,
        points: &[Point3<f64>],
        tolerance: f64,
    ) -> Result<Attachment> {
        if !(tolerance.is_finite() && tolerance > 0.0) {
            return Err(Error::invalid("tolerance", tolerance, "(0, inf)"));
        }
        if points.len() < 3 {
            return Err(Error::invalid("points", points.len(), "at least 3 points"));
        }
        let n = best_fit_normal(points);
        let mut pts = Vec::with_capacity(points.len() * 2);
        for p in points {
            pts.push(p + n * tolerance);
            pts.push(p - n * tolerance);
        }
        let planes = convex_hull_planes(&pts).ok_or_else(|| {
            Error::invalid(
                "points",
                format!("{} points", points.len()),
                "points spanning an area",
            )
        })?;
        Ok(Attachment {
            name: name.into(),
            region: Region::Hull { planes, tolerance },
        })
    }

    /// Converts an index-based attachment (vertex indices into `mesh`, as a segmentation
    /// delivers them) to geometry: balls around the vertices with a radius of 0.6 times the
    /// mean length of the edges at them, which covers the triangles between the vertices
    /// (a triangle's centroid lies 1/sqrt(3) of an edge from its corners) without reaching
    /// the neighbouring vertices.
    pub fn from_vertices(
        name: impl Into<String>,
        mesh: &TriMesh,
        indices: &[u32],
    ) -> Result<Attachment> {
        if let Some(&i) = indices.iter().find(|&&i| i as usize >= mesh.vertices.len()) {
            return Err(Error::invalid(
                "attachment vertex index",
                i,
                format!("[0, {})", mesh.vertices.len()),
            ));
        }
        mesh.validate()?;
        let adj = mesh.adjacency();
        let (mut sum, mut count) = (0.0, 0usize);
        for &i in indices {
            for &j in &adj.vertex_neighbours[i as usize] {
                sum += (mesh.vertices[i as usize] - mesh.vertices[j as usize]).norm();
                count += 1;
            }
        }
        let radius = if count > 0 && sum > 0.0 {
            0.6 * sum / count as f64
        } else {
            1e-9
        };
        let points = indices.iter().map(|&i| mesh.vertices[i as usize]).collect();
        Attachment::from_points(name, points, radius)
    }

    /// Whether `p` lies in the area.
    pub fn contains(&self, p: &Point3<f64>) -> bool {
        match &self.region {
            Region::Balls { points, radius } => points
                .iter()
                .any(|c| (c - p).norm_squared() <= radius * radius),
            Region::Hull { planes, tolerance } => planes
                .iter()
                .all(|(n, d)| n.dot(&p.coords) - d <= *tolerance),
        }
    }

    /// The vertices of `mesh` inside the area, in increasing order; this is how muscle
    /// insertions are re-derived on a re-meshed surface.
    pub fn find_vertices(&self, mesh: &TriMesh) -> Vec<u32> {
        (0..mesh.vertices.len() as u32)
            .filter(|&i| self.contains(&mesh.vertices[i as usize]))
            .collect()
    }
}

/// Writes attachments as a JSON array (the `attachments.json` of a prepared directory).
pub fn save(path: impl AsRef<std::path::Path>, attachments: &[Attachment]) -> Result<()> {
    let path = path.as_ref();
    let json = serde_json::to_string_pretty(attachments)
        .map_err(|e| Error::State(format!("attachments: {e}")))?;
    std::fs::write(path, json).map_err(|e| Error::io(path, e))
}

/// Reads attachments written by [`save`]; malformed JSON is reported with its line and
/// column.
pub fn load(path: impl AsRef<std::path::Path>) -> Result<Vec<Attachment>> {
    let path = path.as_ref();
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let list: Vec<Attachment> = serde_json::from_str(&text).map_err(|e| Error::Parse {
        path: path.display().to_string(),
        line: e.line(),
        column: e.column(),
        message: e.to_string(),
    })?;
    for a in &list {
        let ok = match &a.region {
            Region::Balls { points, radius } => {
                radius.is_finite()
                    && *radius > 0.0
                    && points
                        .iter()
                        .all(|p| p.coords.iter().all(|c| c.is_finite()))
            }
            Region::Hull { planes, tolerance } => {
                tolerance.is_finite()
                    && planes
                        .iter()
                        .all(|(n, d)| d.is_finite() && n.iter().all(|c| c.is_finite()))
            }
        };
        if !ok {
            return Err(Error::invalid(
                format!("attachment {:?} in {}", a.name, path.display()),
                "non-finite or non-positive size",
                "finite points, planes and a positive radius",
            ));
        }
    }
    Ok(list)
}

fn best_fit_normal(points: &[Point3<f64>]) -> Vector3<f64> {
    let c = points.iter().map(|p| p.coords).sum::<Vector3<f64>>() / points.len() as f64;
    let mut m = nalgebra::Matrix3::zeros();
    for p in points {
        let d = p.coords - c;
        m += d * d.transpose();
    }
    let e = m.symmetric_eigen();
    let k = e.eigenvalues.imin();
    e.eigenvectors.column(k).into_owned()
}

/// Outward planes of the 3-D convex hull of `points` by incremental construction (each new
/// point removes the faces it sees and is joined to their horizon). None when the points
/// are (nearly) coplanar.
/// Points are first displaced by a deterministic pseudo-random amount of 1e-7 of their extent,
/// so that coplanar subsets (rings of a generated mesh) cannot hide a point outside a face
/// lying in their plane; the hull is that much larger or smaller than the exact one.
pub fn convex_hull_planes(points: &[Point3<f64>]) -> Option<Vec<(Vector3<f64>, f64)>> {
    let mut bb = super::Aabb::empty();
    for p in points {
        bb.grow(p);
    }
    let jitter = 1e-7 * bb.diagonal();
    let mut state = 0x2545F4914F6CDD1Du64;
    let mut unit = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        (state >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    let pts: Vec<Point3<f64>> = points
        .iter()
        .map(|p| p + Vector3::new(unit(), unit(), unit()) * jitter)
        .collect();
    let scale = pts
        .iter()
        .map(|p| p.coords.amax())
        .fold(0.0, f64::max)
        .max(1e-300);
    let eps = 1e-12 * scale;
    // initial tetrahedron: extreme points
    let i0 = 0;
    let i1 = (0..pts.len()).max_by(|&a, &b| {
        (pts[a] - pts[i0])
            .norm()
            .total_cmp(&(pts[b] - pts[i0]).norm())
    })?;
    let line = pts[i1] - pts[i0];
    let i2 = (0..pts.len()).max_by(|&a, &b| {
        line.cross(&(pts[a] - pts[i0]))
            .norm()
            .total_cmp(&line.cross(&(pts[b] - pts[i0])).norm())
    })?;
    let nrm = line.cross(&(pts[i2] - pts[i0]));
    if nrm.norm() <= eps * scale {
        return None;
    }
    let i3 = (0..pts.len()).max_by(|&a, &b| {
        nrm.dot(&(pts[a] - pts[i0]))
            .abs()
            .total_cmp(&nrm.dot(&(pts[b] - pts[i0])).abs())
    })?;
    let vol = nrm.dot(&(pts[i3] - pts[i0]));
    if vol.abs() <= eps * nrm.norm() {
        return None;
    }
    let mut faces: Vec<[usize; 3]> = if vol < 0.0 {
        vec![[i0, i1, i2], [i0, i3, i1], [i1, i3, i2], [i2, i3, i0]]
    } else {
        vec![[i0, i2, i1], [i0, i1, i3], [i1, i2, i3], [i2, i0, i3]]
    };
    let plane = |f: &[usize; 3]| {
        let n = (pts[f[1]] - pts[f[0]]).cross(&(pts[f[2]] - pts[f[0]]));
        (n, n.dot(&pts[f[0]].coords))
    };
    for (i, p) in pts.iter().enumerate() {
        if [i0, i1, i2, i3].contains(&i) {
            continue;
        }
        let visible: Vec<bool> = faces
            .iter()
            .map(|f| {
                let (n, d) = plane(f);
                n.dot(&p.coords) - d > eps * n.norm()
            })
            .collect();
        if !visible.iter().any(|v| *v) {
            continue;
        }
        let mut edges: HashSet<(usize, usize)> = HashSet::new();
        for (f, _) in faces.iter().zip(&visible).filter(|x| *x.1) {
            for k in 0..3 {
                edges.insert((f[k], f[(k + 1) % 3]));
            }
        }
        let horizon: Vec<(usize, usize)> = edges
            .iter()
            .copied()
            .filter(|&(a, b)| !edges.contains(&(b, a)))
            .collect();
        let mut next: Vec<[usize; 3]> = faces
            .iter()
            .zip(&visible)
            .filter(|x| !*x.1)
            .map(|x| *x.0)
            .collect();
        for (a, b) in horizon {
            next.push([a, b, i]);
        }
        faces = next;
    }
    Some(
        faces
            .iter()
            .filter_map(|f| {
                let (n, _) = plane(f);
                let u = n.try_normalize(0.0)?;
                Some((u, u.dot(&pts[f[0]].coords)))
            })
            .collect(),
    )
}

/// What [`extrude_to_target`] produced.
#[derive(Debug, Clone, PartialEq, serde::Serialize)]
pub struct Extrusion {
    /// Triangles of the bottom part that were moved (F_bottom).
    pub bottom_faces: usize,
    /// Distance the bottom part was moved along the direction.
    pub distance: f64,
    /// Rings of vertices filling the gap.
    pub rings: usize,
    /// Vertices created.
    pub new_vertices: Vec<u32>,
    /// The generated part as an attachment (convex hull of the moved and new vertices), as
    /// the paper saves generated tendons.
    pub attachment: Option<Attachment>,
}

/// Extends a closed surface that stops short of the structure it must reach (Peeters &
/// Pronost 2013, section 3.4). With `dir` the unit direction towards the target, the bottom
/// part F_bottom grows from the faces at the vertex furthest along `dir` over neighbours
/// whose normal lies within `theta_deg` of `dir`; it is moved along `dir` so that its
/// extreme vertex reaches the nearest target point's level, the border of F_bottom is
/// duplicated at its old place, the gap is filled with regularly spaced rings of vertices
/// (one per mean edge length), and F_tendon = F_bottom plus the gap faces is smoothed
/// locally (Taubin, N = 10). Nothing is done when the surface already reaches the target.
pub fn extrude_to_target(
    mesh: &mut TriMesh,
    dir: &Vector3<f64>,
    target: &[Point3<f64>],
    theta_deg: f64,
) -> Result<Extrusion> {
    mesh.validate()?;
    let d = dir
        .try_normalize(1e-300)
        .ok_or_else(|| Error::invalid("direction", format!("{dir:?}"), "non-zero"))?;
    if target.is_empty() {
        return Err(Error::invalid("target points", 0, "at least 1 point"));
    }
    if !(0.0..=90.0).contains(&theta_deg) {
        return Err(Error::invalid("theta_deg", theta_deg, "[0, 90]"));
    }
    let s = |p: &Point3<f64>| p.coords.dot(&d);
    let (vmin, smax) = mesh
        .vertices
        .iter()
        .enumerate()
        .map(|(i, p)| (i as u32, s(p)))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .ok_or_else(|| Error::invalid("mesh", "no vertex", "a non-empty surface"))?;
    let starget = target.iter().map(s).fold(f64::INFINITY, f64::min);
    let gap = starget - smax;
    let none = Extrusion {
        bottom_faces: 0,
        distance: 0.0,
        rings: 0,
        new_vertices: vec![],
        attachment: None,
    };
    if gap <= 0.0 {
        return Ok(none);
    }
    let adj = mesh.adjacency();
    // F_bottom: flood from the faces at v_min over faces facing within theta of dir
    let cos_t = theta_deg.to_radians().cos();
    let facing = |t: usize| mesh.face_normal(t).dot(&d) >= cos_t;
    let mut bottom = vec![false; mesh.triangles.len()];
    let mut stack: Vec<usize> = adj.vertex_faces[vmin as usize]
        .iter()
        .map(|&t| t as usize)
        .collect();
    for &t in &stack {
        bottom[t] = true;
    }
    while let Some(t) = stack.pop() {
        for g in adj.face_neighbours(mesh, t) {
            let g = g as usize;
            if !bottom[g] && facing(g) {
                bottom[g] = true;
                stack.push(g);
            }
        }
    }
    // border edges of F_bottom, in the direction F_bottom traverses them
    let mut border: Vec<(u32, u32)> = Vec::new();
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if !bottom[t] {
            continue;
        }
        for k in 0..3 {
            let (u, w) = (tri[k], tri[(k + 1) % 3]);
            if adj
                .faces_of_edge(u, w)
                .iter()
                .filter(|&&f| bottom[f as usize])
                .count()
                == 1
            {
                border.push((u, w));
            }
        }
    }
    if border.is_empty() {
        return Err(Error::invalid(
            "theta_deg",
            theta_deg,
            "a value whose bottom part does not cover the whole surface",
        ));
    }
    let edge = mesh.mean_edge_length();
    let rings = if edge > 0.0 {
        ((gap / edge).round() as usize).saturating_sub(1).min(200)
    } else {
        0
    };
    let border_vertices: Vec<u32> = {
        let mut v: Vec<u32> = border.iter().flat_map(|&(a, b)| [a, b]).collect();
        v.sort_unstable();
        v.dedup();
        v
    };
    let first_new = mesh.vertices.len() as u32;
    // columns: level 0 = copy at the old place (joined to the rest), 1..=rings inner, rings+1 = moved
    let mut column: HashMap<u32, Vec<u32>> = HashMap::new();
    for &v in &border_vertices {
        let p = mesh.vertices[v as usize];
        let mut col = Vec::with_capacity(rings + 2);
        for k in 0..=rings {
            mesh.vertices
                .push(p + d * (gap * k as f64 / (rings + 1) as f64));
            col.push((mesh.vertices.len() - 1) as u32);
        }
        col.push(v);
        column.insert(v, col);
    }
    for (t, tri) in mesh.triangles.iter_mut().enumerate() {
        if !bottom[t] {
            for v in tri.iter_mut() {
                if let Some(col) = column.get(v) {
                    *v = col[0];
                }
            }
        }
    }
    let mut moved = vec![false; mesh.vertices.len()];
    for (t, tri) in mesh.triangles.iter().enumerate() {
        if bottom[t] {
            for &v in tri {
                moved[v as usize] = true;
            }
        }
    }
    for (i, m) in moved.iter().enumerate() {
        if *m {
            mesh.vertices[i] += d * gap;
        }
    }
    for &(u, w) in &border {
        let (cu, cw) = (&column[&u], &column[&w]);
        for k in 0..=rings {
            mesh.triangles.push([cu[k], cw[k], cw[k + 1]]);
            mesh.triangles.push([cu[k], cw[k + 1], cu[k + 1]]);
        }
    }
    // local smoothing of F_tendon (moved and gap vertices; the copies at level 0 hold)
    let mut free = moved.clone();
    free.resize(mesh.vertices.len(), false);
    for col in column.values() {
        for &v in &col[1..] {
            free[v as usize] = true;
        }
    }
    for col in column.values() {
        free[col[0] as usize] = false;
    }
    Taubin {
        iterations: 10,
        ..Taubin::default()
    }
    .smooth_subset(mesh, &free)?;
    let new_vertices: Vec<u32> = (first_new..mesh.vertices.len() as u32).collect();
    let pts: Vec<Point3<f64>> = (0..mesh.vertices.len())
        .filter(|&i| free[i] || i >= first_new as usize)
        .map(|i| mesh.vertices[i])
        .collect();
    let attachment = Attachment::hull("generated", &pts, 0.5 * edge.max(1e-9)).ok();
    Ok(Extrusion {
        bottom_faces: bottom.iter().filter(|b| **b).count(),
        distance: gap,
        rings,
        new_vertices,
        attachment,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn hull_contains_its_points() {
        let mut x = 12345u64;
        let mut r = || {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            (x % 10_000) as f64 / 10_000.0
        };
        let pts: Vec<Point3<f64>> = (0..300).map(|_| Point3::new(r(), r(), r())).collect();
        let planes = convex_hull_planes(&pts).unwrap();
        for p in &pts {
            for (n, d) in &planes {
                assert!(
                    n.dot(&p.coords) - d <= 1e-6,
                    "{p:?} outside by {}",
                    n.dot(&p.coords) - d
                );
            }
        }
        let a = Attachment {
            name: "c".into(),
            region: Region::Hull {
                planes,
                tolerance: 0.0,
            },
        };
        assert!(a.contains(&Point3::new(0.5, 0.5, 0.5)));
        assert!(!a.contains(&Point3::new(1.5, 0.5, 0.5)));
    }
}
