//! `torso synth`: writes a synthetic SLP recording with known drive parameters and its
//! ground-truth JSON (FMI parameter names, subject, grid, camera transform, noise floor).

use super::common::{DriveArgs, prepare_output_file};
use super::fit::ModelArgs;
use crate::fit::report::{drive_fmi, model_provenance, truth_json};
use crate::fit::{Camera, Format, Markers, SynthOptions, TorsoMarkers, Units, synthesize};
use crate::{Error, Result};
use clap::Args;
use std::path::PathBuf;

/// Options of `torso synth`.
#[derive(Args, Debug)]
pub struct SynthArgs {
    /// Recording to write: `.csv` (the grid CSV, metres), `.c3d` or `.trc` (millimetres);
    /// markers labelled `marker[1]`..`marker[R*C]`, with how it was made (docs/recordings.md).
    #[arg(long)]
    pub out: PathBuf,
    /// Ground-truth JSON to write.
    #[arg(long)]
    pub truth: PathBuf,
    /// The subject and the model.
    #[command(flatten)]
    pub model: ModelArgs,
    /// The drive.
    #[command(flatten)]
    pub drive: DriveArgs,
    /// Frame rate [Hz].
    #[arg(long, default_value_t = 56.0)]
    pub rate: f64,
    /// Duration [s].
    #[arg(long, default_value_t = 18.0)]
    pub duration: f64,
    /// Gaussian noise per coordinate [mm].
    #[arg(long, default_value_t = 0.5)]
    pub noise_mm: f64,
    /// Seed of the random draws.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Camera frame: random or identity.
    #[arg(long, default_value = "random")]
    pub camera: String,
    /// Breath-to-breath variability of period and amplitude (relative standard deviation,
    /// the coefficient of variation of Ttot and depth; alias --breath-cv).
    #[arg(long, visible_alias = "breath-cv", default_value_t = 0.0)]
    pub variability: f64,
    /// Probability that a point is untracked in a frame.
    #[arg(long, default_value_t = 0.0)]
    pub dropout: f64,
}

/// Runs `torso synth`.
pub fn main(args: &SynthArgs) -> Result<()> {
    let drive = args.drive.drive()?;
    let config = args.model.config(drive)?;
    let (rows, cols) = args.model.grid()?;
    let camera = match args.camera.as_str() {
        "random" => Camera::Random,
        "identity" => Camera::Identity,
        other => return Err(Error::invalid("--camera", other, "random or identity")),
    };
    let options = SynthOptions {
        drive,
        rate: args.rate,
        duration: args.duration,
        noise: args.noise_mm * 1e-3,
        seed: args.seed,
        camera,
        variability: args.variability,
        dropout: args.dropout,
    };
    options.validate()?;
    let subject = config.subject.clone();
    let lod = config.scene.level_of_detail;
    let config_solver = (config.solver.method.name(), config.solver.rtol);
    let start = std::time::Instant::now();
    Format::from_path(&args.out)?;
    prepare_output_file(&args.out)?;
    prepare_output_file(&args.truth)?;
    let mut model = TorsoMarkers::new(config)?;
    let synthetic = synthesize(&mut model, &options)?;
    let mut provenance = vec![(
        "made_by".to_string(),
        format!("torso synth {}", env!("CARGO_PKG_VERSION")),
    )];
    provenance.extend(model_provenance(&subject, lod));
    provenance.extend(
        drive_fmi(&options.drive)
            .into_iter()
            .map(|(k, v)| (k, v.to_string())),
    );
    for (k, v) in [
        ("solver.method", config_solver.0.to_string()),
        ("solver.rtol", config_solver.1.to_string()),
        ("rate_hz", args.rate.to_string()),
        ("duration_s", args.duration.to_string()),
        ("noise_mm", args.noise_mm.to_string()),
        ("seed", args.seed.to_string()),
        ("camera", args.camera.clone()),
        ("variability", args.variability.to_string()),
        ("dropout", args.dropout.to_string()),
    ] {
        provenance.push((k.to_string(), v));
    }
    let mut recording = synthetic.recording.clone();
    recording.provenance = provenance;
    match Format::from_path(&args.out)? {
        Format::C3d | Format::Trc => {
            let mut markers = Markers::from_recording(&recording);
            markers.units = Units::Millimetres;
            markers.write(&args.out)?;
        }
        _ => recording.write(&args.out)?,
    }
    let truth = truth_json(&synthetic, &subject, lod, &options);
    let text = serde_json::to_string_pretty(&truth)
        .map_err(|e| Error::State(format!("truth JSON: {e}")))?;
    std::fs::write(&args.truth, text + "\n").map_err(|e| Error::io(&args.truth, e))?;
    println!(
        "{} frames of a {}x{} grid at {} Hz ({:.2} s), noise floor {:.3} mm",
        synthetic.recording.frames.len(),
        rows,
        cols,
        args.rate,
        start.elapsed().as_secs_f64(),
        synthetic.noise_floor_m * 1e3
    );
    println!("wrote {} and {}", args.out.display(), args.truth.display());
    Ok(())
}
