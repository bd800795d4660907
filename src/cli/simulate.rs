//! `torso simulate`: runs a scenario on a subject and writes a CSV of every volume, pressure
//! and displacement at the output rate, then prints a breathing summary.

use super::common::{
    DriveArgs, MethodAlias, SolverArgs, SubjectArgs, prepare_output_dir, prepare_output_file,
};
use crate::anatomy::MuscleGroup;
use crate::model::run::{run, summarise};
use crate::model::{Drive, Torso};
use crate::{Error, Result};
use clap::Args;
use std::io::Write;
use std::path::PathBuf;

/// Options of `torso simulate`.
#[derive(Args, Debug)]
pub struct SimulateArgs {
    /// The subject and scene.
    #[command(flatten)]
    pub subject: SubjectArgs,
    /// The ODE solver.
    #[command(flatten)]
    pub solver: SolverArgs,
    /// `--method`, the former name of `--solver`.
    #[command(flatten)]
    pub method: MethodAlias,
    /// The drive.
    #[command(flatten)]
    pub drive: DriveArgs,
    /// Simulated duration [s].
    #[arg(long, default_value_t = 20.0)]
    pub duration: f64,
    /// Output rate [Hz] (SLP cameras: 56 Hz).
    #[arg(long, default_value_t = 56.0)]
    pub rate: f64,
    /// CSV output file (default: out/simulation.csv). A missing folder is created only below
    /// the working directory.
    #[arg(long, default_value = "out/simulation.csv")]
    pub out: PathBuf,
    /// Also write the skin, markers, abdominal surface and bones as VTK series (.vtp + .pvd).
    #[arg(long)]
    pub export_vtk: Option<PathBuf>,
    /// Write every N-th output frame to the VTK series.
    #[arg(long, default_value_t = 4)]
    pub vtk_stride: usize,
    /// Subject mesh directory from `torso mesh prepare`: its skin and cavity replace the
    /// generated ones (FMI `subject.mesh_dir`).
    #[arg(long)]
    pub mesh_dir: Option<PathBuf>,
}

/// Runs `torso simulate`.
pub fn main(args: &SimulateArgs) -> Result<()> {
    if !(args.duration > 0.0 && args.duration <= 86_400.0) {
        return Err(Error::invalid("--duration", args.duration, "(0, 86400] s"));
    }
    if !(args.rate > 0.0 && args.rate <= 10_000.0) {
        return Err(Error::invalid("--rate", args.rate, "(0, 10000] Hz"));
    }
    let drive = args.drive.drive(args.subject.law()?)?;
    let solver = args.solver.with_alias(&args.method);
    let mut config = args.subject.config(&solver, drive)?;
    prepare_output_file(&args.out)?;
    if let Some(dir) = &args.export_vtk {
        prepare_output_dir(dir)?;
    }
    config.subject_mesh_dir = args.mesh_dir.clone();
    let subject = config.subject.clone();
    let start = std::time::Instant::now();
    let mut torso = Torso::new(config)?;
    let build = start.elapsed().as_secs_f64();
    let start = std::time::Instant::now();
    let frames = match &args.export_vtk {
        Some(dir) => {
            super::skin::run_with_vtk(&mut torso, args.duration, args.rate, dir, args.vtk_stride)?
        }
        None => run(&mut torso, args.duration, args.rate)?,
    };
    let wall = start.elapsed().as_secs_f64();
    write_csv(&args.out, &frames)?;
    let period = 1.0 / drive.frequency;
    let from = summary_start(args.duration, period);
    let stats = torso.solver_stats();
    println!(
        "subject: {:?}, {} y, {} m, {} kg, {:?}",
        subject.sex, subject.age, subject.stature, subject.mass, subject.posture
    );
    println!("drive: {}", describe_drive(&drive));
    if args.duration < period {
        eprintln!(
            "warning: the run ({} s) is shorter than one breath ({period} s at {} Hz): no \
             tidal volume or breathing summary; run --duration {period} or more for one",
            args.duration, drive.frequency,
        );
    } else {
        print_summary(&summarise(&frames, from), subject.frc_ecsc());
    }
    println!(
        "solver: {} steps, {} rejected, {} RHS evaluations; build {:.3} s, run {:.3} s",
        stats.steps, stats.rejected, stats.rhs_evaluations, build, wall
    );
    if torso.stiffness_detected() {
        println!(
            "note: the explicit solver reported stiffness; the stiff method may be faster (--solver rosenbrock, FMI solver.method = 3), or use a lower level of detail"
        );
    }
    println!("wrote {}", args.out.display());
    Ok(())
}

/// The drive in one readable line: frequency, then each family's amplitude and phase.
/// Where the printed summary starts in a run of `duration` seconds with breaths of `period`:
/// the last two breaths, or the last one of a run shorter than two.
fn summary_start(duration: f64, period: f64) -> f64 {
    (duration - 2.0 * period).max(period.min(duration - period))
}

/// The breathing summary `torso simulate --duration 20` prints with every other option at
/// its default (the default subject at level of detail 1, the quiet drive, rtol 1e-6): the
/// figures the README quotes, computed as that command computes them, with the subject's
/// ECSC FRC. `torso demo` prints them beside its level-0 run.
pub fn default_summary() -> Result<(crate::model::run::BreathSummary, f64)> {
    use clap::Parser;
    #[derive(Parser)]
    struct Defaults {
        #[command(flatten)]
        args: SimulateArgs,
    }
    let args = Defaults::try_parse_from(["simulate", "--duration", "20"])
        .map_err(|e| Error::State(format!("the default simulate options: {e}")))?
        .args;
    let drive = args.drive.drive(args.subject.law()?)?;
    let config = args
        .subject
        .config(&args.solver.with_alias(&args.method), drive)?;
    let frc = config.subject.frc_ecsc();
    let mut torso = Torso::new(config)?;
    let frames = run(&mut torso, args.duration, args.rate)?;
    let from = summary_start(args.duration, 1.0 / drive.frequency);
    Ok((summarise(&frames, from), frc))
}

pub fn describe_drive(d: &Drive) -> String {
    let waves = [
        ("ribs", d.ribs),
        ("diaphragm", d.diaphragm),
        ("abdominals", d.abdominals),
    ]
    .map(|(n, w)| format!("{n} {:.3} at {:+.3} rad", w.amplitude, w.phase))
    .join(", ");
    let shape = if d.inspiratory_fraction == crate::model::drive::SINE_FRACTION {
        String::new()
    } else {
        format!(", Ti/Ttot {}", d.inspiratory_fraction)
    };
    format!(
        "{} Hz ({:.1} breaths/min){shape}{}; amplitude and phase: {waves}",
        d.frequency,
        60.0 * d.frequency,
        if d.enabled { "" } else { ", off" }
    )
}

/// Prints the breathing summary of a run of at least one breath.
fn print_summary(summary: &crate::model::run::BreathSummary, frc_ecsc: f64) {
    println!("tidal volume           {:8.3} L", summary.tidal_volume);
    println!(
        "end-expiratory volume  {:8.3} L   (ECSC FRC {frc_ecsc:.2} L)",
        summary.end_expiratory_volume,
    );
    println!(
        "rib-cage share         {:8.1} %",
        100.0 * summary.rib_cage_share
    );
    println!(
        "abdominal share        {:8.1} %",
        100.0 * (1.0 - summary.rib_cage_share)
    );
    println!(
        "diaphragm excursion    {:8.2} cm",
        100.0 * summary.dome_excursion
    );
    println!(
        "abdominal volume swing {:8.3} %",
        100.0 * summary.abdomen_relative_swing
    );
    println!(
        "abdominal pressure     {:8.0} Pa peak-to-trough",
        summary.pressure_swing
    );
}

/// The columns [`write_csv`] writes, in order: time, the eight activations, the volumes,
/// the abdominal pressure and the displacements (also the Python package's `simulate`).
pub fn frame_columns() -> Vec<String> {
    let mut header = vec!["time".to_string()];
    header.extend(
        MuscleGroup::ALL
            .iter()
            .map(|g| format!("activation.{}", g.name())),
    );
    header.extend(
        [
            "volume.lung",
            "volume.thorax",
            "volume.abdomen",
            "volume.trunk",
            "volume.rib_cage_displaced",
            "volume.abdomen_displaced",
            "pressure.abdomen",
            "diaphragm.displacement",
            "sternum.displacement.x",
            "sternum.displacement.y",
            "sternum.displacement.z",
        ]
        .map(String::from),
    );
    header
}

/// Appends one frame's values in [`frame_columns`] order to `row`.
pub fn frame_values(f: &crate::model::run::Frame, row: &mut Vec<f64>) {
    row.push(f.time);
    row.extend(f.activation);
    row.extend([
        f.lung,
        f.thorax,
        f.abdomen,
        f.trunk,
        f.rib_cage_displaced,
        f.abdomen_displaced,
        f.pressure,
        f.diaphragm,
        f.sternum[0],
        f.sternum[1],
        f.sternum[2],
    ]);
}

/// Writes frames as CSV.
pub fn write_csv(path: &std::path::Path, frames: &[crate::model::run::Frame]) -> Result<()> {
    prepare_output_file(path)?;
    let file = std::fs::File::create(path).map_err(|e| Error::io(path, e))?;
    let mut w = std::io::BufWriter::new(file);
    let header = frame_columns();
    let io = |e| Error::io(path, e);
    writeln!(w, "{}", header.join(",")).map_err(io)?;
    for f in frames {
        let mut row = Vec::with_capacity(header.len());
        frame_values(f, &mut row);
        let cells: Vec<String> = row.iter().map(|v| format!("{v}")).collect();
        writeln!(w, "{}", cells.join(",")).map_err(io)?;
    }
    w.flush().map_err(io)
}
