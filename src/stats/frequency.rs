//! Breathing-frequency estimation from a sampled signal (lung volume, marker depth).
//!
//! Method (reference "Frequency of breathing"; Quinn 1994 / Jain et al. 1979 for the
//! interpolation): remove the least-squares linear trend, apply a Hann window, take the
//! DFT bins covering the breathing band 0.1-1 Hz, pick the largest, and refine with the
//! two-bin Hann interpolation `delta = (2a - 1) / (a + 1)`, `a = |X[k +- 1]| / |X[k]|` taken
//! toward the larger neighbour (exact for a pure tone between bins), `f = (k + delta) fs / N`.
//! The autocorrelation of the detrended signal (the first local maximum at lags of 1-10 s
//! reaching 90 % of the largest one) is the cross-check: when the two disagree by more than 10 % (a non-sinusoidal breath whose
//! harmonic dominates the spectrum, for example) the autocorrelation value is used.
//!
//! Only the band's bins are evaluated (direct sums, O(N x bins)), so no FFT library is
//! needed and long recordings stay cheap.

use crate::{Error, Result};
use serde::Serialize;
use std::f64::consts::PI;

/// Lower edge of the breathing band searched [Hz].
pub const BAND_LOW_HZ: f64 = 0.1;
/// Upper edge of the breathing band searched [Hz].
pub const BAND_HIGH_HZ: f64 = 1.0;

/// Result of [`estimate_frequency`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrequencyEstimate {
    /// The frequency to use [Hz] (spectral unless the cross-check overruled it).
    pub frequency_hz: f64,
    /// Spectral estimate with the Hann two-bin interpolation [Hz].
    pub spectral_hz: f64,
    /// Autocorrelation estimate [Hz], when a peak was found at 1-10 s lags.
    pub autocorrelation_hz: Option<f64>,
    /// True when the chosen value is the autocorrelation one.
    pub from_autocorrelation: bool,
    /// Interpolation offset delta in bins, in [-1, 1].
    pub bin_offset: f64,
}

/// Removes the least-squares straight line from `x` (sample index as abscissa).
pub fn detrend_linear(x: &[f64]) -> Vec<f64> {
    let n = x.len() as f64;
    if x.len() < 2 {
        return vec![0.0; x.len()];
    }
    let tm = (n - 1.0) / 2.0;
    let ym = x.iter().sum::<f64>() / n;
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (i, v) in x.iter().enumerate() {
        let d = i as f64 - tm;
        sxy += d * (v - ym);
        sxx += d * d;
    }
    let b = sxy / sxx;
    x.iter()
        .enumerate()
        .map(|(i, v)| v - ym - b * (i as f64 - tm))
        .collect()
}

/// Magnitude of DFT bin `k` of `x`.
fn dft_magnitude(x: &[f64], k: usize) -> f64 {
    let n = x.len() as f64;
    let w = 2.0 * PI * k as f64 / n;
    // Rotating phasor recurrence, re-seeded every 256 samples to bound the drift.
    let (mut re, mut im) = (0.0, 0.0);
    let (sw, cw) = w.sin_cos();
    let (mut c, mut s) = (1.0f64, 0.0f64);
    for (i, v) in x.iter().enumerate() {
        if i % 256 == 0 {
            let (si, ci) = (w * i as f64).sin_cos();
            c = ci;
            s = si;
        }
        re += v * c;
        im -= v * s;
        let c2 = c * cw - s * sw;
        s = s * cw + c * sw;
        c = c2;
    }
    (re * re + im * im).sqrt()
}

/// Frequency [Hz] from the autocorrelation at lags 1-10 s: the first positive local maximum
/// reaching 90 % of the largest one (so that a strong second harmonic's half-period peak is
/// passed over), refined by parabolic interpolation; `None` when no positive peak exists.
pub fn autocorrelation_frequency(x: &[f64], fs: f64) -> Option<f64> {
    let n = x.len();
    let lo = (fs).floor().max(1.0) as usize;
    let hi = ((10.0 * fs).ceil() as usize).min(n.saturating_sub(2));
    if hi <= lo + 1 {
        return None;
    }
    let r0: f64 = x.iter().map(|v| v * v).sum();
    if r0 <= 0.0 {
        return None;
    }
    let ac = |lag: usize| -> f64 {
        x[..n - lag]
            .iter()
            .zip(&x[lag..])
            .map(|(a, b)| a * b)
            .sum::<f64>()
            / r0
    };
    let vals: Vec<f64> = (lo - 1..=hi + 1).map(ac).collect();
    let peaks: Vec<usize> = (1..vals.len() - 1)
        .filter(|&i| vals[i] > 0.0 && vals[i] >= vals[i - 1] && vals[i] > vals[i + 1])
        .collect();
    let top = peaks
        .iter()
        .map(|&i| vals[i])
        .fold(f64::NEG_INFINITY, f64::max);
    if let Some(&i) = peaks.iter().find(|&&i| vals[i] >= 0.9 * top) {
        let (a, b, c) = (vals[i - 1], vals[i], vals[i + 1]);
        let denom = a - 2.0 * b + c;
        let shift = if denom.abs() > 0.0 {
            0.5 * (a - c) / denom
        } else {
            0.0
        };
        let lag = (lo - 1 + i) as f64 + shift;
        return Some(fs / lag);
    }
    None
}

/// Estimates the breathing frequency of `samples` taken at `fs` Hz (see the module doc).
///
/// Errors when `fs` is not positive or not finite, a sample is not finite, there are fewer
/// than 16 samples, or the signal has no energy in the band (constant or a pure trend).
pub fn estimate_frequency(samples: &[f64], fs: f64) -> Result<FrequencyEstimate> {
    if !(fs > 0.0 && fs.is_finite()) {
        return Err(Error::invalid("sampling rate [Hz]", fs, "(0, inf)"));
    }
    let n = samples.len();
    if n < 16 {
        return Err(Error::invalid("number of samples", n, "at least 16"));
    }
    if let Some(bad) = samples.iter().position(|v| !v.is_finite()) {
        return Err(Error::invalid(
            format!("sample {bad}"),
            samples[bad],
            "finite",
        ));
    }
    let x = detrend_linear(samples);
    let nf = n as f64;
    let windowed: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(i, v)| v * 0.5 * (1.0 - (2.0 * PI * i as f64 / nf).cos()))
        .collect();
    let k_lo = ((BAND_LOW_HZ * nf / fs).floor() as usize).max(1);
    let k_hi = ((BAND_HIGH_HZ * nf / fs).ceil() as usize)
        .min(n / 2 - 1)
        .max(k_lo);
    let mags: Vec<f64> = (k_lo - 1..=k_hi + 1)
        .map(|k| dft_magnitude(&windowed, k))
        .collect();
    let mut best = 1;
    for i in 1..mags.len() - 1 {
        if mags[i] > mags[best] {
            best = i;
        }
    }
    if mags[best] <= 0.0 {
        return Err(Error::invalid(
            "signal",
            "constant",
            "a signal varying in the 0.1-1 Hz band",
        ));
    }
    let k = k_lo - 1 + best;
    let (left, right) = (mags[best - 1], mags[best + 1]);
    let delta = if right >= left {
        let a = right / mags[best];
        (2.0 * a - 1.0) / (a + 1.0)
    } else {
        let a = left / mags[best];
        -(2.0 * a - 1.0) / (a + 1.0)
    };
    let delta = delta.clamp(-1.0, 1.0);
    let spectral = (k as f64 + delta) * fs / nf;
    let acf = autocorrelation_frequency(&x, fs);
    let from_acf = matches!(acf, Some(fa) if (spectral - fa).abs() > 0.1 * fa);
    Ok(FrequencyEstimate {
        frequency_hz: if from_acf {
            acf.unwrap_or(spectral)
        } else {
            spectral
        },
        spectral_hz: spectral,
        autocorrelation_hz: acf,
        from_autocorrelation: from_acf,
        bin_offset: delta,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn pure_tone_between_bins_is_exact() {
        let fs = 56.0;
        let f0 = 0.2731;
        let x: Vec<f64> = (0..1000)
            .map(|i| 1.0 + 0.4 * (2.0 * PI * f0 * i as f64 / fs + 0.3).sin())
            .collect();
        let est = estimate_frequency(&x, fs).unwrap();
        // Leakage from the negative-frequency image bounds the error for a short record.
        assert!((est.spectral_hz - f0).abs() < 2e-3, "{est:?}");
        assert!(!est.from_autocorrelation);
        let fa = est.autocorrelation_hz.unwrap();
        assert!((fa - f0).abs() < 0.02 * f0, "{fa}");
    }

    #[test]
    fn harmonic_dominated_breath_uses_autocorrelation() {
        let fs = 50.0;
        let f0 = 0.2;
        let x: Vec<f64> = (0..3000)
            .map(|i| {
                let p = 2.0 * PI * f0 * i as f64 / fs;
                0.3 * p.sin() + 1.0 * (2.0 * p).sin()
            })
            .collect();
        let est = estimate_frequency(&x, fs).unwrap();
        assert!((est.spectral_hz - 0.4).abs() < 0.01);
        assert!(est.from_autocorrelation);
        assert!((est.frequency_hz - f0).abs() < 0.01, "{est:?}");
    }

    #[test]
    fn rejects_bad_input() {
        assert!(estimate_frequency(&[1.0; 10], 56.0).is_err());
        assert!(estimate_frequency(&[1.0; 100], 0.0).is_err());
        assert!(estimate_frequency(&[1.0; 100], 56.0).is_err());
    }
}
