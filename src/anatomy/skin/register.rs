//! Registration of a recording's first frame to the skin (thesis 3.2, figure 3.4): a rigid
//! least-squares fit of the recorded grid to the model markers (Umeyama 1991, optionally
//! with uniform scale), then skin fitting: the bound skin points are moved onto the
//! registered grid points, the displacement spread over the surrounding skin by Gaussian
//! radial basis interpolation, and that region smoothed with Taubin lambda|mu smoothing so
//! that the volume does not shrink. Afterwards marker outputs can be expressed in the
//! recording's frame with [`Registration::to_recording`].

use super::smooth::{taubin_smooth, vertex_neighbours};
use super::{MarkerGrid, Skin};
use crate::{Error, Result};
use nalgebra::{DMatrix, Matrix3, Point3, Rotation3, UnitQuaternion, Vector3};

/// A similarity transform `p -> scale * R p + t` (scale 1 for a rigid registration).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RigidTransform {
    /// Rotation R.
    pub rotation: UnitQuaternion<f64>,
    /// Translation t [m].
    pub translation: Vector3<f64>,
    /// Uniform scale (1 when scale is not estimated).
    pub scale: f64,
}

impl RigidTransform {
    /// The identity.
    pub fn identity() -> Self {
        RigidTransform {
            rotation: UnitQuaternion::identity(),
            translation: Vector3::zeros(),
            scale: 1.0,
        }
    }

    /// Applies the transform.
    pub fn apply(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(self.rotation * p.coords * self.scale + self.translation)
    }

    /// Applies the inverse transform.
    pub fn apply_inverse(&self, p: &Point3<f64>) -> Point3<f64> {
        Point3::from(self.rotation.inverse() * (p.coords - self.translation) / self.scale)
    }

    /// The inverse transform.
    pub fn inverse(&self) -> Self {
        let rotation = self.rotation.inverse();
        RigidTransform {
            rotation,
            translation: -(rotation * self.translation) / self.scale,
            scale: 1.0 / self.scale,
        }
    }
}

/// Least-squares similarity (or rigid, `with_scale = false`) transform mapping the tracked
/// `recorded` points onto `model` (Umeyama 1991, "Least-squares estimation of transformation
/// parameters between two point patterns", eqs. 38-42). `None` entries (untracked points)
/// are skipped. Returns the transform and its root-mean-square residual [m].
pub fn register_rigid(
    model: &[Point3<f64>],
    recorded: &[Option<Point3<f64>>],
    with_scale: bool,
) -> Result<(RigidTransform, f64)> {
    if model.len() != recorded.len() {
        return Err(Error::invalid(
            "recording first frame",
            format!("{} points", recorded.len()),
            format!("{} points (the grid's rows x columns)", model.len()),
        ));
    }
    let pairs: Vec<(Vector3<f64>, Vector3<f64>)> = model
        .iter()
        .zip(recorded)
        .filter_map(|(m, q)| {
            q.filter(|q| q.coords.iter().all(|c| c.is_finite()))
                .map(|q| (m.coords, q.coords))
        })
        .collect();
    if pairs.len() < 3 {
        return Err(Error::invalid(
            "recording first frame",
            format!("{} tracked points", pairs.len()),
            "at least 3",
        ));
    }
    let n = pairs.len() as f64;
    let mean_m = pairs.iter().fold(Vector3::zeros(), |a, p| a + p.0) / n;
    let mean_q = pairs.iter().fold(Vector3::zeros(), |a, p| a + p.1) / n;
    let mut cov = Matrix3::zeros();
    let mut var_q = 0.0;
    for (m, q) in &pairs {
        cov += (m - mean_m) * (q - mean_q).transpose();
        var_q += (q - mean_q).norm_squared();
    }
    cov /= n;
    var_q /= n;
    let svd = cov.svd(true, true);
    let (u, v_t) = match (svd.u, svd.v_t) {
        (Some(u), Some(v)) => (u, v),
        _ => return Err(Error::State("registration: SVD failed".into())),
    };
    let sv = svd.singular_values;
    let mut order = [0usize, 1, 2];
    order.sort_by(|&a, &b| sv[b].total_cmp(&sv[a]));
    if sv[order[1]] <= 1e-12 * sv[order[0]].max(1e-300) {
        return Err(Error::invalid(
            "recording first frame",
            "collinear tracked points",
            "points spanning a plane",
        ));
    }
    let mut s = Matrix3::identity();
    if (u.determinant() * v_t.determinant()) < 0.0 {
        s[(order[2], order[2])] = -1.0;
    }
    let r = u * s * v_t;
    let scale = if with_scale {
        (Matrix3::from_diagonal(&sv) * s).trace() / var_q
    } else {
        1.0
    };
    let rotation = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix_unchecked(r));
    let translation = mean_m - rotation * mean_q * scale;
    let t = RigidTransform {
        rotation,
        translation,
        scale,
    };
    let rms = (pairs
        .iter()
        .map(|(m, q)| (t.apply(&Point3::from(*q)).coords - m).norm_squared())
        .sum::<f64>()
        / n)
        .sqrt();
    Ok((t, rms))
}

/// Settings of the registration and skin fitting.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOptions {
    /// Estimate a uniform scale as well (the thesis scaled the recording to the model).
    pub with_scale: bool,
    /// Width of the Gaussian spreading each marker's displacement, in grid spacings.
    pub spread: f64,
    /// Taubin lambda (> 0).
    pub lambda: f64,
    /// Taubin mu (< -lambda).
    pub mu: f64,
    /// Taubin iterations.
    pub iterations: usize,
}

impl Default for FitOptions {
    fn default() -> Self {
        FitOptions {
            with_scale: false,
            spread: 1.0,
            lambda: 0.5,
            mu: -0.53,
            iterations: 10,
        }
    }
}

/// Skin-fitting errors: distance from each registered grid point to its bound skin point.
#[derive(Clone, Debug, PartialEq)]
pub struct SkinFitReport {
    /// Tracked points used.
    pub points: usize,
    /// Mean error before fitting [m].
    pub mean_before: f64,
    /// Largest error before fitting [m].
    pub max_before: f64,
    /// Mean error after fitting [m].
    pub mean_after: f64,
    /// Largest error after fitting [m].
    pub max_after: f64,
}

/// The result of registering a recording: the transform from the recording's frame to the
/// model's, its residual, and the skin-fitting report.
#[derive(Clone, Debug, PartialEq)]
pub struct Registration {
    /// Recording frame -> model frame.
    pub to_model: RigidTransform,
    /// Model frame -> recording frame (the inverse, stored for the marker outputs).
    pub to_recording: RigidTransform,
    /// RMS residual of the rigid fit [m].
    pub rms: f64,
    /// Skin fitting errors before and after.
    pub fit: SkinFitReport,
}

impl Registration {
    /// Expresses a model-frame point (a marker output) in the recording's frame.
    pub fn to_recording(&self, p: &Point3<f64>) -> Point3<f64> {
        self.to_recording.apply(p)
    }
}

fn errors(a: &[Point3<f64>], b: &[Option<Point3<f64>>]) -> (f64, f64, usize) {
    let d: Vec<f64> = a
        .iter()
        .zip(b)
        .filter_map(|(p, q)| q.map(|q| (p - q).norm()))
        .collect();
    let n = d.len().max(1);
    (
        d.iter().sum::<f64>() / n as f64,
        d.iter().cloned().fold(0.0, f64::max),
        d.len(),
    )
}

impl Skin {
    /// Registers a recording's first frame (end-expiration; `None` = untracked point, in the
    /// grid's index order) to the skin and fits the skin to it. The skin's vertices change;
    /// its topology and the grid's bindings do not.
    pub fn register(
        &mut self,
        grid: &MarkerGrid,
        first_frame: &[Option<Point3<f64>>],
        options: &FitOptions,
    ) -> Result<Registration> {
        if !(options.lambda > 0.0 && options.mu < -options.lambda && options.spread > 0.0) {
            return Err(Error::invalid(
                "fit options",
                format!(
                    "lambda {} mu {} spread {}",
                    options.lambda, options.mu, options.spread
                ),
                "lambda > 0, mu < -lambda, spread > 0",
            ));
        }
        let model = grid.positions(&self.vertices, &self.triangles);
        let (to_model, rms) = register_rigid(&model, first_frame, options.with_scale)?;
        let targets: Vec<Option<Point3<f64>>> = first_frame
            .iter()
            .map(|q| q.map(|q| to_model.apply(&q)))
            .collect();
        let fit = self.fit_to_targets(grid, &targets, options)?;
        Ok(Registration {
            to_model,
            to_recording: to_model.inverse(),
            rms,
            fit,
        })
    }

    /// Skin fitting alone: moves the bound skin points of `grid` onto `targets` (model
    /// frame) and smooths the surrounding skin.
    pub fn fit_to_targets(
        &mut self,
        grid: &MarkerGrid,
        targets: &[Option<Point3<f64>>],
        options: &FitOptions,
    ) -> Result<SkinFitReport> {
        if targets.len() != grid.markers.len() {
            return Err(Error::invalid(
                "fit targets",
                targets.len(),
                format!("{} points", grid.markers.len()),
            ));
        }
        let before = grid.positions(&self.vertices, &self.triangles);
        let (mean_before, max_before, points) = errors(&before, targets);
        let tracked: Vec<(Point3<f64>, Vector3<f64>)> = before
            .iter()
            .zip(targets)
            .filter_map(|(m, t)| t.map(|t| (*m, t - m)))
            .collect();
        let sigma = options.spread * grid.row_spacing.min(grid.col_spacing);
        let phi = |r2: f64| (-0.5 * r2 / (sigma * sigma)).exp();
        // Gaussian RBF interpolation of the displacements: Phi c = delta (SPD for distinct
        // centres; a tiny ridge keeps it well conditioned).
        let m = tracked.len();
        let mut a = DMatrix::<f64>::zeros(m, m);
        for i in 0..m {
            for j in 0..m {
                a[(i, j)] = phi((tracked[i].0 - tracked[j].0).norm_squared())
                    + if i == j { 1e-9 } else { 0.0 };
            }
        }
        let chol = a
            .cholesky()
            .ok_or_else(|| Error::State("skin fitting: coincident grid points".into()))?;
        let mut rhs = DMatrix::<f64>::zeros(m, 3);
        for (i, (_, d)) in tracked.iter().enumerate() {
            for k in 0..3 {
                rhs[(i, k)] = d[k];
            }
        }
        let coef = chol.solve(&rhs);
        let reach2 = (4.0 * sigma).powi(2);
        let mut movable = vec![false; self.vertices.len()];
        for (vi, v) in self.vertices.iter_mut().enumerate() {
            let mut d = Vector3::zeros();
            let mut near = false;
            for (i, (c, _)) in tracked.iter().enumerate() {
                let r2 = (*v - c).norm_squared();
                if r2 < reach2 {
                    near = true;
                    let w = phi(r2);
                    d += Vector3::new(coef[(i, 0)], coef[(i, 1)], coef[(i, 2)]) * w;
                }
            }
            if near {
                *v += d;
                movable[vi] = true;
            }
        }
        let nb = vertex_neighbours(self.vertices.len(), &self.triangles);
        taubin_smooth(
            &mut self.vertices,
            &nb,
            &movable,
            options.lambda,
            options.mu,
            options.iterations,
        );
        let after = grid.positions(&self.vertices, &self.triangles);
        let (mean_after, max_after, _) = errors(&after, targets);
        Ok(SkinFitReport {
            points,
            mean_before,
            max_before,
            mean_after,
            max_after,
        })
    }
}
