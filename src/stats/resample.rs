//! Polyphase rational resampling (thesis 4.2: the 100 Hz spirogram brought to the 56 Hz of
//! SLP and the simulation, ratio 14/25).
//!
//! The filter and the edge handling reproduce the defaults of SciPy's
//! `signal.resample_poly(x, up, down)` (window `('kaiser', 5.0)`, `padtype='constant'`), so
//! that results can be cross-checked sample by sample:
//! - FIR low-pass designed by the window method: `2 L + 1` taps with `L = 10 max(up, down)`,
//!   cutoff `1 / max(up, down)` of the Nyquist frequency of the upsampled signal,
//!   `h[m] = sinc(f_c (m - L)) w[m]` with the Kaiser window of beta 5, normalised to unit DC
//!   gain and multiplied by `up`;
//! - the filter is zero-padded in front by `down - L mod down` taps and the first
//!   `(L + pad) / down` outputs of the full polyphase convolution are dropped, which makes
//!   the filter zero-phase; the input is zero outside its support;
//! - `ceil(n up / down)` samples are returned.

use super::special::bessel_i0;
use crate::{Error, Result};

/// Greatest common divisor (Euclid), which reduces resampling ratios.
pub(crate) fn gcd(a: usize, b: usize) -> usize {
    if b == 0 { a } else { gcd(b, a % b) }
}

/// Kaiser window of `n` points and shape `beta`, symmetric (SciPy `fftbins=False`).
pub fn kaiser_window(n: usize, beta: f64) -> Vec<f64> {
    if n == 1 {
        return vec![1.0];
    }
    let denom = bessel_i0(beta);
    let half = (n - 1) as f64;
    (0..n)
        .map(|i| {
            let r = 2.0 * i as f64 / half - 1.0;
            bessel_i0(beta * (1.0 - r * r).max(0.0).sqrt()) / denom
        })
        .collect()
}

/// The anti-aliasing filter of [`resample_poly`] (already multiplied by `up`), for the
/// reduced ratio `up / down`.
pub fn design_filter(up: usize, down: usize) -> Vec<f64> {
    let max_rate = up.max(down);
    let fc = 1.0 / max_rate as f64;
    let half_len = 10 * max_rate;
    let n = 2 * half_len + 1;
    let w = kaiser_window(n, 5.0);
    let mut h: Vec<f64> = (0..n)
        .map(|i| {
            let m = i as f64 - half_len as f64;
            let x = fc * m;
            let sinc = if x == 0.0 {
                1.0
            } else {
                (std::f64::consts::PI * x).sin() / (std::f64::consts::PI * x)
            };
            fc * sinc * w[i]
        })
        .collect();
    let s: f64 = h.iter().sum();
    for v in &mut h {
        *v = *v / s * up as f64;
    }
    h
}

/// Resamples `x` by the rational factor `up / down` (reduced by their gcd first); see the
/// module documentation for the exact filter. Returns `ceil(len up / down)` samples.
pub fn resample_poly(x: &[f64], up: usize, down: usize) -> Result<Vec<f64>> {
    if up == 0 || down == 0 {
        return Err(Error::invalid(
            "up/down",
            format!("{up}/{down}"),
            "positive integers",
        ));
    }
    let g = gcd(up, down);
    let (up, down) = (up / g, down / g);
    if up == 1 && down == 1 {
        return Ok(x.to_vec());
    }
    let n_in = x.len();
    let n_out = (n_in * up).div_ceil(down);
    let h0 = design_filter(up, down);
    let half_len = 10 * up.max(down);
    let n_pre_pad = down - half_len % down;
    let n_pre_remove = (half_len + n_pre_pad) / down;
    // Padded filter: n_pre_pad zeros then h0.
    let len_h = h0.len() + n_pre_pad;
    let mut out = Vec::with_capacity(n_out);
    for i in 0..n_out {
        // Full convolution index of this output sample.
        let m = (i + n_pre_remove) * down;
        // Input samples j with 0 <= m - j up < len_h.
        let j_max = (m / up).min(n_in.saturating_sub(1));
        let j_min = if m + 1 > len_h {
            (m + 1 - len_h).div_ceil(up)
        } else {
            0
        };
        let mut acc = 0.0;
        if n_in > 0 && j_min <= j_max {
            for (j, xj) in x.iter().enumerate().take(j_max + 1).skip(j_min) {
                let k = m - j * up;
                if k >= n_pre_pad {
                    acc += h0[k - n_pre_pad] * xj;
                }
            }
        }
        out.push(acc);
    }
    Ok(out)
}

/// Rational approximation `up / down` of `to_rate / from_rate`. Rates that are whole
/// numbers of hertz (within 1e-6 relative, so time stamps rounded to microseconds still
/// qualify) give the exact reduced ratio (100 -> 56 Hz is
/// 14/25); otherwise the best continued-fraction convergent with `down <= 1000`.
pub fn rate_ratio(from_rate: f64, to_rate: f64) -> Result<(usize, usize)> {
    if !(from_rate > 0.0 && from_rate.is_finite()) {
        return Err(Error::invalid(
            "source sampling rate [Hz]",
            from_rate,
            "(0, inf)",
        ));
    }
    if !(to_rate > 0.0 && to_rate.is_finite()) {
        return Err(Error::invalid(
            "target sampling rate [Hz]",
            to_rate,
            "(0, inf)",
        ));
    }
    let is_int = |r: f64| (r - r.round()).abs() <= 1e-6 * r && r.round() >= 1.0;
    if is_int(from_rate) && is_int(to_rate) && to_rate.round() <= 1e6 && from_rate.round() <= 1e6 {
        let (a, b) = (to_rate.round() as usize, from_rate.round() as usize);
        let g = gcd(a, b);
        return Ok((a / g, b / g));
    }
    // Continued fraction of r = to/from.
    let r = to_rate / from_rate;
    let (mut p0, mut q0, mut p1, mut q1) = (0u64, 1u64, 1u64, 0u64);
    let mut x = r;
    let mut best = (r.round().max(1.0) as u64, 1u64);
    for _ in 0..40 {
        let a = x.floor();
        let (p2, q2) = (a as u64 * p1 + p0, a as u64 * q1 + q0);
        if q2 > 1000 {
            break;
        }
        best = (p2, q2);
        if (p2 as f64 / q2 as f64 - r).abs() < 1e-12 * r {
            break;
        }
        (p0, q0, p1, q1) = (p1, q1, p2, q2);
        let frac = x - a;
        if frac < 1e-12 {
            break;
        }
        x = 1.0 / frac;
    }
    if best.0 == 0 {
        return Err(Error::invalid("rate ratio", r, "at least 1/1000"));
    }
    Ok((best.0 as usize, best.1 as usize))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ratio_of_spirometry_to_slp() {
        assert_eq!(rate_ratio(100.0, 56.0).unwrap(), (14, 25));
        assert_eq!(rate_ratio(56.0, 100.0).unwrap(), (25, 14));
        let (u, d) = rate_ratio(100.0, 55.5).unwrap();
        assert_eq!((u, d), (111, 200));
        // Time stamps rounded to 6 decimals at 56 Hz.
        assert_eq!(rate_ratio(100.0, 999.0 / 17.839286).unwrap(), (14, 25));
    }

    #[test]
    fn constant_is_preserved_inside() {
        let x = vec![2.0; 400];
        let y = resample_poly(&x, 14, 25).unwrap();
        assert_eq!(y.len(), 224);
        // Far from the edges the unit-DC-gain filter returns the constant.
        for v in &y[40..180] {
            assert!((v - 2.0).abs() < 1e-3, "{v}");
        }
    }

    #[test]
    fn low_frequency_sine_survives() {
        let fs = 100.0;
        let x: Vec<f64> = (0..1000)
            .map(|i| (2.0 * std::f64::consts::PI * 0.25 * i as f64 / fs).sin())
            .collect();
        let y = resample_poly(&x, 14, 25).unwrap();
        for (j, v) in y.iter().enumerate().skip(50).take(450) {
            let t = j as f64 / 56.0;
            assert!((v - (2.0 * std::f64::consts::PI * 0.25 * t).sin()).abs() < 1e-3);
        }
    }
}
