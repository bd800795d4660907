//! `torso validate`: compares a simulated lung volume with a spirogram and writes every
//! statistic (JSON), the aligned data (CSV), plots (PNG and SVG) and a Markdown summary;
//! and `torso synth-spirometry`, which writes a synthetic spirogram for tests.

use crate::stats::autoreg::ArGlsConfig;
use crate::stats::bars::BarsConfig;
use crate::stats::io::{Series, Table, read_table, write_csv};
use crate::stats::prepare::{PrepareOptions, SpiroKind};
use crate::stats::synth::{SpiroSynthOptions, VolumeSource, synth_spirometry};
use crate::stats::validation::{ValidationOptions, summary_markdown, validate, write_outputs};
use crate::{Error, Result};
use clap::Args;
use std::path::PathBuf;

/// Arguments of `torso validate`.
#[derive(Args, Debug, Clone)]
pub struct ValidateArgs {
    /// Simulation CSV: `time` [s] and a lung-volume column [L].
    #[arg(long)]
    pub sim: PathBuf,
    /// Spirometry CSV: `time` [s] and `volume` [L] or `flow` [L/s].
    #[arg(long)]
    pub spiro: PathBuf,
    /// Output directory (created).
    #[arg(long)]
    pub out: PathBuf,
    /// Value column of the simulation CSV (default: `volume.lung`, else `lung_volume`,
    /// else `volume`).
    #[arg(long)]
    pub sim_column: Option<String>,
    /// Factor applied to the simulated volume, for a model whose lungs change as a fraction
    /// of a thoracic volume (the thesis's 0.75, section 4.2); this model's `volume.thorax`
    /// changes one to one with `volume.lung`, so either compares as it is (default 1).
    #[arg(long)]
    pub lung_ratio: Option<f64>,
    /// Largest alignment lag searched [frames at the simulation's rate].
    #[arg(long, default_value_t = 100)]
    pub max_lag: usize,
    /// Number of cosinor harmonics.
    #[arg(long, default_value_t = 4)]
    pub harmonics: usize,
    /// Bootstrap replicates of the robust cosinor equality test (0: nominal F p-value).
    #[arg(long, default_value_t = 399)]
    pub bootstrap: usize,
    /// Largest autoregressive order of the robust test's error model.
    #[arg(long, default_value_t = 8)]
    pub max_ar_order: usize,
    /// Seed of the BARS chains.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// BARS iterations in total (burn-in 200 included).
    #[arg(long, default_value_t = 2200)]
    pub bars_iterations: usize,
    /// Remove the linear trend from a volume spirogram (flow is always detrended).
    #[arg(long)]
    pub detrend: bool,
}

/// Lung-volume columns looked for, in order, when none is named: `volume.lung` (written
/// by `torso simulate` and by `torso fit` in `<stem>_lung_volume.csv`), then
/// `lung_volume` and `volume`.
pub const LUNG_VOLUME_COLUMNS: [&str; 3] = ["volume.lung", "lung_volume", "volume"];

/// The named column, else the first of [`LUNG_VOLUME_COLUMNS`] in the table; an error
/// naming the file and its columns when there is none.
fn lung_volume_column(t: &Table, named: Option<&str>) -> Result<String> {
    if let Some(c) = named {
        return Ok(c.to_string());
    }
    LUNG_VOLUME_COLUMNS
        .iter()
        .find(|c| t.column_index(c).is_some())
        .map(|c| c.to_string())
        .ok_or_else(|| Error::Parse {
            path: t.path.clone(),
            line: t.header_line,
            column: 1,
            message: format!(
                "no lung-volume column: looked for {} (columns: {}); name one with --sim-column",
                LUNG_VOLUME_COLUMNS
                    .iter()
                    .map(|c| format!("`{c}`"))
                    .collect::<Vec<_>>()
                    .join(", "),
                t.headers.join(", ")
            ),
        })
}

/// Reads the simulation series (see [`lung_volume_column`]).
pub fn read_sim(args: &ValidateArgs) -> Result<Series> {
    let t = read_table(&args.sim)?;
    let name = lung_volume_column(&t, args.sim_column.as_deref())?;
    t.series(&name, 32)
}

/// Reads the spirometry series (`volume`, else `flow`).
pub fn read_spiro(args: &ValidateArgs) -> Result<(Series, SpiroKind)> {
    let t = read_table(&args.spiro)?;
    if t.column_index("volume").is_some() {
        Ok((t.series("volume", 32)?, SpiroKind::Volume))
    } else if t.column_index("flow").is_some() {
        Ok((t.series("flow", 32)?, SpiroKind::Flow))
    } else {
        Err(Error::Parse {
            path: args.spiro.display().to_string(),
            line: t.header_line,
            column: 1,
            message: format!(
                "no `volume` or `flow` column in header (columns: {})",
                t.headers.join(", ")
            ),
        })
    }
}

/// Builds the validation options from the arguments.
pub fn options(args: &ValidateArgs) -> Result<ValidationOptions> {
    if args.max_ar_order > 20 {
        return Err(Error::invalid(
            "--max-ar-order",
            args.max_ar_order,
            "0..=20",
        ));
    }
    if args.bootstrap > 100_000 {
        return Err(Error::invalid("--bootstrap", args.bootstrap, "0..=100000"));
    }
    let burn_in = 200;
    if args.bars_iterations <= burn_in {
        return Err(Error::invalid(
            "--bars-iterations",
            args.bars_iterations,
            "more than the burn-in of 200",
        ));
    }
    let lung_ratio = args.lung_ratio.unwrap_or(1.0);
    Ok(ValidationOptions {
        prepare: PrepareOptions {
            lung_ratio,
            max_lag: args.max_lag,
            detrend_volume: args.detrend,
        },
        harmonics: args.harmonics,
        robust: ArGlsConfig {
            max_order: args.max_ar_order,
            bootstrap: args.bootstrap,
            seed: args.seed,
        },
        bars: BarsConfig {
            burn_in,
            samples: args.bars_iterations - burn_in,
            seed: args.seed,
            ..BarsConfig::default()
        },
    })
}

/// Runs `torso validate`.
pub fn run(args: &ValidateArgs) -> Result<()> {
    let opts = options(args)?;
    let sim = read_sim(args)?;
    let (spiro, kind) = read_spiro(args)?;
    let v = validate(&sim, &spiro, kind, &opts)?;
    write_outputs(&v, &args.out)?;
    print!("{}", summary_markdown(&v));
    println!("\nwritten to {}", args.out.display());
    Ok(())
}

/// Arguments of `torso synth-spirometry`.
#[derive(Args, Debug, Clone)]
pub struct SynthSpirometryArgs {
    /// Output CSV (`time,volume` or `time,flow`).
    #[arg(long)]
    pub out: PathBuf,
    /// Source lung-volume curve CSV (e.g. a simulation); otherwise a sinusoidal model.
    #[arg(long)]
    pub from: Option<PathBuf>,
    /// Column of the source curve (default: `volume.lung`, else `lung_volume`, else
    /// `volume`).
    #[arg(long)]
    pub column: Option<String>,
    /// Sinusoidal model: breathing frequency [Hz].
    #[arg(long, default_value_t = 0.25)]
    pub frequency: f64,
    /// Sinusoidal model: tidal volume [L].
    #[arg(long, default_value_t = 0.5)]
    pub tidal_volume: f64,
    /// Sinusoidal model: relative second-harmonic amplitude.
    #[arg(long, default_value_t = 0.0)]
    pub harmonic2: f64,
    /// Sinusoidal model: phase [rad].
    #[arg(long, default_value_t = 0.0)]
    pub phase: f64,
    /// Sinusoidal model: record length [s].
    #[arg(long, default_value_t = 60.0)]
    pub duration: f64,
    /// Sampling rate [Hz].
    #[arg(long, default_value_t = 100.0)]
    pub rate: f64,
    /// White-noise standard deviation [L or L/s].
    #[arg(long, default_value_t = 0.0)]
    pub noise: f64,
    /// Linear volume drift [L/s].
    #[arg(long, default_value_t = 0.0)]
    pub drift: f64,
    /// Start of the record after the source's first sample [s].
    #[arg(long, default_value_t = 0.0, allow_hyphen_values = true)]
    pub start_offset: f64,
    /// Calibration scale error (1 = none).
    #[arg(long, default_value_t = 1.0)]
    pub scale: f64,
    /// Write flow [L/s] instead of volume.
    #[arg(long)]
    pub flow: bool,
    /// Noise seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
}

/// Runs `torso synth-spirometry`.
pub fn run_synth(args: &SynthSpirometryArgs) -> Result<()> {
    let source = match &args.from {
        Some(p) => {
            let t = read_table(p)?;
            let name = lung_volume_column(&t, args.column.as_deref())?;
            VolumeSource::Curve(t.series(&name, 16)?)
        }
        None => VolumeSource::Sine {
            frequency_hz: args.frequency,
            tidal_volume_l: args.tidal_volume,
            harmonic2: args.harmonic2,
            phase: args.phase,
            base_l: 2.5,
            duration_s: args.duration,
        },
    };
    let opts = SpiroSynthOptions {
        rate_hz: args.rate,
        noise_sd: args.noise,
        drift_l_per_s: args.drift,
        start_offset_s: args.start_offset,
        scale: args.scale,
        output: if args.flow {
            SpiroKind::Flow
        } else {
            SpiroKind::Volume
        },
        seed: args.seed,
    };
    let s = synth_spirometry(&source, &opts)?;
    write_csv(&args.out, &["time", &s.column], &[&s.time, &s.values])?;
    println!(
        "{} samples at {} Hz written to {}",
        s.len(),
        args.rate,
        args.out.display()
    );
    Ok(())
}
