//! Ordinary least squares by Householder QR, the classical covariance and the F test of
//! nested models. Small dense problems (a handful of columns), so nalgebra's QR is used as
//! is.

use super::special::f_sf;
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector};
use serde::Serialize;

/// A least-squares fit y = X theta + e.
#[derive(Debug, Clone)]
pub struct OlsFit {
    /// Coefficients theta.
    pub coef: Vec<f64>,
    /// (X'X)^-1.
    pub xtx_inv: DMatrix<f64>,
    /// Residual sum of squares.
    pub rss: f64,
    /// Residuals y - X theta.
    pub residuals: Vec<f64>,
    /// Number of observations.
    pub n: usize,
    /// Number of columns.
    pub p: usize,
}

impl OlsFit {
    /// Residual variance RSS / (n - p).
    pub fn sigma2(&self) -> f64 {
        self.rss / (self.n - self.p) as f64
    }

    /// Classical covariance sigma^2 (X'X)^-1.
    pub fn covariance(&self) -> DMatrix<f64> {
        &self.xtx_inv * self.sigma2()
    }
}

/// Least squares of `y` on the columns of `x` (n x p, n > p, full column rank).
pub fn ols(x: &DMatrix<f64>, y: &[f64]) -> Result<OlsFit> {
    let (n, p) = x.shape();
    if y.len() != n {
        return Err(Error::invalid(
            "response length",
            y.len(),
            format!("{n} (rows of the design)"),
        ));
    }
    if n <= p {
        return Err(Error::invalid(
            "number of observations",
            n,
            format!("more than {p} parameters"),
        ));
    }
    let qr = x.clone().qr();
    let r = qr.r();
    let rmax = (0..p).map(|i| r[(i, i)].abs()).fold(0.0, f64::max);
    if (0..p).any(|i| r[(i, i)].abs() <= 1e-12 * rmax) || rmax == 0.0 {
        return Err(Error::Numerical {
            time: 0.0,
            reason: "design matrix is rank deficient".into(),
        });
    }
    let mut qty = DVector::from_column_slice(y);
    qr.q_tr_mul(&mut qty);
    let rp = r.view((0, 0), (p, p)).into_owned();
    let coef = rp
        .solve_upper_triangular(&qty.rows(0, p).into_owned())
        .ok_or_else(|| Error::Numerical {
            time: 0.0,
            reason: "singular R in least squares".into(),
        })?;
    let rinv = rp
        .solve_upper_triangular(&DMatrix::identity(p, p))
        .ok_or_else(|| Error::Numerical {
            time: 0.0,
            reason: "singular R in least squares".into(),
        })?;
    let xtx_inv = &rinv * rinv.transpose();
    let fitted = x * &coef;
    let residuals: Vec<f64> = y.iter().zip(fitted.iter()).map(|(a, b)| a - b).collect();
    let rss = residuals.iter().map(|e| e * e).sum();
    Ok(OlsFit {
        coef: coef.as_slice().to_vec(),
        xtx_inv,
        rss,
        residuals,
        n,
        p,
    })
}

/// An F test result.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FTest {
    /// F statistic.
    pub f: f64,
    /// Numerator degrees of freedom.
    pub df_num: f64,
    /// Denominator degrees of freedom.
    pub df_den: f64,
    /// P(F > f).
    pub p_value: f64,
}

impl FTest {
    /// Builds the test and its p-value.
    pub fn new(f: f64, df_num: f64, df_den: f64) -> Self {
        FTest {
            f,
            df_num,
            df_den,
            p_value: f_sf(f, df_num, df_den),
        }
    }

    /// Extra-sum-of-squares F test of a restricted model (RSS `rss_r`) against a full one
    /// (`rss_f` on `df_f` residual degrees of freedom) with `q` restrictions.
    pub fn extra_sum_of_squares(rss_r: f64, rss_f: f64, q: usize, df_f: usize) -> Self {
        FTest::new(
            ((rss_r - rss_f) / q as f64) / (rss_f / df_f as f64),
            q as f64,
            df_f as f64,
        )
    }
}
