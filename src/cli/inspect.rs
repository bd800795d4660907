//! `torso inspect` (what a marker recording holds: format, markers, frames, rate, units,
//! missing samples, how it was made) and `torso convert` (a recording into another format).

use super::fit::ReadArgs;
use crate::Result;
use crate::recording::Markers;
use clap::Args;
use std::path::PathBuf;

/// Options of `torso inspect`.
#[derive(Args, Debug)]
pub struct InspectArgs {
    /// The recording: `.c3d`, `.trc` or `.csv`.
    pub file: PathBuf,
    /// Units and frame rate of a recording that does not state them.
    #[command(flatten)]
    pub read: ReadArgs,
}

/// Runs `torso inspect`.
pub fn inspect(args: &InspectArgs) -> Result<()> {
    let m = Markers::read(&args.file, &args.read.options()?)?;
    let frames = m.times.len();
    println!("file: {}", args.file.display());
    println!("format: {}", m.format.name());
    println!("markers: {}", m.markers());
    println!("frames: {frames}");
    println!("rate: {:.6} Hz (mean frame interval)", m.rate());
    println!(
        "duration: {:.6} s ({} s to {} s)",
        m.duration(),
        m.times[0],
        m.times[frames - 1]
    );
    println!("units: {} (positions held in metres)", m.units.name());
    let missing = m.missing_per_marker();
    let total: usize = missing.iter().sum();
    println!(
        "missing samples: {total} of {} ({:.2} %)",
        frames * m.markers(),
        100.0 * total as f64 / (frames * m.markers()) as f64
    );
    println!("marker\tmissing");
    for (l, n) in m.labels.iter().zip(&missing) {
        println!("{l}\t{n}");
    }
    if m.provenance.is_empty() {
        println!("provenance: none recorded");
    } else {
        println!("provenance:");
        for (k, v) in &m.provenance {
            println!("  {k}: {v}");
        }
    }
    Ok(())
}

/// Options of `torso convert`.
#[derive(Args, Debug)]
pub struct ConvertArgs {
    /// The recording to read: `.c3d`, `.trc` or `.csv`.
    pub input: PathBuf,
    /// The recording to write: `.c3d`, `.trc` or `.csv` (same units, labels and provenance).
    pub output: PathBuf,
    /// Units and frame rate of a recording that does not state them.
    #[command(flatten)]
    pub read: ReadArgs,
}

/// Runs `torso convert`.
pub fn convert(args: &ConvertArgs) -> Result<()> {
    let m = Markers::read(&args.input, &args.read.options()?)?;
    crate::recording::Format::from_path(&args.output)?;
    super::common::prepare_output_file(&args.output)?;
    m.write(&args.output)?;
    println!(
        "wrote {} ({} markers, {} frames)",
        args.output.display(),
        m.markers(),
        m.times.len()
    );
    Ok(())
}
