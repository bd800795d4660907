//! `torso bench`: measured figures of the model, each reproducible by one command.
//!
//! - `core`: 1000 frames of quiet breathing at 56 Hz reading the volumes, then the same run
//!   reading the 60 markers too, their ratio, and the nanoseconds per right-hand-side
//!   evaluation per level of detail;
//! - `work-precision`: wall time and right-hand-side evaluations against the error (lung
//!   volume, marker positions) for every method and tolerance, against a high-order
//!   reference at rtol 1e-12, and for a fixed-step semi-implicit Euler at a range of step
//!   sizes; CSV (and the reference frames, for external integrators to compare against) and
//!   a log-log PNG; with `--formulation quasi-static`, the quasi-static mode at rtol 1e-3 ..
//!   1e-9 against its own rtol 1e-10 run, with the static solves' work counts;
//! - `soak`: many random scenes from the declared parameter ranges, each simulated for a
//!   minute: no NaN, no blow-up, every numerical failure listed;
//! - `relaxation`: the relaxed chest wall's and respiratory system's static pressure-volume
//!   curves from RV to TLC, their compliances over the tidal range and relaxation volumes,
//!   beside the cited adult figures;
//! - `physiology`: the physiological figures of issue 35 against their cited ranges
//!   (`src/cli/bench_physiology.rs`);
//! - `report`: the headline figures of one run, written as BENCHMARKS.md
//!   (`src/cli/bench_report.rs`).

use crate::bench::{
    FRAME_RATE, FrameRun, Reads, RhsCost, SceneOutcome, Trajectory, TrajectoryError, frame_loop,
    lung_loop, median, random_scene, rhs_cost, stress_scene, trajectory, trajectory_error,
    trajectory_semi_implicit,
};
use crate::model::{Config, Drive};
use crate::numeric::rng::Pcg64;
use crate::solver::Method;
use crate::stats::plot::{BLUE, DARK, Mark, ORANGE, Panel, RED, Trace, write_figure};
use crate::{Error, Result};
use clap::{Args, Subcommand};
use serde::Serialize;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The benchmarks.
#[derive(Subcommand, Debug)]
pub enum BenchCommand {
    /// Frame-loop wall time (volumes only, 60 markers, whole skin) and right-hand-side cost per level of detail.
    Core(CoreArgs),
    /// Wall time and RHS evaluations against error for every method and tolerance.
    WorkPrecision(WorkPrecisionArgs),
    /// Random scenes from the declared parameter ranges: no NaN, no blow-up.
    Soak(SoakArgs),
    /// Square waves, held maximal activation, an hour's drift, communication steps.
    Stress(super::bench_stress::StressArgs),
    /// What the FMU's instance adds per communication step, against the model facade.
    Fmu(FmuArgs),
    /// The relaxed chest wall's and respiratory system's pressure-volume curves.
    Relaxation(RelaxationArgs),
    /// The physiological figures (compliance, shares, excursions, maximal pressures, a
    /// paralysed hemidiaphragm) against their cited ranges.
    Physiology(super::bench_physiology::PhysiologyArgs),
    /// The current headline figures from one run, as a markdown file stamped with the
    /// commit and the machine, each table with the command that reproduces it.
    Report(super::bench_report::ReportArgs),
}

/// Options of `torso bench core`.
#[derive(Args, Debug)]
pub struct CoreArgs {
    /// Frames at 56 Hz.
    #[arg(long, default_value_t = 1000)]
    pub frames: usize,
    /// Timed repetitions (median reported).
    #[arg(long, default_value_t = 5)]
    pub repeats: usize,
    /// Level of detail of the frame loops (0, 1 or 2).
    #[arg(long, default_value_t = 1)]
    pub lod: u32,
    /// Right-hand-side calls per timed batch.
    #[arg(long, default_value_t = 2000)]
    pub rhs_calls: usize,
    /// ODE solver of the frame loops: dopri5, bs3, high-order, rosenbrock or quasi-static (also taken as
    /// its former name, --method).
    #[arg(long = "solver", alias = "method", default_value = "dopri5")]
    pub method: String,
    /// Inspiratory fraction Ti/Ttot of the quiet drive (0.2-0.8; 0.5 is the sine of thesis
    /// eq. 2.4).
    #[arg(long, default_value_t = 0.5)]
    pub ti_ttot: f64,
    /// Muscle law: thesis or hill (`params.muscle_law`).
    #[arg(long, default_value = "thesis")]
    pub muscle_law: String,
    /// Also write the figures as JSON.
    #[arg(long)]
    pub json: Option<PathBuf>,
}

/// Options of `torso bench work-precision`.
#[derive(Args, Debug)]
pub struct WorkPrecisionArgs {
    /// Output directory (CSV, PNG, SVG).
    #[arg(long, default_value = "out/bench")]
    pub out: PathBuf,
    /// Scenario: quiet or forced.
    #[arg(long, default_value = "quiet")]
    pub scenario: String,
    /// Simulated duration [s].
    #[arg(long, default_value_t = 8.0)]
    pub duration: f64,
    /// Timed runs per combination (median reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Wall-time cap of one run [s]; slower combinations are reported as skipped.
    #[arg(long, default_value_t = 20.0)]
    pub cap: f64,
    /// Level of detail.
    #[arg(long, default_value_t = 1)]
    pub lod: u32,
    /// Nominal step sizes [s] of the fixed-step semi-implicit Euler runs, comma-separated,
    /// largest first (an empty list skips them).
    #[arg(
        long,
        value_delimiter = ',',
        default_value = "2e-3,1e-3,5e-4,2e-4,1e-4,5e-5,2e-5,1e-5"
    )]
    pub fixed_steps: Vec<f64>,
    /// Stiff variant of the scene: default, stiff-cartilage (cartilage joints 10x stiffer),
    /// high-bulk (abdominal bulk modulus 10x) or fine-mesh (level of detail 2).
    #[arg(long, default_value = "default")]
    pub scene: String,
    /// Formulation: inertial (every method against a high-order rtol 1e-12 reference, and
    /// the semi-implicit Euler) or quasi-static (the quasi-static mode at rtol 1e-3 .. 1e-9
    /// against its own rtol 1e-10 run, with the static solves' work counts).
    #[arg(long, default_value = "inertial")]
    pub formulation: String,
}

/// Options of `torso bench soak`.
#[derive(Args, Debug)]
pub struct SoakArgs {
    /// Number of random scenes.
    #[arg(long, default_value_t = 500)]
    pub scenes: usize,
    /// Simulated seconds per scene.
    #[arg(long, default_value_t = 60.0)]
    pub seconds: f64,
    /// Random seed.
    #[arg(long, default_value_t = 2011)]
    pub seed: u64,
    /// Level of detail.
    #[arg(long, default_value_t = 0)]
    pub lod: u32,
    /// Output check rate [Hz].
    #[arg(long, default_value_t = 56.0)]
    pub rate: f64,
    /// ODE solver of every scene: dopri5, bs3, high-order, rosenbrock or quasi-static.
    #[arg(long = "solver", default_value = "dopri5")]
    pub solver: String,
}

/// Options of `torso bench fmu`.
#[derive(Args, Debug)]
pub struct FmuArgs {
    /// Communication steps of 1/56 s per loop.
    #[arg(long, default_value_t = 1000)]
    pub frames: usize,
    /// Loops of each kind, alternating (medians reported).
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Level of detail.
    #[arg(long, default_value_t = 1)]
    pub lod: u32,
    /// ODE solver: dopri5, bs3, high-order, rosenbrock or quasi-static.
    #[arg(long = "solver", default_value = "dopri5")]
    pub solver: String,
}

/// Options of `torso bench relaxation`.
#[derive(Args, Debug)]
pub struct RelaxationArgs {
    /// Level of detail.
    #[arg(long, default_value_t = 1)]
    pub lod: u32,
    /// Postures, comma-separated: standing, sitting, supine.
    #[arg(long, default_value = "standing,supine")]
    pub posture: String,
    /// Volumes from RV to TLC.
    #[arg(long, default_value_t = 25)]
    pub points: usize,
    /// Print every point of the curves.
    #[arg(long)]
    pub curves: bool,
    /// Muscle law: thesis (a shortening linear spring) or hill (passive and active parts,
    /// with the passive wall fitted for it, `HILL_PASSIVE_WALL_SCALE`).
    #[arg(long, default_value = "thesis")]
    pub muscle_law: String,
    /// Fit the factor on the passive wall's hand-set stiffnesses so that the relaxed chest
    /// wall's compliance over the tidal range is the adult's 0.2 L/cmH2O, for the first
    /// posture given, starting from the muscle law's unscaled wall; then print the curves
    /// with the fitted factor.
    #[arg(long)]
    pub fit: bool,
    /// Fit the passive wall's two compartments apart (the cartilage joints' stiffness and the
    /// abdominal wall's, `Params::scale_compartments`, from the muscle law's wall before its
    /// compartments' factors, `Params::before_compartments`) so that
    /// the relaxed rib cage's and diaphragm-abdomen's compliances over the tidal range are
    /// young seated adults' (Estenne et al. 1985: 0.164 and 0.032 L/cmH2O), for the first
    /// posture given (sitting, as they were measured); then print the curves of every
    /// posture with the fitted factors. Not with --fit.
    #[arg(long)]
    pub fit_compartments: bool,
    /// How gravity loads the model: preloaded (each posture's generated anatomy is its rest)
    /// or acting (the standing anatomy with gravity turned; each posture's rest, its relaxed
    /// FRC, found under the loads and printed).
    #[arg(long, default_value = "preloaded")]
    pub gravity_loads: String,
}

/// Runs `torso bench relaxation`: the default subject's curves in each posture.
fn relaxation(args: &RelaxationArgs) -> Result<()> {
    use crate::anatomy::Posture;
    use crate::bench::relaxation::{CMH2O, TIDAL_RANGE, relaxation};
    if args.lod > 2 {
        return Err(Error::invalid("--lod", args.lod, "0, 1 or 2"));
    }
    println!(
        "relaxed chest wall (pleural pressure, airway shut) and respiratory system (alveolar \
         pressure), default subject, level of detail {}, quasi-static equilibria; compliance \
         over FRC to FRC + {TIDAL_RANGE} L; adult figures: chest wall 0.2 L/cmH2O (Agostoni & \
         Mead 1964; Estenne et al. 1985: 0.166 seated, 0.158 supine, of which the rib cage \
         0.141 and 0.088, the diaphragm-abdomen 0.025 and 0.070; relaxed, the diaphragm \
         carries none of it, Agostoni & Rahn 1960), system about 0.1 \
         L/cmH2O, chest wall relaxed near 55-60 % of vital capacity, pleural pressure about \
         -5 cmH2O at FRC",
        args.lod
    );
    use crate::bench::relaxation::fit_passive_wall;
    use crate::dynamics::CHEST_WALL_COMPLIANCE;
    let law = crate::dynamics::muscle::MuscleLaw::parse(&args.muscle_law)
        .map_err(|_| Error::invalid("--muscle-law", &args.muscle_law, "thesis or hill"))?;
    let loads = crate::dynamics::GravityLoads::parse(&args.gravity_loads).map_err(|_| {
        Error::invalid(
            "--gravity-loads",
            &args.gravity_loads,
            "preloaded or acting",
        )
    })?;
    let acting = loads == crate::dynamics::GravityLoads::Acting;
    if args.fit && args.fit_compartments {
        return Err(Error::invalid(
            "--fit-compartments",
            "with --fit",
            "one fit at a time: --fit or --fit-compartments",
        ));
    }
    let mut fitted: Option<f64> = None;
    let mut fitted_compartments: Option<(f64, f64)> = None;
    for name in args.posture.split(',') {
        let posture = Posture::from_name(name.trim())
            .map_err(|_| Error::invalid("--posture", name, "standing, sitting or supine"))?;
        let mut config = Config::default();
        config.scene.level_of_detail = args.lod;
        config.subject.posture = posture;
        // gravity acting: every posture has the standing anatomy's constants
        let tables = if acting { Posture::Standing } else { posture };
        let mut params = crate::dynamics::Params::for_posture_and_law(tables, law);
        if let Some(f) = fitted {
            params = crate::dynamics::Params::unscaled_for_posture_and_law(tables, law);
            params.scale_passive_wall(f);
        }
        params.gravity_loads = loads;
        if args.fit && fitted.is_none() {
            let mut unscaled = crate::dynamics::Params::unscaled_for_posture_and_law(tables, law);
            unscaled.gravity_loads = loads;
            config.params = Some(unscaled.clone());
            let steps = fit_passive_wall(&config, CHEST_WALL_COMPLIANCE)?;
            for s in &steps {
                println!(
                    "fit ({posture:?}): factor {:.4}: C_cw {:.4} L/cmH2O",
                    s.factor, s.compliance
                );
            }
            let f = steps[steps.len() - 1].factor;
            println!(
                "fitted factor on the passive wall ({:?} law): {f:.3} (C_cw {:.4} L/cmH2O against \
                 {CHEST_WALL_COMPLIANCE})",
                law,
                steps[steps.len() - 1].compliance
            );
            fitted = Some(f);
            params = unscaled;
            params.scale_passive_wall(f);
        }
        if args.fit_compartments {
            use crate::bench::relaxation::{SEATED_COMPARTMENTS, fit_compartments};
            params = crate::dynamics::Params::before_compartments(tables, law);
            if fitted_compartments.is_none() {
                params.gravity_loads = loads;
                config.params = Some(params.clone());
                let steps = fit_compartments(&config, SEATED_COMPARTMENTS)?;
                for s in &steps {
                    println!(
                        "fit ({posture:?}): cartilage x{:.4}, abdominal wall x{:.4}: rib cage \
                         {:.4}, abdomen {:.4} L/cmH2O",
                        s.cartilage, s.abdominal_wall, s.rib_cage, s.abdomen
                    );
                }
                let last = steps[steps.len() - 1];
                println!(
                    "fitted factors on the compartments ({law:?} law): cartilage {:.4}, abdominal \
                     wall {:.3} (rib cage {:.4}, abdomen {:.4} L/cmH2O against {:?})",
                    last.cartilage,
                    last.abdominal_wall,
                    last.rib_cage,
                    last.abdomen,
                    SEATED_COMPARTMENTS
                );
                fitted_compartments = Some((last.cartilage, last.abdominal_wall));
            }
            if let Some((c, a)) = fitted_compartments {
                params.scale_compartments(c, a);
            }
        }
        params.gravity_loads = loads;
        if acting {
            // the rest of the wall the curves are measured on (after any fit)
            let mut c = config.clone();
            c.params = Some(params.clone());
            let (v, p) = crate::bench::relaxation::relaxed_frc(&c)?;
            println!(
                "{posture:?}, gravity acting: relaxed FRC {v:.4} L, pleural pressure {:.2} cmH2O",
                p / CMH2O
            );
        }
        config.params = Some(params);
        let r = relaxation(&config, args.points)?;
        let pct = |f: Option<f64>| f.map_or("none".to_string(), |f| format!("{:.1} %", 100.0 * f));
        println!(
            "{posture:?}: RV {:.3} L, FRC {:.3} L, TLC {:.3} L; C_cw {:.4} L/cmH2O (rib cage \
             {:.4}, abdomen {:.4}; the diaphragm carries {:.2} of the pleural pressure's change, \
             the abdomen's own compliance {:.4}), C_rs {:.4} L/cmH2O; chest wall relaxed at {} of \
             VC, system at {} of VC; pleural pressure at FRC {:.2} cmH2O; curve {:.3}-{:.3} L ({} \
             points){}",
            r.rv,
            r.frc,
            r.tlc,
            r.chest_wall_compliance,
            r.rib_cage_compliance,
            r.abdomen_compliance,
            r.diaphragm_share,
            r.abdominal_wall_compliance,
            r.system_compliance,
            pct(r.chest_wall_relaxation),
            pct(r.system_relaxation),
            r.pleural_at_frc / CMH2O,
            r.points.first().map_or(f64::NAN, |p| p.lung),
            r.points.last().map_or(f64::NAN, |p| p.lung),
            r.points.len(),
            r.failed
                .iter()
                .map(|(v, e)| format!("; no equilibrium at {v:.3} L: {e}"))
                .collect::<String>()
        );
        if args.curves {
            println!("  lung [L]   P_cw [cmH2O]   P_rs [cmH2O]");
            for p in &r.points {
                println!(
                    "  {:8.3}   {:12.3}   {:12.3}",
                    p.lung,
                    p.chest_wall / CMH2O,
                    p.system / CMH2O
                );
            }
        }
    }
    Ok(())
}

/// The solver named by `--solver`.
pub fn solver_flag(name: &str) -> Result<Method> {
    Method::from_name(name).ok_or_else(|| {
        Error::invalid(
            "--solver",
            name,
            "dopri5, bs3, high-order, rosenbrock or quasi-static",
        )
    })
}

fn fmu(args: &FmuArgs) -> Result<()> {
    if args.lod > 2 {
        return Err(Error::invalid("--lod", args.lod, "0, 1 or 2"));
    }
    let method = solver_flag(&args.solver)?;
    let f = crate::bench::fmu::fmu_overhead(method, args.lod, args.frames, args.repeats)?;
    println!(
        "FMU instance against the model facade: default subject, quiet drive, {}, level of detail {}, {} steps of 1/56 s, {} values read per step, median of {} loops each",
        f.method, f.level_of_detail, f.frames, f.values, f.repeats
    );
    println!(
        "step          fmi do_step {:10.2} us   native advance_to {:10.2} us",
        f.fmi_step_us, f.native_step_us
    );
    println!(
        "first read    fmi get_real {:9.2} us   native reads {:15.2} us",
        f.fmi_first_read_us, f.native_first_read_us
    );
    println!(
        "read again    fmi get_real {:9.2} us   native reads {:15.2} us",
        f.fmi_read_again_us, f.native_read_again_us
    );
    println!(
        "whole loop    fmi {:.4} s   native {:.4} s   last step's values identical bit for bit: {}",
        f.fmi_loop_s,
        f.native_loop_s,
        if f.identical { "yes" } else { "no" }
    );
    Ok(())
}

/// Runs `torso bench ...`.
pub fn run(command: BenchCommand) -> Result<()> {
    match command {
        BenchCommand::Core(a) => core(&a),
        BenchCommand::WorkPrecision(a) => work_precision(&a),
        BenchCommand::Soak(a) => soak(&a),
        BenchCommand::Stress(a) => super::bench_stress::run(&a),
        BenchCommand::Fmu(a) => fmu(&a),
        BenchCommand::Relaxation(a) => relaxation(&a),
        BenchCommand::Physiology(a) => super::bench_physiology::run(&a),
        BenchCommand::Report(a) => super::bench_report::run(&a),
    }
}

/// Median figures of repeated frame loops.
#[derive(Debug, Serialize)]
pub struct LoopFigures {
    /// What was read after every frame.
    pub reads: Reads,
    /// Frames per loop.
    pub frames: usize,
    /// Loops timed.
    pub runs: usize,
    /// Median wall time of a loop [s].
    pub median_wall_s: f64,
    /// Shortest loop [s].
    pub min_wall_s: f64,
    /// Median wall time of the `Torso::new` before each loop [s].
    pub build_median_s: f64,
    /// Right-hand-side evaluations of the last loop (the same in every loop).
    pub rhs_evaluations: u64,
    /// Accepted steps of the last loop.
    pub steps: u64,
    /// Rejected steps of the last loop.
    pub rejected: u64,
    /// Median wall time per right-hand-side evaluation [ns].
    pub ns_per_rhs: f64,
}

/// The medians of repeated frame loops reading `reads`.
pub fn loop_figures(runs: &[FrameRun], reads: Reads, frames: usize) -> LoopFigures {
    let walls: Vec<f64> = runs.iter().map(|r| r.wall).collect();
    let builds: Vec<f64> = runs.iter().map(|r| r.build).collect();
    let last = runs.last().copied().unwrap_or_default();
    let med = median(&walls);
    LoopFigures {
        reads,
        frames,
        runs: runs.len(),
        median_wall_s: med,
        min_wall_s: walls.iter().copied().fold(f64::INFINITY, f64::min),
        build_median_s: median(&builds),
        rhs_evaluations: last.rhs_evaluations,
        steps: last.steps,
        rejected: last.rejected,
        ns_per_rhs: med * 1e9 / last.rhs_evaluations.max(1) as f64,
    }
}

#[derive(Debug, Serialize)]
struct CoreReport {
    subject: String,
    level_of_detail: u32,
    rtol: f64,
    volumes: LoopFigures,
    markers: LoopFigures,
    skin: LoopFigures,
    ratio_markers_over_volumes: f64,
    ratio_skin_over_volumes: f64,
    rhs: Vec<RhsCost>,
}

fn core(args: &CoreArgs) -> Result<()> {
    if args.frames == 0 || args.repeats == 0 || args.rhs_calls == 0 {
        return Err(Error::invalid(
            "--frames/--repeats/--rhs-calls",
            0,
            "at least 1",
        ));
    }
    let mut config = Config {
        drive: Drive::quiet(),
        ..Config::default()
    };
    crate::model::check(
        "--ti-ttot",
        args.ti_ttot,
        crate::model::drive::INSPIRATORY_FRACTION_RANGE,
    )?;
    config.drive.inspiratory_fraction = args.ti_ttot;
    config.scene.level_of_detail = args.lod;
    config.muscle_law = crate::dynamics::muscle::MuscleLaw::parse(&args.muscle_law)
        .map_err(|_| Error::invalid("--muscle-law", &args.muscle_law, "thesis or hill"))?;
    config.solver.method = Method::from_name(&args.method).ok_or_else(|| {
        Error::invalid(
            "--solver",
            &args.method,
            "dopri5, bs3, high-order, rosenbrock or quasi-static",
        )
    })?;
    config.validate()?;
    println!(
        "quiet breathing{}, default subject, level of detail {}, {} rtol {:e}, {} frames at 56 Hz, median of {}",
        if args.ti_ttot == crate::model::drive::SINE_FRACTION {
            String::new()
        } else {
            format!(" (Ti/Ttot {})", args.ti_ttot)
        },
        args.lod,
        config.solver.method.name(),
        config.solver.rtol,
        args.frames,
        args.repeats
    );
    let mut figures = Vec::new();
    let mut builds = Vec::new();
    for reads in [
        Reads::Volumes,
        Reads::VolumesAndMarkers,
        Reads::VolumesAndSkin,
    ] {
        let runs = (0..args.repeats)
            .map(|_| frame_loop(&config, args.frames, reads))
            .collect::<Result<Vec<_>>>()?;
        builds.extend(runs.iter().map(|r| r.build));
        let f = loop_figures(&runs, reads, args.frames);
        println!(
            "{:<22} median {:8.4} s  min {:8.4} s  RHS {:7}  steps {:6} (+{} rejected)  {:8.0} ns/RHS (wall/RHS)",
            match reads {
                Reads::Volumes => "volumes only",
                Reads::VolumesAndMarkers => "volumes + 60 markers",
                Reads::VolumesAndSkin => "volumes + whole skin",
            },
            f.median_wall_s,
            f.min_wall_s,
            f.rhs_evaluations,
            f.steps,
            f.rejected,
            f.ns_per_rhs
        );
        figures.push(f);
    }
    let [volumes, markers, skin] =
        <[LoopFigures; 3]>::try_from(figures).map_err(|_| Error::State("no runs".into()))?;
    let ratio = markers.median_wall_s / volumes.median_wall_s;
    let ratio_skin = skin.median_wall_s / volumes.median_wall_s;
    println!(
        "Torso::new              median {:8.4} s over {} builds (the model and its start state)",
        median(&builds),
        builds.len()
    );
    println!("ratio (60 markers / volumes only): {ratio:.2}");
    println!("ratio (whole skin / volumes only): {ratio_skin:.2}");
    let mut rhs = Vec::new();
    println!(
        "right-hand side of the inertial equations, median of 5 batches of {} calls:",
        args.rhs_calls
    );
    for lod in 0..=2 {
        let mut c = config.clone();
        c.scene.level_of_detail = lod;
        // the inertial right-hand side's cost: the quasi-static mode has none of that size
        // (its right-hand side is a static solve; its work is in the frame loops above)
        c.solver.method = Method::Dopri5;
        let r = rhs_cost(&c, args.rhs_calls, 5)?;
        println!(
            "  level of detail {lod}: state {:5}  rest {:9.0} ns  breathing {:9.0} ns",
            r.state_dim, r.ns_rest, r.ns_breathing
        );
        rhs.push(r);
    }
    if let Some(path) = &args.json {
        let report = CoreReport {
            subject: "default (male, 30 y, 1.75 m, 75 kg, standing)".into(),
            level_of_detail: args.lod,
            rtol: config.solver.rtol,
            volumes,
            markers,
            skin,
            ratio_markers_over_volumes: ratio,
            ratio_skin_over_volumes: ratio_skin,
            rhs,
        };
        let text = serde_json::to_string_pretty(&report)
            .map_err(|e| Error::State(format!("JSON: {e}")))?;
        write_text(path, &text)?;
        println!("wrote {}", path.display());
    }
    Ok(())
}

fn write_text(path: &Path, text: &str) -> Result<()> {
    let io = |e| Error::Io {
        path: path.to_path_buf(),
        source: e,
    };
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(io)?;
    }
    let mut f = std::fs::File::create(path).map_err(io)?;
    f.write_all(text.as_bytes()).map_err(io)
}

/// One work-precision point.
#[derive(Debug, Clone)]
struct Point {
    method: Method,
    rtol: f64,
    /// `None` when skipped (over the cap) or failed; the reason.
    result: std::result::Result<(f64, u64, u64, TrajectoryError, bool, u64), String>,
}

fn work_precision(args: &WorkPrecisionArgs) -> Result<()> {
    let drive = match args.scenario.as_str() {
        "quiet" => Drive::quiet(),
        "forced" => Drive::forced(),
        other => return Err(Error::invalid("--scenario", other, "quiet or forced")),
    };
    if !(args.duration > 0.0 && args.duration <= 3600.0) {
        return Err(Error::invalid("--duration", args.duration, "(0, 3600] s"));
    }
    if args.cap.is_nan() || args.cap <= 0.0 || args.repeats == 0 {
        return Err(Error::invalid("--cap/--repeats", args.cap, "> 0"));
    }
    let mut base = Config {
        drive,
        ..Config::default()
    };
    base.scene.level_of_detail = args.lod;
    let mut params = crate::dynamics::Params::for_posture(base.subject.posture);
    match args.scene.as_str() {
        "default" => {}
        "stiff-cartilage" => params.cartilage_stiffness *= 10.0,
        "high-bulk" => params.bulk_modulus *= 10.0,
        "fine-mesh" => base.scene.level_of_detail = 2,
        other => {
            return Err(Error::invalid(
                "--scene",
                other,
                "default, stiff-cartilage, high-bulk or fine-mesh",
            ));
        }
    }
    if args.scene != "default" {
        base.params = Some(params);
    }
    match args.formulation.as_str() {
        "inertial" => {}
        "quasi-static" => return work_precision_quasi(args, &base),
        other => {
            return Err(Error::invalid(
                "--formulation",
                other,
                "inertial or quasi-static",
            ));
        }
    }
    let mut rc = base.clone();
    rc.solver.method = Method::HighOrder;
    rc.solver.rtol = 1e-12;
    rc.solver.atol = 1e-14;
    rc.validate()?;
    println!(
        "{} breathing ({} scene), {} s, level of detail {}: reference {} rtol 1e-12 atol 1e-14 ...",
        args.scenario,
        args.scene,
        args.duration,
        base.scene.level_of_detail,
        Method::HighOrder.name()
    );
    let reference: Trajectory = trajectory(&rc, args.duration, f64::INFINITY)?
        .ok_or_else(|| Error::State("reference run abandoned".into()))?;
    println!(
        "reference: {:.2} s, {} RHS evaluations, stiffness flag {}",
        reference.wall, reference.rhs_evaluations, reference.stiffness_detected
    );
    let name = if args.scene == "default" {
        format!("work_precision_{}", args.scenario)
    } else {
        format!("work_precision_{}_{}", args.scenario, args.scene)
    };
    std::fs::create_dir_all(&args.out).map_err(|e| Error::Io {
        path: args.out.clone(),
        source: e,
    })?;
    // written now, so that an external integrator can be scored while the sweep runs
    let reference_path = args.out.join(format!("{name}_reference.csv"));
    write_reference(
        &reference_path,
        args,
        &base,
        &reference,
        &format!("method={} rtol=1e-12 atol=1e-14", Method::HighOrder.name()),
    )?;
    println!("reference frames: {}", reference_path.display());
    let rtols: Vec<f64> = (3..=10).map(|k| 10f64.powi(-k)).collect();
    let mut points = Vec::new();
    println!(
        "{:<11} {:>7} {:>10} {:>9} {:>8} {:>11} {:>11} {:>6}",
        "method", "rtol", "wall [s]", "RHS", "steps", "lung [L]", "marker [m]", "stiff"
    );
    for method in Method::ALL {
        let mut over_cap = false;
        for &rtol in &rtols {
            let mut c = base.clone();
            c.solver.method = method;
            c.solver.rtol = rtol;
            // atol follows rtol two decades below (on states of order 1e-2 m), within range
            c.solver.atol = (rtol * 1e-2).max(1e-14);
            c.validate()?;
            let result = if over_cap {
                Err("skipped: a looser tolerance already exceeded the time cap".to_string())
            } else {
                measure(&c, args, &reference)
            };
            if let Err(reason) = &result
                && reason.starts_with("skipped")
            {
                over_cap = true;
            }
            match &result {
                Ok((wall, rhs, steps, err, stiff, _)) => println!(
                    "{:<11} {:>7.0e} {:>10.4} {:>9} {:>8} {:>11.3e} {:>11.3e} {:>6}",
                    method.name(),
                    rtol,
                    wall,
                    rhs,
                    steps,
                    err.lung,
                    err.markers,
                    stiff
                ),
                Err(reason) => println!("{:<11} {:>7.0e} {reason}", method.name(), rtol),
            }
            points.push(Point {
                method,
                rtol,
                result,
            });
        }
    }
    let mut csv = String::from(
        "method,rtol,atol,status,wall_s,rhs_evaluations,steps,lung_error_l,marker_error_m,stiffness_flag,stiff_steps\n",
    );
    for p in &points {
        let atol = (p.rtol * 1e-2).max(1e-14);
        match &p.result {
            Ok((wall, rhs, steps, err, stiff, stiff_steps)) => csv.push_str(&format!(
                "{},{:e},{:e},ok,{wall},{rhs},{steps},{:e},{:e},{stiff},{stiff_steps}\n",
                p.method.name(),
                p.rtol,
                atol,
                err.lung,
                err.markers
            )),
            Err(reason) => csv.push_str(&format!(
                "{},{:e},{:e},\"{}\",,,,,,,\n",
                p.method.name(),
                p.rtol,
                atol,
                reason.replace('"', "'")
            )),
        }
    }
    csv.push_str(&format!(
        "# reference: {} rtol 1e-12 atol 1e-14, {} RHS evaluations, stiffness flag {}\n",
        Method::HighOrder.name(),
        reference.rhs_evaluations,
        reference.stiffness_detected
    ));
    let csv_path = args.out.join(format!("{name}.csv"));
    write_text(&csv_path, &csv)?;
    let fixed = fixed_step_sweep(&base, args, &reference)?;
    write_text(
        &args.out.join(format!("{name}_fixed.csv")),
        &fixed_csv(&fixed),
    )?;
    let label = if args.scene == "default" {
        args.scenario.clone()
    } else {
        format!("{} ({})", args.scenario, args.scene)
    };
    plot(&args.out, &name, &label, &points, &fixed)?;
    println!(
        "wrote {}, {}_fixed.csv and {}",
        csv_path.display(),
        name,
        args.out.join(format!("{name}.png")).display()
    );
    let flagged: Vec<String> = points
        .iter()
        .filter(|p| matches!(p.result, Ok((_, _, _, _, true, _))))
        .map(|p| format!("{} {:e}", p.method.name(), p.rtol))
        .collect();
    if flagged.is_empty() {
        println!("explicit solver's stiffness flag: not raised in any run");
    } else {
        println!(
            "explicit solver's stiffness flag raised in: {} (compare the rosenbrock rows)",
            flagged.join(", ")
        );
    }
    Ok(())
}

type Measured = (f64, u64, u64, TrajectoryError, bool, u64);

fn measure(
    c: &Config,
    args: &WorkPrecisionArgs,
    reference: &Trajectory,
) -> std::result::Result<Measured, String> {
    let mut walls = Vec::new();
    let mut last = None;
    for _ in 0..args.repeats {
        match trajectory(c, args.duration, args.cap) {
            Ok(Some(t)) => {
                walls.push(t.wall);
                last = Some(t);
            }
            Ok(None) => return Err(format!("skipped: over the {} s time cap", args.cap)),
            Err(e) => return Err(format!("failed: {e}")),
        }
    }
    finish(last, &walls, reference)
}

/// Median wall time, counts and error of the last of repeated runs.
fn finish(
    last: Option<Trajectory>,
    walls: &[f64],
    reference: &Trajectory,
) -> std::result::Result<Measured, String> {
    let t = last.ok_or_else(|| "no run".to_string())?;
    let err = trajectory_error(&t, reference).map_err(|e| e.to_string())?;
    Ok((
        median(walls),
        t.rhs_evaluations,
        t.steps,
        err,
        t.stiffness_detected,
        t.stiff_steps,
    ))
}

/// Label, colour, log10 wall times, log10 lung errors, log10 marker errors.
type Series = (String, (u8, u8, u8), Vec<f64>, Vec<f64>, Vec<f64>);

fn plot(
    dir: &Path,
    name: &str,
    scenario: &str,
    points: &[Point],
    fixed: &[FixedPoint],
) -> Result<()> {
    let colors = [BLUE, RED, ORANGE, DARK];
    let mut series: Vec<Series> = Vec::new();
    for (i, m) in Method::ALL.iter().enumerate() {
        let (mut x, mut yl, mut ym) = (Vec::new(), Vec::new(), Vec::new());
        for p in points.iter().filter(|p| p.method == *m) {
            if let Ok((wall, _, _, err, _, _)) = &p.result {
                x.push(wall.max(1e-9).log10());
                yl.push(err.lung.max(1e-16).log10());
                ym.push(err.markers.max(1e-16).log10());
            }
        }
        series.push((m.name().to_string(), colors[i % colors.len()], x, yl, ym));
    }
    let (mut x, mut yl, mut ym) = (Vec::new(), Vec::new(), Vec::new());
    for p in fixed {
        if let Ok((wall, _, _, err, _, _)) = &p.result {
            x.push(wall.max(1e-9).log10());
            yl.push(err.lung.max(1e-16).log10());
            ym.push(err.markers.max(1e-16).log10());
        }
    }
    series.push((SEMI_IMPLICIT.to_string(), GREEN, x, yl, ym));
    let panel = |title: &str, y_label: &str, lung: bool| Panel {
        title: title.to_string(),
        x_label: "log10 wall time [s]".into(),
        y_label: y_label.to_string(),
        traces: series
            .iter()
            .flat_map(|(label, color, x, yl, ym)| {
                let y = if lung { yl } else { ym };
                [
                    Trace {
                        label: label.clone(),
                        x,
                        y,
                        color: *color,
                        mark: Mark::Line,
                    },
                    Trace {
                        label: String::new(),
                        x,
                        y,
                        color: *color,
                        mark: Mark::Points,
                    },
                ]
            })
            .collect(),
        hlines: Vec::new(),
        bands: Vec::new(),
    };
    write_figure(
        dir,
        name,
        &[
            panel(
                &format!("Work-precision, {scenario} breathing: lung volume"),
                "log10 max |lung volume error| [L]",
                true,
            ),
            panel(
                &format!("Work-precision, {scenario} breathing: 60 markers"),
                "log10 max marker error [m]",
                false,
            ),
        ],
    )
}

/// Name of the fixed-step semi-implicit Euler runs in tables and plots.
const SEMI_IMPLICIT: &str = "semi-implicit-euler";
/// Plot colour of the semi-implicit Euler runs.
const GREEN: (u8, u8, u8) = (40, 150, 60);

/// One fixed-step run of the semi-implicit Euler method.
#[derive(Debug, Clone)]
struct FixedPoint {
    step: f64,
    result: std::result::Result<Measured, String>,
}

/// The semi-implicit Euler method at every `--fixed-steps` size: an unstable step size
/// (non-finite state) is reported as such; once a size exceeds the time cap the smaller ones
/// are skipped.
fn fixed_step_sweep(
    base: &Config,
    args: &WorkPrecisionArgs,
    reference: &Trajectory,
) -> Result<Vec<FixedPoint>> {
    if let Some(h) = args
        .fixed_steps
        .iter()
        .find(|h| !(h.is_finite() && **h > 0.0 && **h <= 1.0 / FRAME_RATE))
    {
        return Err(Error::invalid(
            "--fixed-steps",
            h,
            format!("(0, {:e}] s (one frame)", 1.0 / FRAME_RATE),
        ));
    }
    let mut out = Vec::new();
    let mut over_cap = false;
    for &step in &args.fixed_steps {
        let result = if over_cap {
            Err("skipped: a larger step already exceeded the time cap".to_string())
        } else {
            let mut walls = Vec::new();
            let mut last = None;
            let mut failure = None;
            for _ in 0..args.repeats {
                match trajectory_semi_implicit(base, args.duration, step, args.cap) {
                    Ok(Some(t)) => {
                        walls.push(t.wall);
                        last = Some(t);
                    }
                    Ok(None) => {
                        over_cap = true;
                        failure = Some(format!("skipped: over the {} s time cap", args.cap));
                        break;
                    }
                    Err(Error::Numerical { time, .. }) => {
                        failure = Some(format!("unstable: non-finite state at t = {time:.4} s"));
                        break;
                    }
                    Err(e) => return Err(e),
                }
            }
            match failure {
                Some(reason) => Err(reason),
                None => finish(last, &walls, reference),
            }
        };
        match &result {
            Ok((wall, rhs, steps, err, _, _)) => println!(
                "{:<19} h {:>7.0e} {:>10.4} {:>9} {:>8} {:>11.3e} {:>11.3e}",
                SEMI_IMPLICIT, step, wall, rhs, steps, err.lung, err.markers
            ),
            Err(reason) => println!("{SEMI_IMPLICIT:<19} h {step:>7.0e} {reason}"),
        }
        out.push(FixedPoint { step, result });
    }
    Ok(out)
}

/// CSV of the fixed-step runs.
fn fixed_csv(fixed: &[FixedPoint]) -> String {
    let mut csv = String::from(
        "method,step_s,status,wall_s,rhs_evaluations,steps,lung_error_l,marker_error_m\n",
    );
    for p in fixed {
        match &p.result {
            Ok((wall, rhs, steps, err, _, _)) => csv.push_str(&format!(
                "{SEMI_IMPLICIT},{:e},ok,{wall},{rhs},{steps},{:e},{:e}\n",
                p.step, err.lung, err.markers
            )),
            Err(reason) => csv.push_str(&format!(
                "{SEMI_IMPLICIT},{:e},\"{}\",,,,,\n",
                p.step,
                reason.replace('"', "'")
            )),
        }
    }
    csv
}

/// Writes the reference solution's frames (time, lung volume, every marker) so that an
/// external integrator of the same right-hand side can be scored against the same reference;
/// the first line records the run and, under their FMI parameter names (for `bt_config_set`),
/// the level of detail and the drive, as `key=value` pairs.
fn write_reference(
    path: &Path,
    args: &WorkPrecisionArgs,
    base: &Config,
    reference: &Trajectory,
    run: &str,
) -> Result<()> {
    use std::fmt::Write as _;
    let markers = reference.markers.first().map_or(0, Vec::len);
    let d = &base.drive;
    let mut s = format!(
        "# scenario={} formulation={} duration={} frame_rate={} {run} \
         rhs_evaluations={} scene.level_of_detail={} solver.method={} drive.frequency={}",
        args.scenario,
        args.formulation,
        args.duration,
        FRAME_RATE,
        reference.rhs_evaluations,
        base.scene.level_of_detail,
        base.solver.method.code(),
        d.frequency
    );
    for (group, w) in [
        ("ribs", d.ribs),
        ("diaphragm", d.diaphragm),
        ("abdominals", d.abdominals),
    ] {
        let _ = write!(
            s,
            " drive.{group}.amplitude={} drive.{group}.phase={}",
            w.amplitude, w.phase
        );
    }
    s.push('\n');
    s.push_str("t_s,lung_l");
    for m in 1..=markers {
        let _ = write!(s, ",m{m}_x,m{m}_y,m{m}_z");
    }
    s.push('\n');
    for (i, (lung, frame)) in reference.lung.iter().zip(&reference.markers).enumerate() {
        let _ = write!(s, "{},{lung}", i as f64 / FRAME_RATE);
        for p in frame {
            let _ = write!(s, ",{},{},{}", p[0], p[1], p[2]);
        }
        s.push('\n');
    }
    write_text(path, &s)
}

fn soak(args: &SoakArgs) -> Result<()> {
    if args.scenes == 0
        || args.seconds.is_nan()
        || args.seconds <= 0.0
        || args.rate.is_nan()
        || args.rate <= 0.0
    {
        return Err(Error::invalid(
            "--scenes/--seconds/--rate",
            args.scenes,
            "positive values",
        ));
    }
    let method = Method::from_name(&args.solver).ok_or_else(|| {
        Error::invalid(
            "--solver",
            &args.solver,
            "dopri5, bs3, high-order, rosenbrock or quasi-static",
        )
    })?;
    let mut rng = Pcg64::new(args.seed, 6);
    let (mut ok, mut numerical, mut bounds) = (0, 0, 0);
    let start = std::time::Instant::now();
    let bar = super::progress::Progress::new("soak", args.scenes, "scenes");
    bar.update(0, "");
    for i in 0..args.scenes {
        let mut config = random_scene(&mut rng, args.lod)?;
        config.solver.method = method;
        match stress_scene(&config, args.seconds, args.rate)? {
            SceneOutcome::Ok { .. } => ok += 1,
            SceneOutcome::Numerical(reason) => {
                numerical += 1;
                println!("scene {i}: numerical failure: {reason}\n  {config:?}");
            }
            SceneOutcome::OutOfBounds { time, what } => {
                bounds += 1;
                println!("scene {i}: out of bounds at t = {time} s: {what}\n  {config:?}");
            }
        }
        bar.update(
            i + 1,
            format!("{ok} ok, {numerical} numerical failures, {bounds} out of bounds"),
        );
        if (i + 1) % 10 == 0 {
            println!(
                "{} scenes, {:.0} s wall: {ok} ok, {numerical} numerical failures, {bounds} out of bounds",
                i + 1,
                start.elapsed().as_secs_f64()
            );
        }
    }
    bar.finish(format!(
        "{ok} ok, {numerical} numerical failures, {bounds} out of bounds"
    ));
    println!(
        "soak: {} scenes x {} s (seed {}, level of detail {}, {}): {ok} ok, {numerical} numerical failures, {bounds} out of bounds, {:.0} s wall",
        args.scenes,
        args.seconds,
        args.seed,
        args.lod,
        method.name(),
        start.elapsed().as_secs_f64()
    );
    if numerical + bounds > 0 {
        return Err(Error::State(format!(
            "{} of {} scenes failed",
            numerical + bounds,
            args.scenes
        )));
    }
    Ok(())
}

/// One run of the quasi-static work-precision sweep.
#[derive(Debug, Clone)]
struct QuasiPoint {
    rtol: f64,
    /// Median wall times [s] with the markers read every frame and with the lung volume
    /// alone, the last run's trajectory, its errors over every frame and over the frames
    /// from [`SETTLED`] s on; or why not.
    result: std::result::Result<(f64, f64, Trajectory, TrajectoryError, TrajectoryError), String>,
}

/// Time [s] after which the quasi-static sweep also reports the errors: the first step's
/// error decays with the airway time constant (about 0.1 s), so from 0.5 s on what is left is
/// the integration's along the breath.
const SETTLED: f64 = 0.5;

/// The frames of `t` from [`SETTLED`] s on.
fn settled(t: &Trajectory) -> Trajectory {
    let first = ((SETTLED * FRAME_RATE).round() as usize).min(t.lung.len());
    Trajectory {
        lung: t.lung[first..].to_vec(),
        markers: t.markers[first.min(t.markers.len())..].to_vec(),
        ..Trajectory::default()
    }
}

/// `torso bench work-precision --formulation quasi-static`: the quasi-static mode at rtol
/// 1e-3 .. 1e-9 (atol rtol / 100, on the lung volume in litres) against its own run at rtol
/// 1e-10 (atol 1e-12), reading the lung volume and the markers every frame; the reference's
/// frames are written for `python/bench_scipy.py --formulation quasi-static`, which
/// integrates the same reduced right-hand side (`bt_quasi_rate`) with scipy.
fn work_precision_quasi(args: &WorkPrecisionArgs, base: &Config) -> Result<()> {
    let mut base = base.clone();
    base.solver.method = Method::QuasiStatic;
    let mut rc = base.clone();
    rc.solver.rtol = 1e-10;
    rc.solver.atol = 1e-12;
    rc.validate()?;
    println!(
        "{} breathing ({} scene), {} s, level of detail {}: reference quasi-static rtol 1e-10 atol 1e-12 ...",
        args.scenario, args.scene, args.duration, base.scene.level_of_detail
    );
    let reference = trajectory(&rc, args.duration, f64::INFINITY)?
        .ok_or_else(|| Error::State("reference run abandoned".into()))?;
    let rs = reference.statics.unwrap_or_default();
    println!(
        "reference: {:.2} s, {} steps, {} RHS evaluations, {} static solves, {} Newton iterations",
        reference.wall, reference.steps, reference.rhs_evaluations, rs.solves, rs.iterations
    );
    let name = if args.scene == "default" {
        format!("work_precision_{}_quasi_static", args.scenario)
    } else {
        format!(
            "work_precision_{}_{}_quasi_static",
            args.scenario, args.scene
        )
    };
    std::fs::create_dir_all(&args.out).map_err(|e| Error::Io {
        path: args.out.clone(),
        source: e,
    })?;
    let reference_path = args.out.join(format!("{name}_reference.csv"));
    write_reference(
        &reference_path,
        args,
        &base,
        &reference,
        "method=quasi-static rtol=1e-10 atol=1e-12",
    )?;
    println!("reference frames: {}", reference_path.display());
    println!(
        "{:<12} {:>6} {:>9} {:>9} {:>6} {:>7} {:>7} {:>8} {:>5} {:>10} {:>11} {:>10} {:>11}",
        "method",
        "rtol",
        "wall [s]",
        "lung-only",
        "steps",
        "RHS",
        "solves",
        "Newton",
        "LU",
        "lung [L]",
        "marker [mm]",
        "from 0.5 s",
        "from 0.5 s"
    );
    let mut points = Vec::new();
    let mut over_cap = false;
    for rtol in (3..=9).map(|k| 10f64.powi(-k)) {
        let mut c = base.clone();
        c.solver.rtol = rtol;
        c.solver.atol = rtol * 1e-2;
        c.validate()?;
        let result = if over_cap {
            Err("skipped: a looser tolerance already exceeded the time cap".to_string())
        } else {
            let mut walls = Vec::new();
            let mut last = None;
            let mut failure = None;
            for _ in 0..args.repeats {
                match trajectory(&c, args.duration, args.cap) {
                    Ok(Some(t)) => {
                        walls.push(t.wall);
                        last = Some(t);
                    }
                    Ok(None) => {
                        over_cap = true;
                        failure = Some(format!("skipped: over the {} s time cap", args.cap));
                        break;
                    }
                    Err(e) => {
                        failure = Some(format!("failed: {e}"));
                        break;
                    }
                }
            }
            let mut lung_walls = Vec::new();
            if failure.is_none() {
                for _ in 0..args.repeats {
                    match lung_loop(&c, args.duration) {
                        Ok((wall, _)) => lung_walls.push(wall),
                        Err(e) => {
                            failure = Some(format!("failed: {e}"));
                            break;
                        }
                    }
                }
            }
            match (failure, last) {
                (Some(reason), _) => Err(reason),
                (None, Some(t)) => trajectory_error(&t, &reference)
                    .and_then(|err| {
                        let late = trajectory_error(&settled(&t), &settled(&reference))?;
                        Ok((median(&walls), median(&lung_walls), t, err, late))
                    })
                    .map_err(|e| e.to_string()),
                (None, None) => Err("no run".to_string()),
            }
        };
        match &result {
            Ok((wall, lung_wall, t, err, late)) => {
                let s = t.statics.unwrap_or_default();
                println!(
                    "{:<12} {:>6.0e} {:>9.4} {:>9.4} {:>6} {:>7} {:>7} {:>8} {:>5} {:>10.3e} {:>11.3e} {:>10.3e} {:>11.3e}",
                    Method::QuasiStatic.name(),
                    rtol,
                    wall,
                    lung_wall,
                    t.steps,
                    t.rhs_evaluations,
                    s.solves,
                    s.iterations,
                    s.factorisations,
                    err.lung,
                    err.markers * 1e3,
                    late.lung,
                    late.markers * 1e3
                )
            }
            Err(reason) => println!("{:<12} {:>6.0e} {reason}", Method::QuasiStatic.name(), rtol),
        }
        points.push(QuasiPoint { rtol, result });
    }
    let mut csv = String::from(
        "method,rtol,atol,status,wall_s,wall_lung_only_s,rhs_evaluations,steps,lung_error_l,\
         marker_error_m,lung_error_settled_l,marker_error_settled_m,static_solves,\
         newton_iterations,jacobians,factorisations,residuals,continuations\n",
    );
    for p in &points {
        let atol = p.rtol * 1e-2;
        match &p.result {
            Ok((wall, lung_wall, t, err, late)) => {
                let s = t.statics.unwrap_or_default();
                csv.push_str(&format!(
                    "{},{:e},{:e},ok,{wall},{lung_wall},{},{},{:e},{:e},{:e},{:e},{},{},{},{},{},{}\n",
                    Method::QuasiStatic.name(),
                    p.rtol,
                    atol,
                    t.rhs_evaluations,
                    t.steps,
                    err.lung,
                    err.markers,
                    late.lung,
                    late.markers,
                    s.solves,
                    s.iterations,
                    s.jacobians,
                    s.factorisations,
                    s.residuals,
                    s.continuations
                ))
            }
            Err(reason) => csv.push_str(&format!(
                "{},{:e},{:e},\"{}\",,,,,,,,,,,,,,\n",
                Method::QuasiStatic.name(),
                p.rtol,
                atol,
                reason.replace('"', "'")
            )),
        }
    }
    csv.push_str(&format!(
        "# reference: quasi-static rtol 1e-10 atol 1e-12, {} steps, {} RHS evaluations, {} static solves, {} Newton iterations\n",
        reference.steps, reference.rhs_evaluations, rs.solves, rs.iterations
    ));
    let csv_path = args.out.join(format!("{name}.csv"));
    write_text(&csv_path, &csv)?;
    let series = |lung: bool| -> (Vec<f64>, Vec<f64>) {
        points
            .iter()
            .filter_map(|p| p.result.as_ref().ok())
            .map(|(wall, _, _, err, _)| {
                let e = if lung { err.lung } else { err.markers * 1e3 };
                (wall.max(1e-9).log10(), e.max(1e-16).log10())
            })
            .unzip()
    };
    let (xl, yl) = series(true);
    let (xm, ym) = series(false);
    fn panel<'a>(title: &str, y_label: &str, x: &'a [f64], y: &'a [f64]) -> Panel<'a> {
        Panel {
            title: title.to_string(),
            x_label: "log10 wall time [s]".into(),
            y_label: y_label.to_string(),
            traces: vec![
                Trace {
                    label: Method::QuasiStatic.name().to_string(),
                    x,
                    y,
                    color: BLUE,
                    mark: Mark::Line,
                },
                Trace {
                    label: String::new(),
                    x,
                    y,
                    color: BLUE,
                    mark: Mark::Points,
                },
            ],
            hlines: Vec::new(),
            bands: Vec::new(),
        }
    }
    write_figure(
        &args.out,
        &name,
        &[
            panel(
                &format!(
                    "Work-precision, {} breathing, quasi-static: lung volume",
                    args.scenario
                ),
                "log10 max |lung volume error| [L]",
                &xl,
                &yl,
            ),
            panel(
                &format!(
                    "Work-precision, {} breathing, quasi-static: markers",
                    args.scenario
                ),
                "log10 max marker error [mm]",
                &xm,
                &ym,
            ),
        ],
    )?;
    println!(
        "wrote {} and {}",
        csv_path.display(),
        args.out.join(format!("{name}.png")).display()
    );
    Ok(())
}
