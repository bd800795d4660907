//! Registration without correspondences: a recorded first frame of any marker set (markers
//! anywhere on the trunk, labelled or not, in a laboratory frame) brought onto the skin
//! surface by a similarity transform, then each marker bound to its nearest skin point.
//!
//! The method: a principal-axes start (the markers' principal axes put onto the skin's, in
//! each of the 24 orderings and sign choices of the axes that make a proper rotation, each
//! also turned by sixths of a turn about the skin's long axis), then trimmed iterative
//! closest point against the skin surface (Besl & McKay 1992, "A method for registration of
//! 3-D shapes", IEEE PAMI 14:239, with the trimming of Chetverikov et al. 2002, "The trimmed
//! iterative closest point algorithm", ICPR: each iteration pairs every marker with its
//! closest point on the skin's triangles, keeps the best-matched 80 % of the pairs and
//! solves the least-squares similarity of those pairs, Umeyama 1991), polished
//! point-to-plane (Chen & Medioni 1992). Every start is run briefly, the best few to
//! convergence, and the one of smallest truncated-quadratic distance kept (the mean over
//! all markers of the squared distance capped at [`SurfaceOptions::max_distance`]: a pose
//! must bring many markers near the skin, not fit a trimmed few closely). Each marker is
//! then attached to the closest point on the registered skin (triangle and barycentric
//! coordinates); markers farther than [`SurfaceOptions::max_distance`] are reported and
//! left out.
//!
//! A trunk is nearly symmetric: turned 180 degrees about its long axis, or upside down, a
//! marker cloud fits the skin almost as well as in the right pose (a recording of 30
//! chest-and-back markers scored 119 mm^2 in the pose turned 175 degrees about the vertical
//! against 160 mm^2 in the right one). [`register_candidates`] therefore returns every
//! distinct pose (rotations more than [`DISTINCT_POSE_DEG`] apart) whose score is within
//! [`SurfaceOptions::candidate_margin`] of the best, for a choice by the breathing motion
//! ([`crate::fit::orient`]); [`register_to_surface`] returns the best-scoring one.
//!
//! Limits (tests/marker_registration.rs): 300 markers spread over the trunk are registered
//! within 0.06 deg and 0.04 % of scale; a dozen leave the smooth trunk surface ambiguous,
//! the pose is right but the markers may slide several millimetres along the skin.

use super::SurfaceBinding;
use super::register::{RigidTransform, register_rigid};
use crate::mesh::{Bvh, TriMesh};
use crate::{Error, Result};
use nalgebra::{Matrix3, Point3, Rotation3, SMatrix, SVector, UnitQuaternion, Vector3};

/// Turns about the skin's long axis tried with each principal-axes start: the principal
/// axes of a few markers, or of markers on part of the trunk, are only roughly the skin's,
/// and a trunk is nearly round about its long axis.
const SPINS: usize = 6;

/// Fewest tracked markers the registration accepts: below about a dozen points spread
/// over the trunk, a trimmed closest-point fit has too little surface to lock onto.
pub const MIN_SURFACE_MARKERS: usize = 12;

/// Poses whose rotations differ by less than this are one pose [deg]: the principal-axes
/// starts are a sixth of a turn (60 degrees) or a quarter turn apart, and a converged
/// registration is within 2 degrees of the truth (tests/marker_registration.rs).
/// Numerical: a registration setting.
pub const DISTINCT_POSE_DEG: f64 = 20.0;

/// Settings of [`register_to_surface`].
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceOptions {
    /// Estimate a uniform scale (the recorded subject's size relative to the model's).
    pub with_scale: bool,
    /// Fraction of the worst-matched markers left out of each update (0 <= trim < 0.5).
    pub trim: f64,
    /// Markers farther than this from the registered skin are left out [m] (the issue's
    /// 3 cm: a marker on the skin is within a few millimetres of it once the subject's
    /// size and pose are matched).
    pub max_distance: f64,
    /// Iterations of each candidate's short run (point-to-point, then as many
    /// point-to-plane).
    pub probe_iterations: usize,
    /// Largest number of iterations of the final runs.
    pub max_iterations: usize,
    /// Candidates run to convergence.
    pub finalists: usize,
    /// Allowed range of the scale when estimated.
    pub scale_range: (f64, f64),
    /// A known approximate registration (recorded frame -> model frame) to refine instead
    /// of the principal-axes scan: the same markers on a slightly different skin, say
    /// (the subject-size search, [`crate::fit::size`]).
    pub start: Option<RigidTransform>,
    /// Distinct poses whose score is at most this many times the best are candidates
    /// ([`register_candidates`]). 3 (1.7 x in distance) keeps the near ties of a trunk's
    /// symmetries (1.34 x in score on a real 30-marker recording) with room to spare.
    pub candidate_margin: f64,
}

impl Default for SurfaceOptions {
    fn default() -> Self {
        SurfaceOptions {
            with_scale: true,
            trim: 0.2,
            max_distance: 0.03,
            probe_iterations: 10,
            max_iterations: 100,
            finalists: 16,
            scale_range: (0.7, 1.4),
            start: None,
            candidate_margin: 3.0,
        }
    }
}

/// A marker bound by the registration.
#[derive(Clone, Debug, PartialEq)]
pub struct AttachedMarker {
    /// Index of the marker in the recorded frame.
    pub index: usize,
    /// Where it sits on the skin.
    pub binding: SurfaceBinding,
    /// Its distance to the skin after registration [m].
    pub distance: f64,
}

/// The outcome of [`register_to_surface`].
#[derive(Clone, Debug, PartialEq)]
pub struct SurfaceRegistration {
    /// Recorded frame -> model frame (a similarity when the scale is estimated).
    pub to_model: RigidTransform,
    /// Root-mean-square distance of the kept markers to the skin after registration [m].
    pub rms: f64,
    /// Trimmed root-mean-square distance the search minimised (best 1 - trim of the
    /// markers) [m].
    pub trimmed_rms: f64,
    /// Markers bound to the skin, in recorded order.
    pub attached: Vec<AttachedMarker>,
    /// Markers left out: (index in the recorded frame, distance to the skin [m]); untracked
    /// markers are listed with distance NaN.
    pub excluded: Vec<(usize, f64)>,
    /// Closest-point iterations spent over all candidates.
    pub iterations: usize,
    /// The truncated-quadratic score the pose was chosen by: the mean over the tracked
    /// markers of min(d, max_distance)^2 [m^2].
    pub score: f64,
}

/// Barycentric coordinates of a point `p` lying on triangle (a, b, c).
fn barycentric(p: &Point3<f64>, a: &Point3<f64>, b: &Point3<f64>, c: &Point3<f64>) -> [f64; 3] {
    let (v0, v1, v2) = (b - a, c - a, p - a);
    let (d00, d01, d11) = (v0.dot(&v0), v0.dot(&v1), v1.dot(&v1));
    let (d20, d21) = (v2.dot(&v0), v2.dot(&v1));
    let den = d00 * d11 - d01 * d01;
    if den.abs() <= f64::EPSILON * d00 * d11 {
        return [1.0, 0.0, 0.0];
    }
    let v = ((d11 * d20 - d01 * d21) / den).clamp(0.0, 1.0);
    let w = ((d00 * d21 - d01 * d20) / den).clamp(0.0, 1.0 - v);
    [1.0 - v - w, v, w]
}

/// Mean and principal axes (columns, by decreasing variance, right-handed) of weighted
/// points.
fn principal_axes(points: &[(Point3<f64>, f64)]) -> (Vector3<f64>, Matrix3<f64>) {
    let wsum: f64 = points.iter().map(|p| p.1).sum();
    let mean = points
        .iter()
        .fold(Vector3::zeros(), |a, (p, w)| a + p.coords * *w)
        / wsum;
    let mut cov = Matrix3::zeros();
    for (p, w) in points {
        let d = p.coords - mean;
        cov += d * d.transpose() * *w;
    }
    let eig = (cov / wsum).symmetric_eigen();
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| eig.eigenvalues[b].total_cmp(&eig.eigenvalues[a]));
    let mut axes = Matrix3::from_columns(&[
        eig.eigenvectors.column(order[0]).into_owned(),
        eig.eigenvectors.column(order[1]).into_owned(),
        eig.eigenvectors.column(order[2]).into_owned(),
    ]);
    if axes.determinant() < 0.0 {
        axes.set_column(2, &(-axes.column(2)));
    }
    (mean, axes)
}

/// The outward side of a patch of markers (recorded frame), or `None` when the markers are
/// not a patch: their smallest principal spread is under a fifth of the middle one
/// (variances under 1/25), and the side is the one the patch bulges to (on a convex trunk
/// the markers far from the centroid lie behind it: the height along the thin axis falls
/// with the squared distance in the patch's plane).
fn patch_outward(
    points: &[Point3<f64>],
    mean: &Vector3<f64>,
    axes: &Matrix3<f64>,
) -> Option<Vector3<f64>> {
    let n = points.len() as f64;
    let var = |k: usize| {
        points
            .iter()
            .map(|p| (p.coords - mean).dot(&axes.column(k)).powi(2))
            .sum::<f64>()
            / n
    };
    if var(2) >= var(1) / 25.0 {
        return None;
    }
    let normal = axes.column(2).into_owned();
    let (h, r2): (Vec<f64>, Vec<f64>) = points
        .iter()
        .map(|p| {
            let d = p.coords - mean;
            let h = d.dot(&normal);
            (h, d.norm_squared() - h * h)
        })
        .unzip();
    let (mh, mr) = (h.iter().sum::<f64>() / n, r2.iter().sum::<f64>() / n);
    let cov: f64 = h.iter().zip(&r2).map(|(a, b)| (a - mh) * (b - mr)).sum();
    Some(if cov > 0.0 { -normal } else { normal })
}

/// The 24 proper rotations that permute and flip the coordinate axes.
fn axis_rotations() -> Vec<Matrix3<f64>> {
    let perms = [
        [0, 1, 2],
        [0, 2, 1],
        [1, 0, 2],
        [1, 2, 0],
        [2, 0, 1],
        [2, 1, 0],
    ];
    let mut out = Vec::with_capacity(24);
    for p in perms {
        for signs in 0..8u32 {
            let mut m = Matrix3::zeros();
            for (i, &j) in p.iter().enumerate() {
                m[(i, j)] = if signs & (1 << i) != 0 { -1.0 } else { 1.0 };
            }
            if m.determinant() > 0.0 {
                out.push(m);
            }
        }
    }
    out
}

/// One candidate's state.
#[derive(Clone)]
struct Candidate {
    /// The breathing motion's verdict on the pose (0 best; see `SurfaceIcp::motion_class`);
    /// 0 for all without a motion.
    prior: u8,
    t: RigidTransform,
    trimmed_rms: f64,
    /// Truncated-quadratic score: the mean over all markers of min(d, max_distance)^2, so
    /// that a pose fitting fewer markers within reach scores worse whatever its trimmed
    /// residual (a few markers fit a smooth trunk in many wrong poses).
    score: f64,
}

/// The closest-point machinery over one surface.
struct SurfaceIcp<'a> {
    bvh: Bvh,
    /// Outward unit normal of each triangle.
    normals: Vec<Vector3<f64>>,
    points: &'a [Point3<f64>],
    keep: usize,
    options: &'a SurfaceOptions,
}

impl SurfaceIcp<'_> {
    /// Closest skin points of the transformed markers and their distances.
    fn match_points(&self, t: &RigidTransform) -> Vec<(Point3<f64>, f64, u32)> {
        self.points
            .iter()
            .map(|p| {
                let q = t.apply(p);
                match self.bvh.closest(&q) {
                    Some(c) => (c.point, c.distance, c.triangle),
                    None => (q, f64::INFINITY, 0),
                }
            })
            .collect()
    }

    /// The truncated-quadratic score of matches (see [`Candidate::score`]).
    fn score(&self, matches: &[(Point3<f64>, f64, u32)]) -> f64 {
        let c = self.options.max_distance;
        matches.iter().map(|m| m.1.min(c).powi(2)).sum::<f64>() / matches.len() as f64
    }

    /// The breathing motion's verdict on a pose: `motion` holds each recorded marker's
    /// inspiratory direction up to sign (recorded frame, by index into the frame; the
    /// recording's principal-displacement loadings), `tracked` the frame indices of
    /// `points`. In the pose the motion is signed so that the markers within reach of the
    /// skin move out of it (the front and sides expand on inspiration, the back barely
    /// moves); then 0: it points forwards (+x) and cranially (+y), as the chest wall's does
    /// (the sternum moves ventrally and cranially on inspiration: Wilson et al. 1987,
    /// J Appl Physiol 62:1872); 1: forwards only; 2: backwards.
    fn motion_class(&self, t: &RigidTransform, motion: &[Vector3<f64>], tracked: &[usize]) -> u8 {
        let matches = self.match_points(t);
        let (mut outward, mut sum) = (0.0, Vector3::zeros());
        for (k, m) in matches.iter().enumerate() {
            if m.1 > self.options.max_distance {
                continue;
            }
            let l = t.rotation * motion[tracked[k]];
            outward += l.dot(&self.normals[m.2 as usize]);
            sum += l;
        }
        let sum = if outward < 0.0 { -sum } else { sum };
        match (sum.x > 0.0, sum.y > 0.0) {
            (true, true) => 0,
            (true, false) => 1,
            _ => 2,
        }
    }

    /// The best-matched `keep` markers' indices and their trimmed RMS distance.
    fn trimmed(&self, matches: &[(Point3<f64>, f64, u32)]) -> (Vec<usize>, f64) {
        let mut idx: Vec<usize> = (0..matches.len()).collect();
        idx.sort_by(|&a, &b| matches[a].1.total_cmp(&matches[b].1));
        idx.truncate(self.keep);
        let rms =
            (idx.iter().map(|&i| matches[i].1.powi(2)).sum::<f64>() / idx.len() as f64).sqrt();
        (idx, rms)
    }

    /// Point-to-plane refinement (Chen & Medioni 1992, "Object modelling by registration of
    /// multiple range images", Image Vis Comput 10:145): each iteration linearises the
    /// distances of the kept markers to the tangent planes at their closest skin points in a
    /// small rotation w, translation u and scale change e about the kept markers' centroid
    /// m, r_i + ((q_i - m) x n_i) . w + n_i . u + e (q_i - m) . n_i, and solves the
    /// least-squares step (a tiny ridge keeps a flat direction still). It converges in a few
    /// iterations where point-to-point pairs slide slowly along a smooth surface. Returns the
    /// iterations spent.
    fn refine(&self, c: &mut Candidate, iterations: usize) -> usize {
        let mut done = 0;
        let (lo, hi) = self.options.scale_range;
        for _ in 0..iterations {
            let matches = self.match_points(&c.t);
            let (kept, _) = self.trimmed(&matches);
            let q: Vec<Point3<f64>> = kept.iter().map(|&i| c.t.apply(&self.points[i])).collect();
            let m = q.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / q.len() as f64;
            let mut ata = SMatrix::<f64, 7, 7>::zeros();
            let mut atb = SVector::<f64, 7>::zeros();
            for (k, &i) in kept.iter().enumerate() {
                let (cp, _, tri) = matches[i];
                let n = self.normals[tri as usize];
                let a = q[k].coords - m;
                let r = (q[k] - cp).dot(&n);
                let w = a.cross(&n);
                let row = SVector::<f64, 7>::from_column_slice(&[
                    w.x,
                    w.y,
                    w.z,
                    n.x,
                    n.y,
                    n.z,
                    if self.options.with_scale {
                        a.dot(&n)
                    } else {
                        0.0
                    },
                ]);
                ata += row * row.transpose();
                atb -= row * r;
            }
            let ridge = 1e-9 * ata.trace().max(1e-300);
            for k in 0..7 {
                ata[(k, k)] += ridge;
            }
            if !self.options.with_scale {
                ata[(6, 6)] = 1.0;
                atb[6] = 0.0;
            }
            let Some(x) = ata.cholesky().map(|ch| ch.solve(&atb)) else {
                break;
            };
            let w = Vector3::new(x[0], x[1], x[2]);
            let u = Vector3::new(x[3], x[4], x[5]);
            let e = x[6];
            // q -> (1 + e) R(w) (q - m) + m + u, composed with the current transform.
            let rw = UnitQuaternion::from_scaled_axis(w);
            let scale = ((1.0 + e) * c.t.scale).clamp(lo, hi);
            let f = scale / c.t.scale;
            let next = RigidTransform {
                rotation: rw * c.t.rotation,
                translation: rw * (c.t.translation - m) * f + m + u,
                scale,
            };
            let moved = self
                .points
                .iter()
                .map(|p| (next.apply(p) - c.t.apply(p)).norm())
                .fold(0.0, f64::max);
            c.t = next;
            done += 1;
            if moved < 1e-8 {
                break;
            }
        }
        let matches = self.match_points(&c.t);
        c.trimmed_rms = self.trimmed(&matches).1;
        c.score = self.score(&matches);
        done + 1
    }

    /// Runs up to `iterations` trimmed ICP updates from `c`; returns the iterations spent.
    fn run(&self, c: &mut Candidate, iterations: usize) -> Result<usize> {
        let mut done = 0;
        let (lo, hi) = self.options.scale_range;
        for _ in 0..iterations {
            let matches = self.match_points(&c.t);
            let (kept, rms) = self.trimmed(&matches);
            c.trimmed_rms = rms;
            let model: Vec<Point3<f64>> = kept.iter().map(|&i| matches[i].0).collect();
            let recorded: Vec<Option<Point3<f64>>> =
                kept.iter().map(|&i| Some(self.points[i])).collect();
            let (mut next, _) = register_rigid(&model, &recorded, self.options.with_scale)?;
            if !(lo..=hi).contains(&next.scale) {
                // Out of range: keep the rotation, re-solve the translation at the clamped
                // scale.
                let s = next.scale.clamp(lo, hi);
                let n = model.len() as f64;
                let mm = model.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / n;
                let mq = kept
                    .iter()
                    .fold(Vector3::zeros(), |a, &i| a + self.points[i].coords)
                    / n;
                next.scale = s;
                next.translation = mm - next.rotation * mq * s;
            }
            done += 1;
            let moved = self
                .points
                .iter()
                .map(|p| (next.apply(p) - c.t.apply(p)).norm())
                .fold(0.0, f64::max);
            c.t = next;
            if moved < 1e-7 {
                break;
            }
        }
        let matches = self.match_points(&c.t);
        c.trimmed_rms = self.trimmed(&matches).1;
        c.score = self.score(&matches);
        Ok(done + 1)
    }
}

/// Registers a recorded frame of markers (`None` = untracked) to a closed skin surface
/// (model frame) without knowing which marker is which (see the module doc), and binds
/// each marker within `options.max_distance` of the registered skin to its closest skin
/// point: the best-scoring pose of [`register_candidates`]. Needs at least
/// [`MIN_SURFACE_MARKERS`] tracked markers not all on a line.
pub fn register_to_surface(
    vertices: &[Point3<f64>],
    triangles: &[[u32; 3]],
    frame: &[Option<Point3<f64>>],
    options: &SurfaceOptions,
) -> Result<SurfaceRegistration> {
    let all = register_candidates(vertices, triangles, frame, None, options)?;
    Ok(all
        .into_iter()
        .min_by(|a, b| a.score.total_cmp(&b.score))
        .expect("register_candidates returns at least one pose"))
}

/// Whether two transforms are one pose: rotations within [`DISTINCT_POSE_DEG`].
fn same_pose(a: &RigidTransform, b: &RigidTransform) -> bool {
    (a.rotation * b.rotation.inverse()).angle() < DISTINCT_POSE_DEG.to_radians()
}

/// Every distinct pose of a recorded frame on the skin whose score is within
/// [`SurfaceOptions::candidate_margin`] times the best, each with its markers bound (see
/// [`register_to_surface`] and the module doc). With `motion` (each marker's inspiratory
/// direction up to sign, recorded frame, in the frame's order), the poses are ranked first
/// by the breathing motion's verdict (a pose whose
/// inspiratory motion points backwards or caudally comes after those where it points
/// forwards and cranially) and then by score, in the choice of the finalists, in the
/// margin (taken within each verdict) and in the order returned. The probes' finalists are chosen
/// distinct (no two within [`DISTINCT_POSE_DEG`]) so that the trunk's near-symmetric poses
/// are all run to convergence. Poses that bind fewer than 3 markers are dropped; an error
/// when none binds 3.
pub fn register_candidates(
    vertices: &[Point3<f64>],
    triangles: &[[u32; 3]],
    frame: &[Option<Point3<f64>>],
    motion: Option<&[Vector3<f64>]>,
    options: &SurfaceOptions,
) -> Result<Vec<SurfaceRegistration>> {
    let valid = (0.0..0.5).contains(&options.trim)
        && options.max_distance > 0.0
        && options.scale_range.0 > 0.0
        && options.scale_range.0 <= 1.0
        && options.scale_range.1 >= 1.0
        && options.finalists > 0
        && options.candidate_margin >= 1.0;
    if !valid {
        return Err(Error::invalid(
            "surface registration options",
            format!("{options:?}"),
            "0 <= trim < 0.5, max_distance > 0, scale range around 1, at least one finalist, candidate margin >= 1",
        ));
    }
    let tracked: Vec<usize> = (0..frame.len())
        .filter(|&i| frame[i].is_some_and(|p| p.coords.iter().all(|c| c.is_finite())))
        .collect();
    if tracked.len() < MIN_SURFACE_MARKERS {
        return Err(Error::invalid(
            "recording first frame",
            format!("{} tracked markers", tracked.len()),
            format!("at least {MIN_SURFACE_MARKERS} markers on the trunk"),
        ));
    }
    let points: Vec<Point3<f64>> = tracked
        .iter()
        .map(|&i| frame[i].expect("tracked"))
        .collect();
    let mesh = TriMesh::new(vertices.to_vec(), triangles.to_vec())?;
    // Skin principal axes: triangle centroids weighted by area (the surface's own moments).
    let skin_pts: Vec<(Point3<f64>, f64)> = triangles
        .iter()
        .map(|t| {
            let (a, b, c) = (
                vertices[t[0] as usize],
                vertices[t[1] as usize],
                vertices[t[2] as usize],
            );
            (
                Point3::from((a.coords + b.coords + c.coords) / 3.0),
                0.5 * (b - a).cross(&(c - a)).norm(),
            )
        })
        .collect();
    let (skin_mean, skin_axes) = principal_axes(&skin_pts);
    let marker_pts: Vec<(Point3<f64>, f64)> = points.iter().map(|p| (*p, 1.0)).collect();
    let (marker_mean, marker_axes) = principal_axes(&marker_pts);
    let spread = marker_pts
        .iter()
        .map(|(p, _)| (p.coords - marker_mean).norm_squared())
        .sum::<f64>();
    if spread <= 0.0 || !spread.is_finite() {
        return Err(Error::invalid(
            "recording first frame",
            "coincident markers",
            "markers spread over the trunk",
        ));
    }
    let normals = triangles
        .iter()
        .map(|t| {
            let (a, b, c) = (
                vertices[t[0] as usize],
                vertices[t[1] as usize],
                vertices[t[2] as usize],
            );
            (b - a)
                .cross(&(c - a))
                .try_normalize(0.0)
                .unwrap_or_else(Vector3::zeros)
        })
        .collect();
    let icp = SurfaceIcp {
        bvh: Bvh::new(&mesh),
        normals,
        points: &points,
        keep: ((points.len() as f64 * (1.0 - options.trim)).ceil() as usize).clamp(3, points.len()),
        options,
    };
    let mut iterations = 0;
    let mut candidates = Vec::with_capacity(48 * SPINS);
    let long_axis = nalgebra::Unit::new_normalize(skin_axes.column(0).into_owned());
    if let Some(t) = options.start {
        candidates.push(Candidate {
            prior: 0,
            t,
            trimmed_rms: f64::INFINITY,
            score: f64::INFINITY,
        });
    }
    let scan = if options.start.is_some() { 0 } else { 24 };
    // A patch of markers (one side of the trunk: its thinnest spread under a fifth of the
    // next) started with its centroid at the skin's centre must travel a trunk's radius to
    // the surface and may settle on the wrong side on the way; it is also started on the
    // skin, at the skin point farthest along its outward side.
    let outward = patch_outward(&points, &marker_mean, &marker_axes);
    let placements: &[bool] = if outward.is_some() {
        &[false, true]
    } else {
        &[false]
    };
    for (p, k, on_skin) in axis_rotations()
        .into_iter()
        .take(scan)
        .flat_map(|p| (0..SPINS).map(move |k| (p, k)))
        .flat_map(|(p, k)| placements.iter().map(move |&o| (p, k, o)))
    {
        let spin = UnitQuaternion::from_axis_angle(
            &long_axis,
            std::f64::consts::TAU * k as f64 / SPINS as f64,
        );
        let r = skin_axes * p * marker_axes.transpose();
        let rotation =
            spin * UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
        let target = match (on_skin, outward) {
            (true, Some(n)) => {
                let d = rotation * n;
                vertices
                    .iter()
                    .map(|v| v.coords)
                    .max_by(|a, b| (a - skin_mean).dot(&d).total_cmp(&(b - skin_mean).dot(&d)))
                    .unwrap_or(skin_mean)
            }
            _ => skin_mean,
        };
        let mut c = Candidate {
            prior: 0,
            t: RigidTransform {
                rotation,
                translation: target - rotation * marker_mean,
                scale: 1.0,
            },
            trimmed_rms: f64::INFINITY,
            score: f64::INFINITY,
        };
        iterations += icp.run(&mut c, options.probe_iterations)?;
        iterations += icp.refine(&mut c, options.probe_iterations);
        candidates.push(c);
    }
    if let Some(motion) = motion {
        for c in &mut candidates {
            c.prior = icp.motion_class(&c.t, motion, &tracked);
        }
    }
    candidates.sort_by(|a, b| a.prior.cmp(&b.prior).then(a.score.total_cmp(&b.score)));
    let mut finalists: Vec<Candidate> = Vec::with_capacity(options.finalists);
    for c in candidates {
        if finalists.len() == options.finalists {
            break;
        }
        if !finalists.iter().any(|f| same_pose(&f.t, &c.t)) {
            finalists.push(c);
        }
    }
    for c in &mut finalists {
        iterations += icp.run(c, options.max_iterations)?;
        iterations += icp.refine(c, options.max_iterations);
    }
    if let Some(motion) = motion {
        for c in &mut finalists {
            c.prior = icp.motion_class(&c.t, motion, &tracked);
        }
    }
    // The margin is taken within each class of the motion's verdict (the best class
    // first), so that a pose the breathing motion favours is kept even when the shape
    // prefers a pose it rules out.
    finalists.sort_by(|a, b| a.prior.cmp(&b.prior).then(a.score.total_cmp(&b.score)));
    let mut kept: Vec<Candidate> = Vec::new();
    for c in finalists.iter() {
        let class_best = finalists
            .iter()
            .filter(|f| f.prior == c.prior)
            .map(|f| f.score)
            .fold(f64::INFINITY, f64::min);
        if c.score > options.candidate_margin * class_best {
            continue;
        }
        if !kept.iter().any(|k| same_pose(&k.t, &c.t)) {
            kept.push(c.clone());
        }
    }
    let mut out = Vec::new();
    let mut last_error = None;
    for c in kept {
        match bind_pose(&icp, &c, vertices, triangles, frame, &tracked, iterations) {
            Ok(r) => out.push(r),
            Err(e) => last_error = Some(e),
        }
    }
    match (out.is_empty(), last_error) {
        (true, Some(e)) => Err(e),
        _ => Ok(out),
    }
}

/// Binds each tracked marker of `frame` to its closest skin point in the pose of `c`.
fn bind_pose(
    icp: &SurfaceIcp,
    c: &Candidate,
    vertices: &[Point3<f64>],
    triangles: &[[u32; 3]],
    frame: &[Option<Point3<f64>>],
    tracked: &[usize],
    iterations: usize,
) -> Result<SurfaceRegistration> {
    let options = icp.options;
    let matches = icp.match_points(&c.t);
    let mut attached = Vec::new();
    let mut excluded: Vec<(usize, f64)> = (0..frame.len())
        .filter(|i| !tracked.contains(i))
        .map(|i| (i, f64::NAN))
        .collect();
    for (k, &i) in tracked.iter().enumerate() {
        let (q, d, tri) = matches[k];
        if d > options.max_distance {
            excluded.push((i, d));
            continue;
        }
        let t = triangles[tri as usize];
        let bary = barycentric(
            &q,
            &vertices[t[0] as usize],
            &vertices[t[1] as usize],
            &vertices[t[2] as usize],
        );
        attached.push(AttachedMarker {
            index: i,
            binding: SurfaceBinding {
                triangle: tri,
                barycentric: bary,
            },
            distance: d,
        });
    }
    excluded.sort_by_key(|e| e.0);
    if attached.len() < 3 {
        return Err(Error::State(format!(
            "surface registration: only {} of {} markers lie within {:.0} mm of the skin",
            attached.len(),
            tracked.len(),
            options.max_distance * 1e3
        )));
    }
    let rms =
        (attached.iter().map(|a| a.distance.powi(2)).sum::<f64>() / attached.len() as f64).sqrt();
    Ok(SurfaceRegistration {
        to_model: c.t,
        rms,
        trimmed_rms: c.trimmed_rms,
        attached,
        excluded,
        iterations,
        score: c.score,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_recovers_a_point_on_the_triangle() {
        let a = Point3::new(0.0, 0.0, 0.0);
        let b = Point3::new(1.0, 0.0, 0.0);
        let c = Point3::new(0.0, 2.0, 0.0);
        let p = Point3::new(0.25, 0.5, 0.0);
        let w = barycentric(&p, &a, &b, &c);
        let q = a.coords * w[0] + b.coords * w[1] + c.coords * w[2];
        assert!((q - p.coords).norm() < 1e-12);
    }

    #[test]
    fn rotations_are_24_proper() {
        let r = axis_rotations();
        assert_eq!(r.len(), 24);
        assert!(r.iter().all(|m| (m.determinant() - 1.0).abs() < 1e-12));
    }
}
