//! The `torso` command-line tool: one file per subcommand.

pub mod bench;
pub mod bench_physiology;
pub mod bench_report;
pub mod bench_stress;
pub mod common;
pub mod fit;
pub mod inspect;
pub mod mesh;
pub mod progress;
pub mod simulate;
pub mod skin;

use clap::{CommandFactory, FromArgMatches, Parser, Subcommand};

mod fmu;
pub mod synth;
pub mod validate;

/// Breathing torso simulator: simulate, fit SLP recordings, validate against spirometry.
#[derive(Parser, Debug)]
#[command(name = "torso", version, about)]
pub struct Cli {
    /// The subcommand.
    #[command(subcommand)]
    pub command: Command,
}

/// Subcommands of `torso`.
#[derive(Subcommand, Debug)]
pub enum Command {
    /// Simulate a breathing scenario and write a CSV of volumes, pressures and displacements.
    Simulate(simulate::SimulateArgs),
    /// Print the library version.
    Version,
    /// Build the FMI 2.0 co-simulation FMU or write its model description.
    Fmu(fmu::FmuArgs),
    /// Compare a simulated lung volume with a spirogram (statistics, plots, summary).
    Validate(validate::ValidateArgs),
    /// Write a synthetic spirogram (from a curve or a sinusoidal model).
    SynthSpirometry(validate::SynthSpirometryArgs),
    /// Write a synthetic SLP recording with known drive parameters and its ground truth.
    Synth(synth::SynthArgs),
    /// Fit the model to an SLP recording (registration, frequency, amplitudes and phases).
    Fit(fit::FitArgs),
    /// Describe a marker recording (.c3d, .trc, .csv): markers, frames, rate, units,
    /// missing samples per marker, how it was made.
    Inspect(inspect::InspectArgs),
    /// Convert a marker recording between .c3d, .trc and .csv.
    Convert(inspect::ConvertArgs),
    /// Synthesise the six acceptance recordings, fit each, print truth against fit.
    FitSweep(fit::SweepArgs),
    /// Package the FMU, simulate the default subject and fit the bundled recording.
    Demo(fit::DemoArgs),
    /// Write the rest geometry (skin, ribs, sternum, abdomen, marker grid) as OBJ files.
    ExportObj(skin::ExportObjArgs),
    /// Render the skin and markers at rest and at end-inspiration as a PNG.
    RenderSkin(skin::RenderSkinArgs),
    /// Prepare, inspect and volume-mesh subject surfaces.
    Mesh {
        /// The mesh subcommand.
        #[command(subcommand)]
        command: mesh::MeshCommand,
    },
    /// Benchmarks: frame loops, right-hand-side cost, work-precision, stress soak.
    Bench {
        /// The benchmark.
        #[command(subcommand)]
        command: bench::BenchCommand,
    },
}

/// `cmd` and its subcommands with every option that takes a value accepting a negative
/// number as that value (`--stature -1` is then a value, checked against its range, rather
/// than an unknown flag `-1`). Real-valued options take any value starting with `-`, as
/// clap's own number test does not know a negative exponent (`--rtol -1e-6`); what is not a
/// number is then reported by the option's parser.
pub fn allow_negative_values(cmd: clap::Command) -> clap::Command {
    cmd.mut_args(|a| {
        if !a.get_action().takes_values() {
            a
        } else if a.get_value_parser().type_id() == std::any::TypeId::of::<f64>() {
            a.allow_hyphen_values(true)
        } else {
            a.allow_negative_numbers(true)
        }
    })
    .mut_subcommands(allow_negative_values)
}

/// Parses the command line (see [`allow_negative_values`]); exits with clap's message on
/// a usage error.
pub fn parse() -> Cli {
    let args = help_request(&Cli::command(), std::env::args_os().collect());
    let matches = allow_negative_values(Cli::command()).get_matches_from(args);
    Cli::from_arg_matches(&matches).unwrap_or_else(|e| e.exit())
}

/// The command line to parse: `args` itself, or, when it asks for help (`--help` or `-h`
/// anywhere after the subcommands), the subcommands followed by `--help` alone. A
/// real-valued option takes a value starting with `-` ([`allow_negative_values`]), so
/// `torso simulate --rtol --help` would otherwise read `--help` as the tolerance and report
/// it as not a number; a request for help is answered with help wherever it stands.
pub fn help_request(cmd: &clap::Command, args: Vec<std::ffi::OsString>) -> Vec<std::ffi::OsString> {
    let asks_help = args.iter().skip(1).any(|a| a == "--help" || a == "-h");
    if !asks_help {
        return args;
    }
    let mut kept: Vec<std::ffi::OsString> = args.iter().take(1).cloned().collect();
    let mut current = cmd;
    for a in args.iter().skip(1) {
        match a.to_str().and_then(|s| current.find_subcommand(s)) {
            Some(sub) => {
                kept.push(a.clone());
                current = sub;
            }
            None => break,
        }
    }
    kept.push("--help".into());
    kept
}

/// Entry point: parses arguments, runs the subcommand, returns the process exit code.
pub fn main() -> i32 {
    let cli = parse();
    let result: crate::Result<()> = match cli.command {
        Command::Simulate(args) => simulate::main(&args),
        Command::Version => {
            println!("torso {}", env!("CARGO_PKG_VERSION"));
            Ok(())
        }
        Command::Fmu(args) => fmu::run(args),
        Command::Validate(a) => validate::run(&a),
        Command::SynthSpirometry(a) => validate::run_synth(&a),
        Command::Synth(a) => synth::main(&a),
        Command::Fit(a) => fit::main(&a),
        Command::Inspect(a) => inspect::inspect(&a),
        Command::Convert(a) => inspect::convert(&a),
        Command::FitSweep(a) => fit::sweep(&a),
        Command::Demo(a) => fit::demo(&a),
        Command::ExportObj(a) => skin::export_obj(&a),
        Command::RenderSkin(a) => skin::render_skin(&a),
        Command::Mesh { command } => mesh::run(command),
        Command::Bench { command } => bench::run(command),
    };
    match result {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
