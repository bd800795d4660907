//! `torso synth`: writes a synthetic SLP recording with known drive parameters and its
//! ground-truth JSON (FMI parameter names, subject, grid, camera transform, noise floor).

use super::common::{DriveArgs, prepare_output_file};
use super::fit::ModelArgs;
use crate::anatomy::skin::{BUILTIN_SETS, MarkerSet, Skin, SkinOptions};
use crate::fit::report::{drive_fmi, model_provenance, truth_json};
use crate::fit::{Camera, SynthOptions, TorsoMarkers, synthesize};
use crate::recording::{Format, Markers, Recording, Units};
use crate::{Error, Result, Torso};
use clap::Args;
use std::path::Path;
use std::path::PathBuf;
use std::sync::Arc;

/// Options of `torso synth`.
#[derive(Args, Debug)]
pub struct SynthArgs {
    /// Recording to write: `.csv` (the grid CSV or, for a named set, a CSV of named markers;
    /// metres, millimetres in a lab frame), `.c3d` or `.trc` (millimetres); the grid's
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
    /// Marker set: `grid` (the model's `--grid`, labels `marker[k]`), `chest30` (30 markers
    /// on the chest and back) or `oep89` (89 markers after optoelectronic plethysmography),
    /// the named sets placed from the subject's own landmarks (docs/recordings.md).
    #[arg(long, default_value = "grid")]
    pub marker_set: String,
    /// Write the markers in a laboratory frame (z up, the subject turned by a random angle
    /// about the vertical and moved on the floor; millimetres) instead of a camera's;
    /// overrides --camera.
    #[arg(long)]
    pub lab_frame: bool,
}

/// Runs `torso synth`.
pub fn main(args: &SynthArgs) -> Result<()> {
    let drive = args.drive.drive(args.model.subject.law()?)?;
    let config = args.model.config(drive)?;
    let (rows, cols) = args.model.grid()?;
    let camera = match args.camera.as_str() {
        _ if args.lab_frame => Camera::Lab,
        "random" => Camera::Random,
        "identity" => Camera::Identity,
        other => return Err(Error::invalid("--camera", other, "random or identity")),
    };
    if !BUILTIN_SETS.contains(&args.marker_set.as_str()) {
        return Err(Error::invalid(
            "--marker-set",
            &args.marker_set,
            BUILTIN_SETS.join(", "),
        ));
    }
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
    let format = Format::from_path(&args.out)?;
    prepare_output_file(&args.out)?;
    prepare_output_file(&args.truth)?;
    let truth_config = config.clone();
    let mut torso = Torso::new(config)?;
    let set = if args.marker_set == "grid" {
        None
    } else {
        let skin = Skin::for_anatomy(&torso.compiled().anatomy, &SkinOptions::default())?;
        let set = Arc::new(MarkerSet::builtin(&skin, &args.marker_set)?);
        torso.set_marker_set(Some(set.clone()));
        Some(set)
    };
    let mut model = TorsoMarkers::from_torso(torso)?;
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
    let camera_name = if args.lab_frame {
        "lab".to_string()
    } else {
        args.camera.clone()
    };
    for (k, v) in [
        ("solver.method", config_solver.0.to_string()),
        ("solver.rtol", config_solver.1.to_string()),
        ("rate_hz", args.rate.to_string()),
        ("duration_s", args.duration.to_string()),
        ("noise_mm", args.noise_mm.to_string()),
        ("seed", args.seed.to_string()),
        ("camera", camera_name),
        ("variability", args.variability.to_string()),
        ("dropout", args.dropout.to_string()),
    ] {
        provenance.push((k.to_string(), v));
    }
    let mut recording = synthetic.recording.clone();
    let millimetres = args.lab_frame || format != Format::MarkerCsv;
    match &set {
        Some(set) => {
            provenance.push(("marker_set".to_string(), set.name.clone()));
            Markers {
                labels: set.labels.clone(),
                times: recording.times.clone(),
                frames: recording.frames.clone(),
                units: if millimetres {
                    Units::Millimetres
                } else {
                    Units::Metres
                },
                format,
                provenance,
            }
            .write(&args.out)?;
        }
        None => {
            recording.provenance = provenance;
            if millimetres {
                recording.units = Units::Millimetres;
            }
            write_grid(&recording, &args.out)?;
        }
    }
    let mut truth = truth_json(&synthetic, &subject, lod, &options);
    if let Some(set) = &set {
        truth["marker_set"] = serde_json::json!(set.name);
        truth["marker_labels"] = serde_json::json!(set.labels);
        // What a fit of a named set is judged by: the lung's tidal volume under the true
        // drive (three breaths from rest, the last two, as `torso fit`'s fitted breath).
        let breath = super::fit::breath_of(&truth_config, synthetic.truth)?;
        truth["lung_tidal_volume_l"] = serde_json::json!(breath.tidal_volume);
    }
    let text = serde_json::to_string_pretty(&truth)
        .map_err(|e| Error::State(format!("truth JSON: {e}")))?;
    std::fs::write(&args.truth, text + "\n").map_err(|e| Error::io(&args.truth, e))?;
    println!(
        "{} frames of {} at {} Hz ({:.2} s), noise floor {:.3} mm",
        synthetic.recording.frames.len(),
        match &set {
            Some(s) => format!("the {} markers of set {}", s.len(), s.name),
            None => format!("a {rows}x{cols} grid"),
        },
        args.rate,
        start.elapsed().as_secs_f64(),
        synthetic.noise_floor_m * 1e3
    );
    println!("wrote {} and {}", args.out.display(), args.truth.display());
    Ok(())
}

/// Writes a grid recording: the grid CSV in its units, or C3D / TRC in millimetres.
fn write_grid(recording: &Recording, out: &Path) -> Result<()> {
    match Format::from_path(out)? {
        Format::C3d | Format::Trc => {
            let mut markers = Markers::from_recording(recording);
            markers.units = Units::Millimetres;
            markers.write(out)
        }
        _ => recording.write(out),
    }
}
