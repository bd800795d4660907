//! Synthetic spirometry for tests and demonstrations: the volume a spirometer would record
//! from a known lung-volume curve (a model run, or any CSV curve) or from a sinusoidal
//! breathing model, with the errors real recordings carry: white measurement noise, a
//! linear volume drift (a flow-sensor zero offset), a start-time offset (the recordings are
//! triggered by hand, thesis 4.2), a scale (calibration) error, and a start at zero volume.
//!
//! Recorded volume at sample `i`, time `t_i = i / rate`:
//! `V_spiro(t_i) = scale (V(t0 + offset + t_i) - V(t0 + offset)) + drift t_i + noise_i`.
//! As flow, the derivative of the same (central differences) plus `drift` plus noise.

use super::io::Series;
use super::prepare::SpiroKind;
use crate::numeric::rng::Pcg64;
use crate::{Error, Result};
use std::f64::consts::PI;

/// Where the true lung volume comes from.
#[derive(Debug, Clone)]
pub enum VolumeSource {
    /// A sampled curve (time [s], volume [L]), e.g. a simulation's lung volume.
    Curve(Series),
    /// `V(t) = base + (Vt/2) (1 - cos(2 pi f t + phase)) + h2 (Vt/2) sin(4 pi f t + phase)`.
    Sine {
        /// Breathing frequency [Hz].
        frequency_hz: f64,
        /// Tidal volume Vt [L].
        tidal_volume_l: f64,
        /// Relative amplitude of a second harmonic (0 for a pure sinusoid).
        harmonic2: f64,
        /// Phase [rad].
        phase: f64,
        /// Functional residual capacity added [L] (the spirometer does not see it).
        base_l: f64,
        /// Record length [s].
        duration_s: f64,
    },
}

/// Recording errors and format of the synthetic spirogram.
#[derive(Debug, Clone, Copy)]
pub struct SpiroSynthOptions {
    /// Sampling rate [Hz] (spirometers: 100).
    pub rate_hz: f64,
    /// Standard deviation of white noise [L, or L/s for flow].
    pub noise_sd: f64,
    /// Linear volume drift [L/s].
    pub drift_l_per_s: f64,
    /// Start of the spirometer record on the source's clock, after its first sample [s].
    pub start_offset_s: f64,
    /// Multiplicative calibration error (1 = none).
    pub scale: f64,
    /// Volume or flow output.
    pub output: SpiroKind,
    /// Noise seed.
    pub seed: u64,
}

impl Default for SpiroSynthOptions {
    fn default() -> Self {
        SpiroSynthOptions {
            rate_hz: 100.0,
            noise_sd: 0.0,
            drift_l_per_s: 0.0,
            start_offset_s: 0.0,
            scale: 1.0,
            output: SpiroKind::Volume,
            seed: 1,
        }
    }
}

fn check(name: &str, v: f64, ok: bool, range: &str) -> Result<()> {
    if ok && v.is_finite() {
        Ok(())
    } else {
        Err(Error::invalid(name, v, range))
    }
}

/// Catmull-Rom interpolation of uniformly sampled `v` at fractional index `x`.
fn catmull_rom(v: &[f64], x: f64) -> f64 {
    let n = v.len();
    let k = (x.floor().max(0.0) as usize).min(n - 2);
    let f = x - k as f64;
    let at = |i: isize| v[i.clamp(0, n as isize - 1) as usize];
    let (p0, p1, p2, p3) = (
        at(k as isize - 1),
        at(k as isize),
        at(k as isize + 1),
        at(k as isize + 2),
    );
    p1 + 0.5
        * f
        * (p2 - p0 + f * (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3 + f * (3.0 * (p1 - p2) + p3 - p0)))
}

/// Generates a spirogram (see the module doc). The result's column is `volume` or `flow`.
pub fn synth_spirometry(source: &VolumeSource, opts: &SpiroSynthOptions) -> Result<Series> {
    check(
        "rate [Hz]",
        opts.rate_hz,
        opts.rate_hz > 0.0 && opts.rate_hz <= 10_000.0,
        "(0, 10000]",
    )?;
    check("noise [L]", opts.noise_sd, opts.noise_sd >= 0.0, "[0, inf)")?;
    check("drift [L/s]", opts.drift_l_per_s, true, "finite")?;
    check("scale", opts.scale, opts.scale > 0.0, "(0, inf)")?;
    check("start offset [s]", opts.start_offset_s, true, "finite")?;
    let fs = opts.rate_hz;
    // True volume on the spirometer's clock.
    let truth: Vec<f64> = match source {
        VolumeSource::Sine {
            frequency_hz,
            tidal_volume_l,
            harmonic2,
            phase,
            base_l,
            duration_s,
        } => {
            check(
                "frequency [Hz]",
                *frequency_hz,
                *frequency_hz > 0.0,
                "(0, inf)",
            )?;
            check(
                "duration [s]",
                *duration_s,
                *duration_s > 0.0 && *duration_s * fs < 1e8,
                "(0, 1e8 / rate)",
            )?;
            let n = (duration_s * fs).round() as usize;
            (0..n)
                .map(|i| {
                    let t = opts.start_offset_s + i as f64 / fs;
                    let a = 2.0 * PI * frequency_hz * t + phase;
                    base_l
                        + 0.5 * tidal_volume_l * (1.0 - a.cos())
                        + harmonic2 * 0.5 * tidal_volume_l * (2.0 * a).sin()
                })
                .collect()
        }
        VolumeSource::Curve(s) => {
            if s.len() < 16 {
                return Err(Error::invalid(
                    "source curve samples",
                    s.len(),
                    "at least 16",
                ));
            }
            check(
                "start offset [s]",
                opts.start_offset_s,
                opts.start_offset_s >= 0.0,
                "[0, curve duration) for a curve source",
            )?;
            // Catmull-Rom cubic interpolation on the source's uniform grid (no filter edge
            // transients; error O(h^4) on smooth curves).
            let src_dt = 1.0 / s.rate();
            let span = s.time[s.len() - 1] - s.time[0];
            let n_out = ((span - opts.start_offset_s) * fs).floor();
            if n_out < 16.0 {
                return Err(Error::invalid(
                    "start offset [s]",
                    opts.start_offset_s,
                    "leaving at least 16 samples of the curve",
                ));
            }
            (0..n_out as usize)
                .map(|i| catmull_rom(&s.values, (opts.start_offset_s + i as f64 / fs) / src_dt))
                .collect()
        }
    };
    let v0 = truth[0];
    let n = truth.len();
    let time: Vec<f64> = (0..n).map(|i| i as f64 / fs).collect();
    let mut rng = Pcg64::new(opts.seed, 11);
    let values: Vec<f64> = match opts.output {
        SpiroKind::Volume => (0..n)
            .map(|i| {
                opts.scale * (truth[i] - v0)
                    + opts.drift_l_per_s * time[i]
                    + opts.noise_sd * rng.normal()
            })
            .collect(),
        SpiroKind::Flow => (0..n)
            .map(|i| {
                let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
                let dv = (truth[b] - truth[a]) / (time[b] - time[a]);
                opts.scale * dv + opts.drift_l_per_s + opts.noise_sd * rng.normal()
            })
            .collect(),
    };
    let column = match opts.output {
        SpiroKind::Volume => "volume",
        SpiroKind::Flow => "flow",
    };
    Ok(Series {
        time,
        values,
        column: column.to_string(),
        source: format!("synthetic {column} spirogram"),
    })
}
