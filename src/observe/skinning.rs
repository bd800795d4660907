//! Skin deformation by bone heat (Baran & Popovic 2007, "Automatic rigging and animation of
//! 3D characters"; thesis 3.3) and linear blend skinning (thesis 3.3, [34]).
//!
//! Handles are rigid bones (ribs, sternum, the fixed spine and clavicles) and translation handles (the
//! abdominal wall's vertices). Translation handles are grouped into patches of neighbouring
//! vertices, each patch one influence moving with the mean displacement of its members. A
//! patch spans a fixed radius on the wall ([`PATCH_RADIUS`]), not a number of vertices, so
//! that every level of detail averages the wall's motion over the same area. For
//! each influence j the weights solve the heat equilibrium on the skin (Baran & Popovic,
//! section 4):
//!
//! `(-Delta + H) w_j = H p_j`,
//!
//! with Delta the cotangent Laplace-Beltrami operator `Delta = -A^-1 K` (K the cotangent
//! stiffness matrix, A the barycentric vertex areas), `H_ii = c / d_i^2` where d_i is the
//! distance from vertex i to its nearest visible influence and `p_j,i = 1` when that
//! influence is j. Multiplying by A gives the symmetric positive definite system
//! `(K + A H) w_j = A H p_j`, the same matrix for every influence: it is factorised once by a
//! sparse envelope Cholesky (reverse Cuthill-McKee ordering) and each influence costs two
//! triangular solves. Weights are clamped to be non-negative, the largest `max_influences`
//! kept per vertex and normalised to sum 1.
//!
//! Deformation: `v' = v + sum_j w_j ((R_j - I) v + t_j)` (linear blend skinning written as an
//! offset so that the rest pose reproduces the skin exactly); translation influences have
//! `R_j = I` and `t_j` their patch displacement. Points bound to the skin (markers) are
//! pre-combined so that only they are evaluated.

use super::envelope::EnvelopeCholesky;
use crate::anatomy::skin::SurfaceBinding;
use crate::anatomy::skin::geometry::{
    TriangleGrid, closest_point_on_segment, mean_edge_length, segment_crosses_triangle,
};
use crate::{Error, Result};
use nalgebra::{Isometry3, Matrix3, Point3, Vector3};

/// The kind of a skinning handle.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum HandleKind {
    /// A bone: rib, sternum, spine or clavicle (the last two fixed); moves by an isometry.
    Rigid,
    /// An abdominal-wall vertex; moves by a displacement.
    Translation,
}

/// A skinning handle.
#[derive(Clone, Debug, PartialEq)]
pub struct Handle {
    /// Rigid bone or translation vertex.
    pub kind: HandleKind,
    /// Name (for reports and exports).
    pub name: String,
    /// Rest-pose samples: a bone's centreline (consecutive samples form segments) or the
    /// single vertex of a translation handle.
    pub points: Vec<Point3<f64>>,
    /// Wall area [m^2] a translation handle stands for (a third of its vertex's incident
    /// triangles' areas; > 0); 0 for a rigid handle (unused).
    pub area: f64,
}

/// The current pose of one handle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum HandlePose {
    /// Rest-to-current isometry of a rigid handle.
    Rigid(Isometry3<f64>),
    /// Rest-to-current displacement of a translation handle [m].
    Translation(Vector3<f64>),
}

impl HandlePose {
    /// The rest pose of a handle of this kind.
    pub fn rest(kind: HandleKind) -> Self {
        match kind {
            HandleKind::Rigid => HandlePose::Rigid(Isometry3::identity()),
            HandleKind::Translation => HandlePose::Translation(Vector3::zeros()),
        }
    }
}

/// Default radius [m] of an abdominal-wall patch (a patch covers pi r^2 of wall): the
/// abdominal wall's thickness, the length over which the skin smooths the motion of the
/// cavity wall beneath it (a displacement imposed under an elastic layer spreads over about
/// the layer's thickness).
/// Rectus abdominis 10.3 mm plus subcutaneous fat 23.9 mm at the umbilicus (CT of 545 adult
/// women; Kim et al. 2012, Arch Plast Surg 39:528, Results), 34 mm. The patches were 8
/// vertices each before, 7 / 26 / 104 patches at levels of detail 0 / 1 / 2.
pub const PATCH_RADIUS: f64 = 0.034;

/// Settings of the bone-heat weights.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinningOptions {
    /// Heat constant c of `H_ii = c / d_i^2` (Baran & Popovic use 1).
    pub heat_constant: f64,
    /// Influences kept per vertex (1..=16).
    pub max_influences: usize,
    /// Radius [m] of an abdominal-wall patch of translation handles: the wall is cut into
    /// patches of pi r^2 each, or one per handle where the handles are sparser
    /// ([`PATCH_RADIUS`] by default; > 0).
    pub patch_radius: f64,
    /// Heat a vertex only from influences it can see (the segment to the influence does not
    /// cross the skin).
    pub visibility: bool,
}

impl Default for SkinningOptions {
    fn default() -> Self {
        SkinningOptions {
            heat_constant: 1.0,
            max_influences: 6,
            patch_radius: PATCH_RADIUS,
            visibility: true,
        }
    }
}

/// What drives one influence.
#[derive(Clone, Debug, PartialEq)]
pub enum InfluenceSource {
    /// A rigid handle (index into the handle list).
    Rigid(usize),
    /// A patch of translation handles (indices), moving with their mean displacement.
    TranslationGroup(Vec<usize>),
}

/// One column of the weight matrix.
#[derive(Clone, Debug, PartialEq)]
pub struct Influence {
    /// Handle name, or `abdominal_patch<k>` for a patch of translation handles.
    pub name: String,
    /// What moves it.
    pub source: InfluenceSource,
    /// Rest-pose samples used for distances (a centreline or the patch's vertices).
    pub points: Vec<Point3<f64>>,
    /// Whether `points` form a polyline (rigid bones) or a point set (patches).
    pub polyline: bool,
}

impl Influence {
    /// Nearest point of the influence to `p`.
    pub fn closest_point(&self, p: &Point3<f64>) -> Point3<f64> {
        let mut best = (f64::MAX, self.points[0]);
        let mut try_point = |q: Point3<f64>| {
            let d = (q - p).norm_squared();
            if d < best.0 {
                best = (d, q);
            }
        };
        if self.polyline && self.points.len() >= 2 {
            for w in self.points.windows(2) {
                try_point(closest_point_on_segment(p, &w[0], &w[1]));
            }
        } else {
            for q in &self.points {
                try_point(*q);
            }
        }
        best.1
    }
}

/// Sparse per-vertex weights: `max_influences` slots per vertex (unused slots weigh 0).
#[derive(Clone, Debug, PartialEq)]
pub struct SkinWeights {
    /// Slots per vertex.
    pub max_influences: usize,
    /// Influence index of each slot, `vertex * max_influences + slot`.
    pub influence: Vec<u32>,
    /// Weight of each slot (>= 0, summing to 1 per vertex).
    pub weight: Vec<f64>,
}

impl SkinWeights {
    /// (influence, weight) pairs of vertex `i` with non-zero weight.
    pub fn of_vertex(&self, i: usize) -> impl Iterator<Item = (usize, f64)> + '_ {
        let k = self.max_influences;
        (i * k..(i + 1) * k)
            .filter(|&s| self.weight[s] > 0.0)
            .map(|s| (self.influence[s] as usize, self.weight[s]))
    }

    /// The weight of influence `j` at vertex `i` (0 when not among its slots).
    pub fn get(&self, i: usize, j: usize) -> f64 {
        self.of_vertex(i)
            .filter(|&(q, _)| q == j)
            .map(|(_, w)| w)
            .sum()
    }
}

/// The cotangent discretisation of the Laplace-Beltrami operator (Pinkall & Polthier 1993;
/// Meyer et al. 2003): stiffness `K_ik = -(cot a_ik + cot b_ik) / 2` for an edge ik with
/// opposite angles a, b, `K_ii = -sum_k K_ik`; vertex areas are a third of the incident
/// triangles' areas.
#[derive(Clone, Debug, PartialEq)]
pub struct CotangentLaplacian {
    /// Off-diagonal edge weights `(k, (cot a + cot b) / 2)` of each vertex, sorted by k.
    pub neighbours: Vec<Vec<(u32, f64)>>,
    /// Diagonal `K_ii`, the sum of the vertex's edge weights.
    pub diagonal: Vec<f64>,
    /// Barycentric vertex areas [m^2].
    pub areas: Vec<f64>,
}

impl CotangentLaplacian {
    /// Assembles the operator of a triangle surface.
    pub fn new(vertices: &[Point3<f64>], triangles: &[[u32; 3]]) -> Self {
        let n = vertices.len();
        let mut entries: Vec<Vec<(u32, f64)>> = vec![Vec::new(); n];
        let mut areas = vec![0.0; n];
        for t in triangles {
            let p = t.map(|i| vertices[i as usize]);
            let area = 0.5 * (p[1] - p[0]).cross(&(p[2] - p[0])).norm();
            for k in 0..3 {
                areas[t[k] as usize] += area / 3.0;
                // Angle at corner k is opposite the edge (k+1, k+2).
                let (a, b) = (p[(k + 1) % 3] - p[k], p[(k + 2) % 3] - p[k]);
                let cross = a.cross(&b).norm();
                let cot = if cross > 0.0 { a.dot(&b) / cross } else { 0.0 };
                let (i, j) = (t[(k + 1) % 3], t[(k + 2) % 3]);
                entries[i as usize].push((j, 0.5 * cot));
                entries[j as usize].push((i, 0.5 * cot));
            }
        }
        let mut diagonal = vec![0.0; n];
        for (i, e) in entries.iter_mut().enumerate() {
            e.sort_by_key(|x| x.0);
            let mut merged: Vec<(u32, f64)> = Vec::with_capacity(e.len() / 2 + 1);
            for &(j, w) in e.iter() {
                match merged.last_mut() {
                    Some(last) if last.0 == j => last.1 += w,
                    _ => merged.push((j, w)),
                }
            }
            diagonal[i] = merged.iter().map(|x| x.1).sum();
            *e = merged;
        }
        CotangentLaplacian {
            neighbours: entries,
            diagonal,
            areas,
        }
    }
}

/// The heat equilibrium of one skin and its influences, factorised once.
#[derive(Clone, Debug)]
pub struct BoneHeat {
    /// The cotangent operator of the skin.
    pub laplacian: CotangentLaplacian,
    /// `H_ii = c / d_i^2` (0 where no influence is visible).
    pub heat: Vec<f64>,
    /// Nearest visible influence of each vertex.
    pub nearest: Vec<Option<u32>>,
    chol: EnvelopeCholesky,
}

impl BoneHeat {
    /// Assembles and factorises `K + A H` for the given influences.
    pub fn new(
        vertices: &[Point3<f64>],
        triangles: &[[u32; 3]],
        influences: &[Influence],
        options: &SkinningOptions,
    ) -> Result<Self> {
        if influences.is_empty() {
            return Err(Error::invalid("skinning handles", 0, "at least one handle"));
        }
        let laplacian = CotangentLaplacian::new(vertices, triangles);
        let n = vertices.len();
        let grid = options.visibility.then(|| {
            TriangleGrid::new(
                vertices,
                triangles,
                2.0 * mean_edge_length(vertices, triangles),
            )
        });
        let mut stamp = vec![u32::MAX; triangles.len()];
        let mut heat = vec![0.0; n];
        let mut nearest = vec![None; n];
        let mut cand: Vec<(f64, usize, Point3<f64>)> = Vec::with_capacity(influences.len());
        for (i, v) in vertices.iter().enumerate() {
            cand.clear();
            for (j, inf) in influences.iter().enumerate() {
                let c = inf.closest_point(v);
                cand.push(((c - v).norm(), j, c));
            }
            cand.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)));
            for &(d, j, c) in cand.iter().take(4) {
                let visible = match &grid {
                    None => true,
                    Some(g) => {
                        let start = v + (c - v) * 1e-6;
                        let (lo, hi) = (start.inf(&c), start.sup(&c));
                        let mut blocked = false;
                        g.visit_box(&lo, &hi, &mut stamp, i as u32, |t| {
                            let tri = &triangles[t as usize];
                            if blocked || tri.contains(&(i as u32)) {
                                return;
                            }
                            let p = tri.map(|k| &vertices[k as usize]);
                            blocked = segment_crosses_triangle(&start, &c, p[0], p[1], p[2]);
                        });
                        !blocked
                    }
                };
                if visible {
                    heat[i] = options.heat_constant / (d * d).max(1e-12);
                    nearest[i] = Some(j as u32);
                    break;
                }
            }
        }
        let extra: Vec<f64> = (0..n).map(|i| laplacian.areas[i] * heat[i]).collect();
        let chol = EnvelopeCholesky::factor(&laplacian.diagonal, &laplacian.neighbours, &extra)
            .map_err(|(vertex, d)| Error::Numerical {
                time: 0.0,
                reason: format!(
                    "bone-heat matrix not positive definite at vertex {vertex} (pivot {d:e}): is every skin component heated?"
                ),
            })?;
        Ok(BoneHeat {
            laplacian,
            heat,
            nearest,
            chol,
        })
    }

    /// The raw (unclamped, unpruned) weight field of influence `j`.
    pub fn solve(&self, j: usize) -> Vec<f64> {
        let mut work = Vec::new();
        self.solve_into(j, &mut work)
    }

    fn solve_into(&self, j: usize, work: &mut Vec<f64>) -> Vec<f64> {
        let mut b: Vec<f64> = (0..self.heat.len())
            .map(|i| {
                if self.nearest[i] == Some(j as u32) {
                    self.laplacian.areas[i] * self.heat[i]
                } else {
                    0.0
                }
            })
            .collect();
        self.chol.solve(&mut b, work);
        b
    }
}

/// Groups translation handles into patches of `pi radius^2` of wall each (by the handles'
/// areas), at most one per handle: farthest-point seeds, then a few area-weighted Lloyd
/// iterations; deterministic. The patch count follows the wall's area, not its vertex count.
fn group_translations(handles: &[Handle], members: &[usize], radius: f64) -> Vec<Vec<usize>> {
    if members.is_empty() {
        return Vec::new();
    }
    let loc = |h: usize| -> Point3<f64> {
        let p = &handles[h].points;
        Point3::from(p.iter().fold(Vector3::zeros(), |a, q| a + q.coords) / p.len() as f64)
    };
    let pts: Vec<Point3<f64>> = members.iter().map(|&h| loc(h)).collect();
    let area: Vec<f64> = members.iter().map(|&h| handles[h].area).collect();
    let patch = std::f64::consts::PI * radius * radius;
    let k = ((area.iter().sum::<f64>() / patch).ceil() as usize).clamp(1, members.len());
    let mut centres = vec![pts[0]];
    let mut dmin: Vec<f64> = pts.iter().map(|p| (p - pts[0]).norm_squared()).collect();
    while centres.len() < k {
        let (far, _) = dmin
            .iter()
            .enumerate()
            .fold((0, -1.0), |b, (i, &d)| if d > b.1 { (i, d) } else { b });
        centres.push(pts[far]);
        for (i, p) in pts.iter().enumerate() {
            dmin[i] = dmin[i].min((p - pts[far]).norm_squared());
        }
    }
    let mut assign = vec![0usize; pts.len()];
    for _ in 0..8 {
        for (i, p) in pts.iter().enumerate() {
            assign[i] = (0..centres.len())
                .min_by(|&a, &b| {
                    (p - centres[a])
                        .norm_squared()
                        .total_cmp(&(p - centres[b]).norm_squared())
                })
                .unwrap_or(0);
        }
        for (c, centre) in centres.iter_mut().enumerate() {
            let (sum, weight) = pts
                .iter()
                .zip(&area)
                .zip(&assign)
                .filter(|(_, a)| **a == c)
                .fold((Vector3::zeros(), 0.0), |(s, n), ((p, w), _)| {
                    (s + p.coords * *w, n + w)
                });
            if weight > 0.0 {
                *centre = Point3::from(sum / weight);
            }
        }
    }
    (0..centres.len())
        .map(|c| {
            members
                .iter()
                .zip(&assign)
                .filter(|(_, a)| **a == c)
                .map(|(&h, _)| h)
                .collect::<Vec<_>>()
        })
        .filter(|g: &Vec<usize>| !g.is_empty())
        .collect()
}

/// Per-influence motion of one frame: `(R - I, t)`.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct SkinningFrame {
    linear: Vec<Matrix3<f64>>,
    translation: Vec<Vector3<f64>>,
}

/// Skinning of one skin by a set of handles: weights computed once, deformation per frame.
#[derive(Clone, Debug)]
pub struct Skinning {
    rest: Vec<Point3<f64>>,
    kinds: Vec<HandleKind>,
    influences: Vec<Influence>,
    weights: SkinWeights,
}

impl Skinning {
    /// Computes bone-heat weights of `handles` on the skin (vertices, triangles).
    pub fn new(
        vertices: &[Point3<f64>],
        triangles: &[[u32; 3]],
        handles: &[Handle],
        options: &SkinningOptions,
    ) -> Result<Self> {
        if !(1..=16).contains(&options.max_influences) {
            return Err(Error::invalid(
                "skinning.max_influences",
                options.max_influences,
                "1..=16",
            ));
        }
        if !(options.patch_radius > 0.0 && options.patch_radius.is_finite()) {
            return Err(Error::invalid(
                "skinning.patch_radius",
                options.patch_radius,
                "(0, inf) m",
            ));
        }
        if !(options.heat_constant > 0.0 && options.heat_constant.is_finite()) {
            return Err(Error::invalid(
                "skinning.heat_constant",
                options.heat_constant,
                "(0, inf)",
            ));
        }
        for h in handles {
            if h.points.is_empty()
                || h.points
                    .iter()
                    .any(|p| !p.coords.iter().all(|c| c.is_finite()))
            {
                return Err(Error::invalid(
                    format!("handle `{}` points", h.name),
                    h.points.len(),
                    "one or more finite points",
                ));
            }
            if h.kind == HandleKind::Translation && !(h.area > 0.0 && h.area.is_finite()) {
                return Err(Error::invalid(
                    format!("handle `{}` area", h.name),
                    h.area,
                    "(0, inf) m^2 for a translation handle",
                ));
            }
        }
        let mut influences = Vec::new();
        let mut translations = Vec::new();
        for (i, h) in handles.iter().enumerate() {
            match h.kind {
                HandleKind::Rigid => influences.push(Influence {
                    name: h.name.clone(),
                    source: InfluenceSource::Rigid(i),
                    points: h.points.clone(),
                    polyline: true,
                }),
                HandleKind::Translation => translations.push(i),
            }
        }
        for (g, members) in group_translations(handles, &translations, options.patch_radius)
            .into_iter()
            .enumerate()
        {
            let points = members
                .iter()
                .flat_map(|&m| handles[m].points.iter().copied())
                .collect();
            influences.push(Influence {
                name: format!("abdominal_patch{g}"),
                source: InfluenceSource::TranslationGroup(members),
                points,
                polyline: false,
            });
        }
        let heat = BoneHeat::new(vertices, triangles, &influences, options)?;
        let n = vertices.len();
        let k = options.max_influences;
        let mut slots: Vec<(f64, u32)> = vec![(0.0, 0); n * k];
        let mut work = Vec::new();
        for j in 0..influences.len() {
            let w = heat.solve_into(j, &mut work);
            for (i, &wi) in w.iter().enumerate() {
                let s = &mut slots[i * k..(i + 1) * k];
                // Keep the k largest: replace the smallest slot when larger.
                let (min_slot, min_w) =
                    s.iter().enumerate().fold(
                        (0, f64::MAX),
                        |b, (q, x)| if x.0 < b.1 { (q, x.0) } else { b },
                    );
                if wi > min_w && wi > 0.0 {
                    s[min_slot] = (wi, j as u32);
                }
            }
        }
        let mut influence = vec![0u32; n * k];
        let mut weight = vec![0.0; n * k];
        for i in 0..n {
            let s = &mut slots[i * k..(i + 1) * k];
            s.sort_by(|a, b| b.0.total_cmp(&a.0).then(a.1.cmp(&b.1)));
            let sum: f64 = s.iter().map(|x| x.0.max(0.0)).sum();
            if sum > 1e-12 {
                for (q, x) in s.iter().enumerate() {
                    influence[i * k + q] = x.1;
                    weight[i * k + q] = x.0.max(0.0) / sum;
                }
            } else {
                // No heat reached this vertex: follow the nearest influence.
                let j = heat.nearest[i].unwrap_or_else(|| {
                    (0..influences.len())
                        .min_by(|&a, &b| {
                            let da =
                                (influences[a].closest_point(&vertices[i]) - vertices[i]).norm();
                            let db =
                                (influences[b].closest_point(&vertices[i]) - vertices[i]).norm();
                            da.total_cmp(&db)
                        })
                        .unwrap_or(0) as u32
                });
                influence[i * k] = j;
                weight[i * k] = 1.0;
            }
        }
        Ok(Skinning {
            rest: vertices.to_vec(),
            kinds: handles.iter().map(|h| h.kind).collect(),
            influences,
            weights: SkinWeights {
                max_influences: k,
                influence,
                weight,
            },
        })
    }

    /// The influences (weight columns): rigid handles first, then abdominal patches.
    pub fn influences(&self) -> &[Influence] {
        &self.influences
    }

    /// The weights.
    pub fn weights(&self) -> &SkinWeights {
        &self.weights
    }

    /// Rest-pose vertices.
    pub fn rest(&self) -> &[Point3<f64>] {
        &self.rest
    }

    /// Fills `frame` with the motion of every influence for these handle poses (one per
    /// handle, in handle order, of the handle's kind). Does not allocate after the first call.
    pub fn frame_into(&self, poses: &[HandlePose], frame: &mut SkinningFrame) -> Result<()> {
        if poses.len() != self.kinds.len() {
            return Err(Error::invalid(
                "handle poses",
                poses.len(),
                format!("{} poses, one per handle", self.kinds.len()),
            ));
        }
        let m = self.influences.len();
        frame.linear.resize(m, Matrix3::zeros());
        frame.translation.resize(m, Vector3::zeros());
        for (j, inf) in self.influences.iter().enumerate() {
            match &inf.source {
                InfluenceSource::Rigid(h) => match &poses[*h] {
                    HandlePose::Rigid(iso) => {
                        frame.linear[j] =
                            iso.rotation.to_rotation_matrix().into_inner() - Matrix3::identity();
                        frame.translation[j] = iso.translation.vector;
                    }
                    HandlePose::Translation(_) => {
                        return Err(Error::invalid(
                            format!("pose of handle {h}"),
                            "a translation",
                            "an isometry (rigid handle)",
                        ));
                    }
                },
                InfluenceSource::TranslationGroup(members) => {
                    let mut sum = Vector3::zeros();
                    for &h in members {
                        match &poses[h] {
                            HandlePose::Translation(d) => sum += d,
                            HandlePose::Rigid(_) => {
                                return Err(Error::invalid(
                                    format!("pose of handle {h}"),
                                    "an isometry",
                                    "a translation (abdominal-wall handle)",
                                ));
                            }
                        }
                    }
                    frame.linear[j] = Matrix3::zeros();
                    frame.translation[j] = sum / members.len() as f64;
                }
            }
        }
        Ok(())
    }

    /// The motion of every influence for these handle poses.
    pub fn frame(&self, poses: &[HandlePose]) -> Result<SkinningFrame> {
        let mut f = SkinningFrame::default();
        self.frame_into(poses, &mut f)?;
        Ok(f)
    }

    /// Deformed position of vertex `i`.
    pub fn deform_vertex(&self, frame: &SkinningFrame, i: usize) -> Point3<f64> {
        let v = self.rest[i];
        let k = self.weights.max_influences;
        let mut off = Vector3::zeros();
        for s in i * k..(i + 1) * k {
            let w = self.weights.weight[s];
            if w > 0.0 {
                let j = self.weights.influence[s] as usize;
                off += (frame.linear[j] * v.coords + frame.translation[j]) * w;
            }
        }
        v + off
    }

    /// Deforms the whole skin into `out` (resized to the vertex count).
    pub fn deform_all(&self, frame: &SkinningFrame, out: &mut Vec<Point3<f64>>) {
        out.clear();
        out.extend((0..self.rest.len()).map(|i| self.deform_vertex(frame, i)));
    }

    /// Pre-combines the weights of points bound to the skin (markers) so that each frame
    /// evaluates only them.
    pub fn bind(&self, triangles: &[[u32; 3]], bindings: &[SurfaceBinding]) -> Result<BoundPoints> {
        let k = self.weights.max_influences;
        let mut out = BoundPoints {
            rest: Vec::new(),
            start: vec![0],
            influence: Vec::new(),
            alpha: Vec::new(),
            beta: Vec::new(),
        };
        for (m, b) in bindings.iter().enumerate() {
            let t = *triangles.get(b.triangle as usize).ok_or_else(|| {
                Error::invalid(
                    format!("binding {m} triangle"),
                    b.triangle,
                    format!("below {}", triangles.len()),
                )
            })?;
            if t.iter().any(|&v| v as usize >= self.rest.len()) {
                return Err(Error::invalid(
                    format!("binding {m} triangle"),
                    format!("{t:?}"),
                    "vertices of the skinned surface",
                ));
            }
            out.rest.push(b.point(&self.rest, triangles));
            let first = out.influence.len();
            for (c, &v) in t.iter().enumerate() {
                let v = v as usize;
                for s in v * k..(v + 1) * k {
                    let w = self.weights.weight[s] * b.barycentric[c];
                    if w == 0.0 {
                        continue;
                    }
                    let j = self.weights.influence[s];
                    let pos = out.influence[first..]
                        .iter()
                        .position(|&q| q == j)
                        .map(|p| p + first);
                    let idx = pos.unwrap_or_else(|| {
                        out.influence.push(j);
                        out.alpha.push(0.0);
                        out.beta.push(Vector3::zeros());
                        out.influence.len() - 1
                    });
                    out.alpha[idx] += w;
                    out.beta[idx] += self.rest[v].coords * w;
                }
            }
            out.start.push(out.influence.len() as u32);
        }
        Ok(out)
    }
}

/// Points bound to the skin with pre-combined weights: point m moves as
/// `p_m + sum_j ((R_j - I) beta_mj + alpha_mj t_j)` with `alpha_mj = sum_c b_c w_cj` and
/// `beta_mj = sum_c b_c w_cj v_c` over the three vertices c of its triangle.
#[derive(Clone, Debug, PartialEq)]
pub struct BoundPoints {
    rest: Vec<Point3<f64>>,
    start: Vec<u32>,
    influence: Vec<u32>,
    alpha: Vec<f64>,
    beta: Vec<Vector3<f64>>,
}

impl BoundPoints {
    /// Number of bound points.
    pub fn len(&self) -> usize {
        self.rest.len()
    }

    /// True when no point is bound.
    pub fn is_empty(&self) -> bool {
        self.rest.is_empty()
    }

    /// Rest positions.
    pub fn rest(&self) -> &[Point3<f64>] {
        &self.rest
    }

    /// Evaluates the bound points for a frame into `out` (length [`BoundPoints::len`]).
    pub fn evaluate(&self, frame: &SkinningFrame, out: &mut [Point3<f64>]) {
        for (m, o) in out.iter_mut().enumerate().take(self.rest.len()) {
            let mut off = Vector3::zeros();
            for s in self.start[m] as usize..self.start[m + 1] as usize {
                let j = self.influence[s] as usize;
                off += frame.linear[j] * self.beta[s] + frame.translation[j] * self.alpha[s];
            }
            *o = self.rest[m] + off;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Translation handles on a 0.32 m square wall at `spacing` [m], each standing for an
    /// equal share of its area.
    fn wall(spacing: f64) -> Vec<Handle> {
        let n = (0.32 / spacing).round() as usize;
        let area = 0.32 * 0.32 / ((n + 1) * (n + 1)) as f64;
        (0..=n)
            .flat_map(|i| (0..=n).map(move |j| (i, j)))
            .map(|(i, j)| Handle {
                kind: HandleKind::Translation,
                name: format!("wall{i}_{j}"),
                points: vec![Point3::new(0.1, i as f64 * spacing, j as f64 * spacing)],
                area,
            })
            .collect()
    }

    #[test]
    fn patches_cover_the_same_area_at_every_resolution() {
        let r = PATCH_RADIUS;
        let patch = std::f64::consts::PI * r * r;
        let mut sizes = Vec::new();
        // Vertex spacings 4 to 1 cm: 81 to 1,089 handles, as the levels of detail's walls.
        for spacing in [0.04, 0.02, 0.01] {
            let handles = wall(spacing);
            let members: Vec<usize> = (0..handles.len()).collect();
            let groups = group_translations(&handles, &members, r);
            assert_eq!(groups.iter().map(Vec::len).sum::<usize>(), handles.len());
            let areas: Vec<f64> = groups
                .iter()
                .map(|g| g.iter().map(|&h| handles[h].area).sum())
                .collect();
            let mean = areas.iter().sum::<f64>() / areas.len() as f64;
            // The wall cut into patches of pi r^2, none of them left empty: the mean patch
            // is at most pi r^2 and more than the wall shared among one patch more.
            let k = (0.32 * 0.32 / patch).ceil();
            assert_eq!(groups.len() as f64, k, "patches at {spacing} m");
            assert!(
                mean <= patch && mean > 0.32 * 0.32 / (k + 1.0),
                "{mean} m^2"
            );
            sizes.push((groups.len(), mean));
        }
        // A count of vertices per patch gave 16 times the area at 4 cm as at 1 cm.
        assert!(
            sizes.iter().all(|s| s.0 == sizes[0].0),
            "patch counts and mean areas {sizes:?}"
        );
    }
    #[test]
    fn a_bad_patch_radius_or_handle_area_is_named() {
        let mut handles = wall(0.04);
        let options = SkinningOptions {
            patch_radius: 0.0,
            ..SkinningOptions::default()
        };
        let skin = [
            Point3::new(0.0, 0.0, 0.0),
            Point3::new(0.0, 1.0, 0.0),
            Point3::new(0.0, 0.0, 1.0),
        ];
        let err = Skinning::new(&skin, &[[0, 1, 2]], &handles, &options).unwrap_err();
        assert!(err.to_string().contains("skinning.patch_radius"), "{err}");
        handles[3].area = f64::NAN;
        let err =
            Skinning::new(&skin, &[[0, 1, 2]], &handles, &SkinningOptions::default()).unwrap_err();
        assert!(err.to_string().contains("handle `wall0_3` area"), "{err}");
    }
}
