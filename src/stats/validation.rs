//! The whole comparison of a simulated lung volume with a spirogram (thesis chapter 4):
//! preparation, frequency, correlation, Bland-Altman on samples and on breaths, cosinor fits
//! and equality tests, BARS fits and equality test; and the outputs (JSON, CSV, plots,
//! Markdown summary).

use super::agreement::{BlandAltman, Pearson, bland_altman, pearson};
use super::autoreg::ArGlsConfig;
use super::bars::{BarsConfig, BarsEquality, BarsFit, bars_equality, bars_fit_on_stream};
use super::breaths::{Breath, BreathDetector, pair_breaths, segment_breaths};
use super::cosinor::{CosinorEquality, CosinorFit, compare_cosinor, fit_cosinor};
use super::frequency::{FrequencyEstimate, estimate_frequency};
use super::io::{Series, write_csv};
use super::plot::{BLUE, Band, DARK, HLine, Mark, ORANGE, Panel, RED, Trace, write_figure};
use super::prepare::{PrepareOptions, Prepared, SpiroKind, check_not_flat, clock_overlap, prepare};
use crate::{Error, Result};
use serde::Serialize;
use std::path::Path;

/// Options of [`validate`].
#[derive(Debug, Clone, Copy, Serialize)]
pub struct ValidationOptions {
    /// Data preparation.
    pub prepare: PrepareOptions,
    /// Number of cosinor harmonics C (thesis: 4).
    pub harmonics: usize,
    /// Settings of the robust cosinor equality test (AR errors, bootstrap).
    pub robust: ArGlsConfig,
    /// BARS settings (the seed drives all three chains).
    pub bars: BarsConfig,
}

impl Default for ValidationOptions {
    fn default() -> Self {
        ValidationOptions {
            prepare: PrepareOptions::default(),
            harmonics: 4,
            robust: ArGlsConfig::default(),
            bars: BarsConfig::default(),
        }
    }
}

/// Breath-level agreement.
#[derive(Debug, Clone, Serialize)]
pub struct BreathAgreement {
    /// Breaths found in the simulation.
    pub sim_breaths: Vec<Breath>,
    /// Breaths found in the spirogram.
    pub spiro_breaths: Vec<Breath>,
    /// Paired breath indices (simulation, spirometry).
    pub pairs: Vec<(usize, usize)>,
    /// Bland-Altman of tidal volumes [L] (None with fewer than 2 pairs).
    pub tidal_volume: Option<BlandAltman>,
    /// Bland-Altman of inspiratory times [s].
    pub ti: Option<BlandAltman>,
    /// Bland-Altman of expiratory times [s].
    pub te: Option<BlandAltman>,
    /// Bland-Altman of total breath times [s].
    pub ttot: Option<BlandAltman>,
    /// Bland-Altman of duty cycles Ti/Ttot.
    pub ti_ttot: Option<BlandAltman>,
    /// Bland-Altman of IE50 (pairs where both are defined).
    pub ie50: Option<BlandAltman>,
}

/// Cosinor results.
#[derive(Debug, Clone, Serialize)]
pub struct CosinorResults {
    /// Fit of the simulation.
    pub sim: CosinorFit,
    /// Fit of the spirogram.
    pub spiro: CosinorFit,
    /// Equality tests.
    pub equality: CosinorEquality,
}

/// BARS results.
#[derive(Debug, Clone, Serialize)]
pub struct BarsResults {
    /// Fit of the simulation.
    pub sim: BarsFit,
    /// Fit of the spirogram.
    pub spiro: BarsFit,
    /// Equality test.
    pub equality: BarsEquality,
}

/// Every statistic of a validation (serialised as the JSON report).
#[derive(Debug, Clone, Serialize)]
pub struct Validation {
    /// Options used.
    pub options: ValidationOptions,
    /// Spirometry column kind.
    pub spiro_kind: SpiroKind,
    /// Prepared data summary.
    pub preparation: Prepared,
    /// Number of aligned samples.
    pub n: usize,
    /// Frequency estimate of the simulation (used for cosinor and breaths).
    pub frequency_sim: FrequencyEstimate,
    /// Frequency estimate of the spirogram.
    pub frequency_spiro: FrequencyEstimate,
    /// Pearson correlation.
    pub pearson: Pearson,
    /// Bland-Altman on samples (simulation - spirometry).
    pub bland_altman: BlandAltman,
    /// Breath-level agreement.
    pub breaths: BreathAgreement,
    /// Cosinor.
    pub cosinor: CosinorResults,
    /// BARS.
    pub bars: BarsResults,
}

/// Bland-Altman of the pairs where both values are finite (None below 2 pairs).
fn ba_opt(a: &[f64], b: &[f64]) -> Option<BlandAltman> {
    let (a, b): (Vec<f64>, Vec<f64>) = a
        .iter()
        .zip(b)
        .filter(|(x, y)| x.is_finite() && y.is_finite())
        .map(|(x, y)| (*x, *y))
        .unzip();
    bland_altman(&a, &b).ok()
}

/// Fewest whole breaths the compared stretch must hold: breaths are segmented and paired,
/// the frequency is estimated and the cosinor fitted on it, none of which means anything
/// on less than two cycles.
pub const MIN_BREATHS: f64 = 2.0;

fn check_two_breaths(
    sim: &Series,
    spiro: &Series,
    overlap_s: f64,
    frequency_hz: f64,
    when: &str,
) -> Result<()> {
    let need = MIN_BREATHS / frequency_hz;
    if overlap_s < need {
        return Err(Error::State(format!(
            "{} and {} overlap for {overlap_s:.2} s {when}, shorter than two breaths at the \
             simulation's {frequency_hz:.3} Hz ({need:.2} s): record the spirogram over the \
             simulated interval",
            sim.source, spiro.source
        )));
    }
    Ok(())
}

/// Runs the validation on a simulation series and a spirometry series.
pub fn validate(
    sim: &Series,
    spiro: &Series,
    kind: SpiroKind,
    opts: &ValidationOptions,
) -> Result<Validation> {
    check_not_flat(sim, "simulation", None)?;
    check_not_flat(spiro, "spirometry", Some(kind))?;
    let (o0, o1) = clock_overlap(sim, spiro)?;
    // Two breaths at the simulation's own frequency must fit in the overlap.
    let f_record = estimate_frequency(&sim.values, sim.rate())?.frequency_hz;
    check_two_breaths(sim, spiro, o1 - o0, f_record, "on their clocks")?;
    let prep = prepare(sim, spiro, kind, &opts.prepare)?;
    let n = prep.time.len();
    if n < 32 {
        return Err(Error::invalid("aligned samples", n, "at least 32"));
    }
    let fs = prep.rate_hz;
    let f_sim = estimate_frequency(&prep.sim, fs)?;
    check_two_breaths(
        sim,
        spiro,
        n as f64 / fs,
        f_sim.frequency_hz,
        &format!("after alignment (lag {} frames)", prep.lag_frames),
    )?;
    let f_spiro = estimate_frequency(&prep.spiro, fs)?;
    let f0 = f_sim.frequency_hz;
    let period = 1.0 / f0;
    let pear = pearson(&prep.sim, &prep.spiro)?;
    let ba = bland_altman(&prep.sim, &prep.spiro)?;
    let det = BreathDetector::for_period(period);
    let bs = segment_breaths(&prep.time, &prep.sim, &det);
    let bp = segment_breaths(&prep.time, &prep.spiro, &det);
    let pairs = pair_breaths(&bs, &bp, 0.5 * period);
    let pick = |f: fn(&Breath) -> f64| -> (Vec<f64>, Vec<f64>) {
        pairs.iter().map(|&(i, j)| (f(&bs[i]), f(&bp[j]))).unzip()
    };
    let (vt_a, vt_b) = pick(|b| b.tidal_volume);
    let (ti_a, ti_b) = pick(|b| b.ti);
    let (te_a, te_b) = pick(|b| b.te);
    let (tt_a, tt_b) = pick(|b| b.ttot);
    let (dc_a, dc_b) = pick(|b| b.ti_ttot);
    let (ie_a, ie_b) = pick(|b| b.ie50);
    let breaths = BreathAgreement {
        tidal_volume: ba_opt(&vt_a, &vt_b),
        ti: ba_opt(&ti_a, &ti_b),
        te: ba_opt(&te_a, &te_b),
        ttot: ba_opt(&tt_a, &tt_b),
        ti_ttot: ba_opt(&dc_a, &dc_b),
        ie50: ba_opt(&ie_a, &ie_b),
        sim_breaths: bs,
        spiro_breaths: bp,
        pairs,
    };
    let c_sim = fit_cosinor(&prep.time, &prep.sim, f0, opts.harmonics)?;
    let c_spiro = fit_cosinor(&prep.time, &prep.spiro, f0, opts.harmonics)?;
    let c_eq = compare_cosinor(
        &prep.time,
        &prep.sim,
        &prep.spiro,
        f0,
        opts.harmonics,
        &opts.robust,
    )?;
    let (t, a, b) = (&prep.time, &prep.sim, &prep.spiro);
    let cfg = &opts.bars;
    let (r_sim, r_spiro, r_eq) = std::thread::scope(|s| {
        let h1 = s.spawn(|| bars_fit_on_stream(t, a, cfg, 0));
        let h2 = s.spawn(|| bars_fit_on_stream(t, b, cfg, 1));
        let eq = bars_equality(t, a, b, cfg);
        let join = |h: std::thread::ScopedJoinHandle<'_, Result<BarsFit>>| {
            h.join()
                .unwrap_or_else(|_| Err(Error::State("BARS worker thread panicked".into())))
        };
        (join(h1), join(h2), eq)
    });
    Ok(Validation {
        options: *opts,
        spiro_kind: kind,
        n,
        frequency_sim: f_sim,
        frequency_spiro: f_spiro,
        pearson: pear,
        bland_altman: ba,
        breaths,
        cosinor: CosinorResults {
            sim: c_sim,
            spiro: c_spiro,
            equality: c_eq,
        },
        bars: BarsResults {
            sim: r_sim?,
            spiro: r_spiro?,
            equality: r_eq?,
        },
        preparation: prep,
    })
}

fn fmt_p(p: f64) -> String {
    if p == 0.0 {
        "< 1e-300".into()
    } else if p < 1e-3 {
        format!("{p:.2e}")
    } else {
        format!("{p:.4}")
    }
}

/// The one-page Markdown summary (layout of the thesis's Table 4.4, plus the rest).
pub fn summary_markdown(v: &Validation) -> String {
    use std::fmt::Write as _;
    let p = &v.preparation;
    let ce = &v.cosinor.equality;
    let be = &v.bars.equality;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Validation of simulated lung volume against spirometry\n"
    );
    let _ = writeln!(
        s,
        "{} aligned samples at {:.3} Hz ({:.1} s); spirometry ({}) at {:.3} Hz resampled by {}/{}; \
         lung ratio {}; lag {} frames ({:+.3} s, correlation {:.4}); spirogram offset {:+.4} L.\n",
        v.n,
        p.rate_hz,
        v.n as f64 / p.rate_hz,
        match v.spiro_kind {
            SpiroKind::Volume => "volume",
            SpiroKind::Flow => "flow, integrated",
        },
        p.spiro_rate_hz,
        p.resample_ratio.0,
        p.resample_ratio.1,
        p.lung_ratio,
        p.lag_frames,
        p.lag_seconds,
        p.max_correlation,
        p.spiro_offset
    );
    if p.lag_at_search_limit {
        let _ = writeln!(
            s,
            "**Warning**: the best lag is at the edge of the +-{} frame search; the true lag may lie outside it.\n",
            v.options.prepare.max_lag
        );
    }
    let _ = writeln!(s, "## Table (as thesis Table 4.4)\n");
    let _ = writeln!(
        s,
        "| BARS P(H0 \\| sim, spir) | COS p-value (with / without intercept) | r(sim, spir) |"
    );
    let _ = writeln!(s, "|---|---|---|");
    let _ = writeln!(
        s,
        "| {} | {} / {} | {:.3} |\n",
        if be.p_h0 > 0.0 {
            fmt_p(be.p_h0)
        } else {
            format!("1e{:.0}", be.log10_p_h0)
        },
        fmt_p(ce.f_with_intercept.p_value),
        fmt_p(ce.f_without_intercept.p_value),
        v.pearson.r
    );
    let _ = writeln!(s, "## Details\n");
    let _ = writeln!(s, "| statistic | value |");
    let _ = writeln!(s, "|---|---|");
    let _ = writeln!(
        s,
        "| breathing frequency sim / spiro [Hz] | {:.4} / {:.4} |",
        v.frequency_sim.frequency_hz, v.frequency_spiro.frequency_hz
    );
    let _ = writeln!(
        s,
        "| Pearson r (95 % CI), p | {:.4} ({:.4}, {:.4}), {} |",
        v.pearson.r,
        v.pearson.ci_low,
        v.pearson.ci_high,
        fmt_p(v.pearson.p_value)
    );
    let ba = &v.bland_altman;
    let _ = writeln!(
        s,
        "| Bland-Altman samples: bias (SE) [L] | {:.4} ({:.4}) |\n| limits of agreement (SE) [L] | {:.4}, {:.4} ({:.4}) |\n| outside limits | {:.1} % |",
        ba.bias,
        ba.bias_se,
        ba.loa_low,
        ba.loa_high,
        ba.loa_se,
        100.0 * ba.fraction_outside
    );
    let b = &v.breaths;
    let _ = writeln!(
        s,
        "| breaths sim / spiro / paired | {} / {} / {} |",
        b.sim_breaths.len(),
        b.spiro_breaths.len(),
        b.pairs.len()
    );
    for (name, x) in [
        ("tidal volume [L]", &b.tidal_volume),
        ("Ti [s]", &b.ti),
        ("Te [s]", &b.te),
        ("Ttot [s]", &b.ttot),
        ("Ti/Ttot", &b.ti_ttot),
        ("IE50", &b.ie50),
    ] {
        if let Some(x) = x {
            let _ = writeln!(
                s,
                "| breaths {name}: bias, limits | {:.4}, [{:.4}, {:.4}] |",
                x.bias, x.loa_low, x.loa_high
            );
        }
    }
    let (cs, cp) = (&v.cosinor.sim, &v.cosinor.spiro);
    let _ = writeln!(
        s,
        "| cosinor C = {} at {:.4} Hz: mesor sim / spiro [L] | {:.4} / {:.4} |",
        cs.harmonics, cs.frequency_hz, cs.mesor, cp.mesor
    );
    let _ = writeln!(
        s,
        "| amplitude 1 sim / spiro [L] | {:.4} ± {:.4} / {:.4} ± {:.4} |",
        cs.components[0].amplitude,
        cs.components[0].amplitude_se,
        cp.components[0].amplitude,
        cp.components[0].amplitude_se
    );
    let _ = writeln!(
        s,
        "| acrophase 1 sim / spiro [rad] | {:.4} ± {:.4} / {:.4} ± {:.4} |",
        cs.components[0].acrophase,
        cs.components[0].acrophase_se,
        cp.components[0].acrophase,
        cp.components[0].acrophase_se
    );
    let _ = writeln!(
        s,
        "| zero-amplitude F sim / spiro | {:.1} (p {}) / {:.1} (p {}) |",
        cs.zero_amplitude.f,
        fmt_p(cs.zero_amplitude.p_value),
        cp.zero_amplitude.f,
        fmt_p(cp.zero_amplitude.p_value)
    );
    for (name, t) in [
        (
            "equality F with intercept (iid errors)",
            &ce.f_with_intercept,
        ),
        (
            "equality F without intercept (iid errors)",
            &ce.f_without_intercept,
        ),
        ("paired F on differences (iid errors)", &ce.paired_f),
    ] {
        let _ = writeln!(
            s,
            "| cosinor {name} | F({:.0}, {:.0}) = {:.3}, p = {} |",
            t.df_num,
            t.df_den,
            t.f,
            fmt_p(t.p_value)
        );
    }
    for (name, t) in [
        ("with intercept", &ce.robust_with_intercept),
        ("without intercept", &ce.robust_without_intercept),
    ] {
        let _ = writeln!(
            s,
            "| cosinor robust equality {name} (AR({}) errors) | GLS F({:.0}, {:.0}) = {:.3}, bootstrap p = {} ({} replicates) |",
            ce.robust_ar_order,
            t.f.df_num,
            t.f.df_den,
            t.f.f,
            fmt_p(t.p_value),
            ce.robust_config.bootstrap
        );
    }
    let _ = writeln!(
        s,
        "| residual lag-1 autocorrelation; REML AR coefficients | {:.3}; {} |",
        ce.residual_lag1_autocorrelation,
        ce.robust_ar
            .iter()
            .map(|a| format!("{a:.3}"))
            .collect::<Vec<_>>()
            .join(", ")
    );
    let _ = writeln!(
        s,
        "| BARS knots (mean) sim / spiro / pooled | {:.1} / {:.1} / {:.1} |",
        v.bars.sim.knots_mean, v.bars.spiro.knots_mean, be.knots_mean
    );
    let _ = writeln!(
        s,
        "| BARS P(H0) averaged / at best knots; log10 | {} / {}; {:.2} |",
        fmt_p(be.p_h0),
        fmt_p(be.p_h0_at_best),
        be.log10_p_h0
    );
    let _ = writeln!(
        s,
        "| BARS T² (p = {}) | {:.2}, screening p = {} |",
        be.t2_df,
        be.t2,
        fmt_p(be.t2_p_value)
    );
    let _ = writeln!(
        s,
        "\nWhich to trust (measured sizes and powers: docs/validation.md): for equality of the two curves, \
         the robust equality p-value without intercept, which holds its level under autocorrelated errors; the \
         iid F tests reject most true nulls once the residuals are autocorrelated (lag-1 autocorrelation above) \
         and are shown for comparison with the thesis. The Bland-Altman rows estimate agreement, per sample and \
         per breath. BARS P(H0) also assumes independent errors and tests exact equality of the two curves \
         (thesis 4.4.4).\n\nPlots: aligned.png, bland_altman.png, cosinor.png, bars.png (and .svg). All numbers: validation.json."
    );
    s
}

/// Writes `validation.json`, `aligned.csv` (the compared series and fits),
/// `spiro_resampled.csv` (the spirogram at the simulation's rate before alignment),
/// `summary.md` and the plots into `dir`.
pub fn write_outputs(v: &Validation, dir: &Path) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    let json = serde_json::to_string_pretty(v)
        .map_err(|e| Error::State(format!("JSON encoding failed: {e}")))?;
    let jp = dir.join("validation.json");
    std::fs::write(&jp, json).map_err(|e| Error::io(&jp, e))?;
    let p = &v.preparation;
    write_csv(
        &dir.join("aligned.csv"),
        &[
            "time",
            "sim",
            "spiro",
            "cosinor_sim",
            "cosinor_spiro",
            "bars_sim",
            "bars_sim_lo",
            "bars_sim_hi",
            "bars_spiro",
            "bars_spiro_lo",
            "bars_spiro_hi",
        ],
        &[
            &p.time,
            &p.sim,
            &p.spiro,
            &v.cosinor.sim.fitted,
            &v.cosinor.spiro.fitted,
            &v.bars.sim.mean,
            &v.bars.sim.lower,
            &v.bars.sim.upper,
            &v.bars.spiro.mean,
            &v.bars.spiro.lower,
            &v.bars.spiro.upper,
        ],
    )?;
    let rt: Vec<f64> = (0..p.spiro_resampled.len())
        .map(|i| i as f64 / p.rate_hz)
        .collect();
    write_csv(
        &dir.join("spiro_resampled.csv"),
        &["time", "volume"],
        &[&rt, &p.spiro_resampled],
    )?;
    let mp = dir.join("summary.md");
    std::fs::write(&mp, summary_markdown(v)).map_err(|e| Error::io(&mp, e))?;
    write_plots(v, dir)
}

fn write_plots(v: &Validation, dir: &Path) -> Result<()> {
    let p = &v.preparation;
    let t = &p.time;
    let aligned = Panel {
        title: format!(
            "Lung volume: simulation vs spirometry (r = {:.3}, lag {} frames = {:+.2} s)",
            v.pearson.r, p.lag_frames, p.lag_seconds
        ),
        x_label: "time [s]".into(),
        y_label: "volume [L]".into(),
        traces: vec![
            Trace {
                label: "simulation".into(),
                x: t,
                y: &p.sim,
                color: BLUE,
                mark: Mark::Line,
            },
            Trace {
                label: "spirometry".into(),
                x: t,
                y: &p.spiro,
                color: RED,
                mark: Mark::Line,
            },
        ],
        hlines: vec![],
        bands: vec![],
    };
    write_figure(dir, "aligned", &[aligned])?;
    let ba = &v.bland_altman;
    let ba_lines = |b: &BlandAltman| {
        vec![
            HLine {
                label: format!("bias {:+.3}", b.bias),
                y: b.bias,
                color: DARK,
                dashed: false,
            },
            HLine {
                label: format!("+1.96 SD {:+.3}", b.loa_high),
                y: b.loa_high,
                color: RED,
                dashed: true,
            },
            HLine {
                label: format!("-1.96 SD {:+.3}", b.loa_low),
                y: b.loa_low,
                color: RED,
                dashed: true,
            },
        ]
    };
    let mut panels = vec![Panel {
        title: format!(
            "Bland-Altman, samples (n = {}, {:.1} % outside)",
            ba.n,
            100.0 * ba.fraction_outside
        ),
        x_label: "mean of simulation and spirometry [L]".into(),
        y_label: "simulation - spirometry [L]".into(),
        traces: vec![Trace {
            label: "samples".into(),
            x: &ba.means,
            y: &ba.diffs,
            color: BLUE,
            mark: Mark::Points,
        }],
        hlines: ba_lines(ba),
        bands: vec![],
    }];
    if let Some(bt) = &v.breaths.tidal_volume {
        panels.push(Panel {
            title: format!(
                "Bland-Altman, tidal volume per breath ({} breath pairs)",
                bt.n
            ),
            x_label: "mean tidal volume [L]".into(),
            y_label: "difference [L]".into(),
            traces: vec![Trace {
                label: "breaths".into(),
                x: &bt.means,
                y: &bt.diffs,
                color: ORANGE,
                mark: Mark::Points,
            }],
            hlines: ba_lines(bt),
            bands: vec![],
        });
    }
    // Breath-by-breath timing (Motamedi-Fakhr et al. 2017): one panel per index.
    let b = &v.breaths;
    for (name, unit, x, color) in [
        ("inspiratory time Ti", " [s]", &b.ti, BLUE),
        ("expiratory time Te", " [s]", &b.te, RED),
        ("total breath time Ttot", " [s]", &b.ttot, ORANGE),
        ("duty cycle Ti/Ttot", "", &b.ti_ttot, BLUE),
        ("IE50 = TIF50 / TEF50", "", &b.ie50, RED),
    ] {
        if let Some(x) = x {
            panels.push(Panel {
                title: format!("Bland-Altman, {name} per breath ({} breath pairs)", x.n),
                x_label: format!("mean {name}{unit}"),
                y_label: format!("difference{unit}"),
                traces: vec![Trace {
                    label: "breaths".into(),
                    x: &x.means,
                    y: &x.diffs,
                    color,
                    mark: Mark::Points,
                }],
                hlines: ba_lines(x),
                bands: vec![],
            });
        }
    }
    write_figure(dir, "bland_altman", &panels)?;
    let cz = &v.cosinor;
    fn cos_panel<'a>(
        name: &str,
        t: &'a [f64],
        y: &'a [f64],
        fit: &'a CosinorFit,
        color: (u8, u8, u8),
        p_eq: f64,
    ) -> Panel<'a> {
        Panel {
            title: format!(
                "{name}: cosinor fit, C = {} at {:.3} Hz (R² = {:.3}); equality p = {}",
                fit.harmonics,
                fit.frequency_hz,
                fit.r_squared,
                fmt_p(p_eq)
            ),
            x_label: "time [s]".into(),
            y_label: "volume [L]".into(),
            traces: vec![
                Trace {
                    label: name.to_lowercase(),
                    x: t,
                    y,
                    color,
                    mark: Mark::Line,
                },
                Trace {
                    label: "cosinor fit".into(),
                    x: t,
                    y: &fit.fitted,
                    color: DARK,
                    mark: Mark::Dashed,
                },
            ],
            hlines: vec![],
            bands: vec![],
        }
    }
    let peq = cz.equality.f_with_intercept.p_value;
    write_figure(
        dir,
        "cosinor",
        &[
            cos_panel("Simulation", t, &p.sim, &cz.sim, BLUE, peq),
            cos_panel("Spirometry", t, &p.spiro, &cz.spiro, RED, peq),
        ],
    )?;
    let bz = &v.bars;
    fn bars_panel<'a>(
        name: &str,
        t: &'a [f64],
        y: &'a [f64],
        fit: &'a BarsFit,
        color: (u8, u8, u8),
        eq: &BarsEquality,
    ) -> Panel<'a> {
        Panel {
            title: format!(
                "{name}: BARS fit ({:.1} knots on average); P(H0 | sim, spir) = {}",
                fit.knots_mean,
                if eq.p_h0 > 0.0 {
                    fmt_p(eq.p_h0)
                } else {
                    format!("1e{:.0}", eq.log10_p_h0)
                }
            ),
            x_label: "time [s]".into(),
            y_label: "volume [L]".into(),
            traces: vec![
                Trace {
                    label: name.to_lowercase(),
                    x: t,
                    y,
                    color,
                    mark: Mark::Points,
                },
                Trace {
                    label: "BARS posterior mean".into(),
                    x: t,
                    y: &fit.mean,
                    color: DARK,
                    mark: Mark::Line,
                },
            ],
            hlines: vec![],
            bands: vec![Band {
                label: "95 % band".into(),
                x: t,
                lo: &fit.lower,
                hi: &fit.upper,
                color: ORANGE,
            }],
        }
    }
    let eq = &bz.equality;
    write_figure(
        dir,
        "bars",
        &[
            bars_panel("Simulation", t, &p.sim, &bz.sim, BLUE, eq),
            bars_panel("Spirometry", t, &p.spiro, &bz.spiro, RED, eq),
        ],
    )
}
