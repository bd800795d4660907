//! Slow drift of each marker as a nuisance of the fit's cost, solved in closed form at each
//! evaluation (variable projection: the drift is linear given the drive, so it is
//! eliminated by least squares and the search runs over the drive alone; Golub & Pereyra
//! 2003, "Separable nonlinear least squares: the variable projection method and its
//! applications", Inverse Problems 19:R1).
//!
//! The drift of each marker coordinate is a linear spline in time (hat functions) with its
//! knots at least [`KNOT_BREATHS`] breaths apart, from the first frame to the last: slow
//! enough that it cannot absorb a change of end-expiratory volume within a few breaths, or
//! the breath itself. Its constant part is the marker's offset, so a cost with drift also
//! compares each marker about its own mean. For each marker coordinate the residual of the
//! recording minus the model is projected onto the complement of the spline's span over the
//! frames where the marker is tracked (a K x K normal-equation solve, K the number of knots).

use nalgebra::{DMatrix, DVector, Point3, Vector3};

/// Least spacing of the drift spline's knots [breaths] (the three breaths).
pub const KNOT_BREATHS: f64 = 3.0;

/// The drift spline over a recording's frames.
#[derive(Clone, Debug, PartialEq)]
pub struct DriftBasis {
    /// Knot times [s] (first frame to last).
    pub knots: Vec<f64>,
    /// Per frame: the two (knot index, weight) pairs of its hat functions.
    weights: Vec<[(usize, f64); 2]>,
}

impl DriftBasis {
    /// The spline over `times` (from the recording's first frame) for breathing at
    /// `frequency` Hz: the most knots whose spacing is at least [`KNOT_BREATHS`] breaths, at
    /// least two (a linear drift).
    pub fn new(times: &[f64], frequency: f64) -> DriftBasis {
        let (t0, t1) = (
            times.first().copied().unwrap_or(0.0),
            times.last().copied().unwrap_or(0.0),
        );
        let span = (t1 - t0).max(0.0);
        let intervals = ((span * frequency / KNOT_BREATHS).floor() as usize).max(1);
        let knots: Vec<f64> = (0..=intervals)
            .map(|k| t0 + span * k as f64 / intervals as f64)
            .collect();
        let h = span / intervals as f64;
        let weights = times
            .iter()
            .map(|&t| {
                if h <= 0.0 {
                    return [(0, 1.0), (0, 0.0)];
                }
                let x = ((t - t0) / h).clamp(0.0, intervals as f64);
                let j = (x.floor() as usize).min(intervals - 1);
                let w = x - j as f64;
                [(j, 1.0 - w), (j + 1, w)]
            })
            .collect();
        DriftBasis { knots, weights }
    }

    /// Number of basis functions (knots).
    pub fn len(&self) -> usize {
        self.knots.len()
    }

    /// Whether the basis is empty (never: at least two knots).
    pub fn is_empty(&self) -> bool {
        self.knots.is_empty()
    }

    /// The drift of one marker coordinate fitted to `residual` (per frame, `None` where the
    /// marker is not tracked) by least squares, evaluated at every frame (NaN-free; zero
    /// when fewer samples than knots are tracked).
    fn fit_one(&self, residual: &[Option<f64>]) -> Vec<f64> {
        let k = self.len();
        let mut ata = DMatrix::<f64>::zeros(k, k);
        let mut atb = DVector::<f64>::zeros(k);
        let mut n = 0;
        for (w, r) in self.weights.iter().zip(residual) {
            if let Some(r) = r {
                n += 1;
                for &(i, a) in w {
                    atb[i] += a * r;
                    for &(j, b) in w {
                        ata[(i, j)] += a * b;
                    }
                }
            }
        }
        let ridge = 1e-12 * ata.trace().max(1e-300);
        for i in 0..k {
            ata[(i, i)] += ridge;
        }
        let c = if n >= k {
            ata.cholesky()
                .map(|ch| ch.solve(&atb))
                .unwrap_or_else(|| DVector::zeros(k))
        } else {
            DVector::zeros(k)
        };
        self.weights
            .iter()
            .map(|w| w.iter().map(|&(i, a)| a * c[i]).sum())
            .collect()
    }

    /// The least-squares fit of the spline to one series (per frame, `None` where
    /// missing), at every frame (zero with fewer samples than knots).
    pub fn fit_series(&self, values: &[Option<f64>]) -> Vec<f64> {
        self.fit_one(values)
    }

    /// The drift of every marker fitted to recorded minus model (per frame, per marker),
    /// per frame and marker [m].
    pub fn drift(
        &self,
        model: &[Vec<Point3<f64>>],
        recorded: &[Vec<Option<Point3<f64>>>],
    ) -> Vec<Vec<Vector3<f64>>> {
        let points = recorded.first().map_or(0, Vec::len);
        let mut out = vec![vec![Vector3::zeros(); points]; recorded.len()];
        for p in 0..points {
            for axis in 0..3 {
                let residual: Vec<Option<f64>> = recorded
                    .iter()
                    .zip(model)
                    .map(|(r, m)| r[p].map(|q| q[axis] - m[p][axis]))
                    .collect();
                for (f, d) in self.fit_one(&residual).into_iter().enumerate() {
                    out[f][p][axis] = d;
                }
            }
        }
        out
    }

    /// The cost with drift projected out: the mean Euclidean length of recorded minus model
    /// minus the fitted drift, over every tracked sample.
    pub fn projected_cost(
        &self,
        model: &[Vec<Point3<f64>>],
        recorded: &[Vec<Option<Point3<f64>>>],
    ) -> f64 {
        let drift = self.drift(model, recorded);
        let (mut sum, mut n) = (0.0, 0usize);
        for ((r, m), d) in recorded.iter().zip(model).zip(&drift) {
            for (p, q) in r.iter().enumerate() {
                if let Some(q) = q {
                    sum += (q.coords - m[p].coords - d[p]).norm();
                    n += 1;
                }
            }
        }
        if n == 0 {
            f64::INFINITY
        } else {
            sum / n as f64
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn knots_are_three_breaths_apart_and_a_linear_drift_is_removed() {
        let times: Vec<f64> = (0..=180).map(|k| k as f64 * 0.1).collect();
        let b = DriftBasis::new(&times, 0.25);
        // 18 s at 0.25 Hz: 4.5 breaths, one interval of at least 3 breaths.
        assert_eq!(b.len(), 2);
        let b = DriftBasis::new(&times, 0.5);
        assert_eq!(b.len(), 4);
        let recorded: Vec<Vec<Option<Point3<f64>>>> = times
            .iter()
            .map(|t| vec![Some(Point3::new(0.001 * t, 0.0, 0.0))])
            .collect();
        let model = vec![vec![Point3::origin()]; times.len()];
        assert!(b.projected_cost(&model, &recorded) < 1e-12);
    }
}
