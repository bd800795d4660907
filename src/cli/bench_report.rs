//! `torso bench report`: the project's current headline figures from one run on one machine,
//! written as a markdown file (BENCHMARKS.md) stamped with the commit, the date, the CPU and
//! its cores, each table with the command that reproduces it. The figures come from the
//! kernels the other `torso bench` commands use ([`crate::bench`]) and from `torso synth` and
//! `torso fit` run as their command lines say; nothing is measured here that those commands
//! do not measure. Counts (right-hand-side evaluations, steps, fit evaluations) are exact;
//! wall times are medians over the repeats stated in each table.

use super::bench::{LoopFigures, loop_figures};
use crate::bench::fmu::{FmuOverhead, fmu_overhead};
use crate::bench::{FrameRun, Reads, RhsCost, frame_loop, rhs_cost};
use crate::model::{Config, Drive};
use crate::solver::Method;
use crate::{Error, Result};
use clap::{Args, CommandFactory, FromArgMatches};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Options of `torso bench report`.
#[derive(Args, Debug)]
pub struct ReportArgs {
    /// The markdown file to write.
    #[arg(long, default_value = "BENCHMARKS.md")]
    pub out: PathBuf,
    /// Tiny workloads (level of detail 0, a few frames, a short recording, a few fit
    /// evaluations): checks that the report runs and what it writes; its figures are not the
    /// project's.
    #[arg(long)]
    pub quick: bool,
}

/// Headings of the report's sections, in order (a test checks that each is present).
pub const SECTIONS: [&str; 5] = [
    "Frame loops: quiet breathing at 56 Hz",
    "Right-hand side",
    "Building a torso",
    "Fitting an SLP recording on one thread",
    "What the FMU adds per communication step",
];

/// The workloads of one report.
struct Plan {
    /// Frames of every frame loop.
    frames: usize,
    /// Levels of detail of the frame loops, each with its repeats.
    loops: Vec<(u32, usize)>,
    /// Levels of detail of the right-hand-side timing and calls per batch (5 batches).
    rhs: (Vec<u32>, usize),
    /// Duration of the synthetic recording [s], the levels of detail it is fitted at, and a
    /// limit on the fit's evaluations (None: `torso fit`'s default).
    fit: (f64, Vec<u32>, Option<usize>),
    /// The FMU loops: level of detail, steps, repeats.
    fmu: (u32, usize, usize),
}

impl Plan {
    fn new(quick: bool) -> Plan {
        if quick {
            Plan {
                frames: 20,
                loops: vec![(0, 1)],
                rhs: (vec![0], 20),
                fit: (4.0, vec![0], Some(10)),
                fmu: (0, 10, 1),
            }
        } else {
            Plan {
                frames: 1000,
                loops: vec![(0, 5), (1, 3), (2, 1)],
                rhs: (vec![0, 1, 2], 2000),
                fit: (18.0, vec![0, 1], None),
                fmu: (1, 1000, 3),
            }
        }
    }
}

/// The solvers every frame loop and FMU loop is run with: the inertial default and the
/// quasi-static mode.
const METHODS: [Method; 2] = [Method::Dopri5, Method::QuasiStatic];

/// The machine and the code a report was measured on.
struct Stamp {
    commit: String,
    tree: String,
    date: String,
    cpu: String,
    cores: usize,
    load_start: String,
}

/// `git` run in the working directory: its trimmed output, or None.
fn git(args: &[&str]) -> Option<String> {
    let out = std::process::Command::new("git").args(args).output().ok()?;
    out.status
        .success()
        .then(|| String::from_utf8_lossy(&out.stdout).trim().to_string())
}

/// The first field of /proc/loadavg (the 1-minute load average), or "unknown".
fn load_average() -> String {
    std::fs::read_to_string("/proc/loadavg")
        .ok()
        .and_then(|s| s.split_whitespace().next().map(str::to_string))
        .unwrap_or_else(|| "unknown".into())
}

/// The CPU's model name from /proc/cpuinfo, or "unknown".
fn cpu_model() -> String {
    std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split_once(':'))
                .map(|(_, v)| v.trim().to_string())
        })
        .unwrap_or_else(|| "unknown".into())
}

/// The civil date (year, month, day) of `days` since 1970-01-01 (the proleptic Gregorian
/// calendar; H. Hinnant's days-to-civil algorithm).
fn civil_date(days: i64) -> (i64, u32, u32) {
    let z = days + 719_468;
    let era = z.div_euclid(146_097);
    let doe = z.rem_euclid(146_097);
    let yoe = (doe - doe / 1460 + doe / 36_524 - doe / 146_096) / 365;
    let doy = doe - (365 * yoe + yoe / 4 - yoe / 100);
    let mp = (5 * doy + 2) / 153;
    let day = (doy - (153 * mp + 2) / 5 + 1) as u32;
    let month = if mp < 10 { mp + 3 } else { mp - 9 } as u32;
    let year = yoe + era * 400 + i64::from(month <= 2);
    (year, month, day)
}

/// The current UTC time as `YYYY-MM-DD HH:MM UTC`.
fn utc_now() -> String {
    let secs = std::time::SystemTime::now()
        .duration_since(std::time::UNIX_EPOCH)
        .map_or(0, |d| d.as_secs() as i64);
    let (y, m, d) = civil_date(secs.div_euclid(86_400));
    let s = secs.rem_euclid(86_400);
    format!(
        "{y:04}-{m:02}-{d:02} {:02}:{:02} UTC",
        s / 3600,
        s % 3600 / 60
    )
}

impl Stamp {
    fn now() -> Stamp {
        let commit = git(&["rev-parse", "--short", "HEAD"]).unwrap_or_else(|| "unknown".into());
        let tree = match git(&["status", "--porcelain", "--untracked-files=no"]) {
            Some(s) if s.is_empty() => "clean",
            Some(_) => "uncommitted changes",
            None => "unknown",
        };
        Stamp {
            commit,
            tree: tree.into(),
            date: utc_now(),
            cpu: cpu_model(),
            cores: std::thread::available_parallelism().map_or(1, |n| n.get()),
            load_start: load_average(),
        }
    }
}

/// The configuration of every frame loop: the default subject breathing the quiet drive.
fn quiet(lod: u32, method: Method) -> Result<Config> {
    let mut c = Config {
        drive: Drive::quiet(),
        ..Config::default()
    };
    c.scene.level_of_detail = lod;
    c.solver.method = method;
    c.validate()?;
    Ok(c)
}

/// The frame loops of one level of detail and solver: volumes only and volumes with the
/// markers, alternating, `repeats` times each.
struct LoopRow {
    lod: u32,
    method: Method,
    volumes: LoopFigures,
    markers: LoopFigures,
    builds: Vec<f64>,
}

fn frame_loops(lod: u32, method: Method, frames: usize, repeats: usize) -> Result<LoopRow> {
    let config = quiet(lod, method)?;
    let (mut volumes, mut markers): (Vec<FrameRun>, Vec<FrameRun>) = (Vec::new(), Vec::new());
    for _ in 0..repeats {
        volumes.push(frame_loop(&config, frames, Reads::Volumes)?);
        markers.push(frame_loop(&config, frames, Reads::VolumesAndMarkers)?);
    }
    let builds = volumes.iter().chain(&markers).map(|r| r.build).collect();
    Ok(LoopRow {
        lod,
        method,
        volumes: loop_figures(&volumes, Reads::Volumes, frames),
        markers: loop_figures(&markers, Reads::VolumesAndMarkers, frames),
        builds,
    })
}

/// One fit of the synthetic recording.
struct FitRow {
    lod: u32,
    command: String,
    evaluations: usize,
    search_s: f64,
    command_s: f64,
    cost_mm: f64,
}

/// A `torso` command line parsed as the program parses its own.
fn parse(args: &[String]) -> Result<super::Command> {
    let argv = std::iter::once("torso".to_string()).chain(args.iter().cloned());
    let matches = super::allow_negative_values(super::Cli::command())
        .try_get_matches_from(argv)
        .map_err(|e| Error::State(format!("torso {}: {e}", args.join(" "))))?;
    super::Cli::from_arg_matches(&matches)
        .map(|c| c.command)
        .map_err(|e| Error::State(format!("torso {}: {e}", args.join(" "))))
}

/// `args` with the directory `dir` before each file name of `files`, and the command as
/// shown (file names alone, to be run in a directory of one's choice).
fn in_dir(args: &[&str], files: &[&str], dir: &Path) -> (Vec<String>, String) {
    let run = args
        .iter()
        .map(|a| {
            if files.contains(a) {
                dir.join(a).display().to_string()
            } else {
                a.to_string()
            }
        })
        .collect();
    (run, format!("torso {}", args.join(" ")))
}

/// Synthesises the recording, then fits it at each level of detail; returns the synthesis
/// command, its noise floor [mm] and the fits.
fn fits(plan: &Plan, dir: &Path) -> Result<(String, f64, Vec<FitRow>)> {
    let (duration, lods, max_evals) = &plan.fit;
    let duration = duration.to_string();
    let files = ["rec.csv", "truth.json"];
    let synth = [
        "synth",
        "--lod",
        "0",
        "--duration",
        &duration,
        "--seed",
        "11",
        "--out",
        "rec.csv",
        "--truth",
        "truth.json",
    ];
    let (argv, synth_command) = in_dir(&synth, &files, dir);
    match parse(&argv)? {
        super::Command::Synth(a) => super::synth::main(&a)?,
        _ => {
            return Err(Error::State(
                "`torso synth` parsed as another command".into(),
            ));
        }
    }
    let truth_path = dir.join("truth.json");
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(&truth_path).map_err(|e| Error::io(&truth_path, e))?,
    )
    .map_err(|e| Error::State(format!("{}: {e}", truth_path.display())))?;
    let noise_mm = truth["noise_floor_m"].as_f64().unwrap_or(f64::NAN) * 1e3;
    let mut rows = Vec::new();
    for lod in lods {
        let lod_text = lod.to_string();
        let out = format!("fit_lod{lod}.json");
        let max = max_evals.map(|m| m.to_string());
        let mut fit = vec![
            "fit",
            "--slp",
            "rec.csv",
            "--lod",
            &lod_text,
            "--threads",
            "1",
            "--out",
            &out,
        ];
        if let Some(m) = &max {
            fit.extend(["--max-evals", m.as_str()]);
        }
        let (argv, command) = in_dir(&fit, &["rec.csv", out.as_str()], dir);
        let super::Command::Fit(args) = parse(&argv)? else {
            return Err(Error::State("`torso fit` parsed as another command".into()));
        };
        let (options, read, flags) = super::fit::fit_settings(&args)?;
        let start = Instant::now();
        // an observer keeps the fit quiet (no progress bar, no summary)
        let result = super::fit::fit_file_observed(
            &args.slp,
            &read,
            &args.model,
            &args.out,
            &options,
            &flags,
            Some(&mut |_, _| {}),
        )?;
        rows.push(FitRow {
            lod: *lod,
            command,
            evaluations: result.evaluations,
            search_s: result.wall_s,
            command_s: start.elapsed().as_secs_f64(),
            cost_mm: result.cost_m * 1e3,
        });
    }
    Ok((synth_command, noise_mm, rows))
}

/// Everything one report measured.
struct Measured {
    stamp: Stamp,
    quick: bool,
    frames: usize,
    loops: Vec<LoopRow>,
    rhs_calls: usize,
    rhs: Vec<RhsCost>,
    synth_command: String,
    noise_mm: f64,
    fits: Vec<FitRow>,
    fmu: Vec<FmuOverhead>,
    load_end: String,
    total_s: f64,
}

/// Runs `torso bench report`.
pub fn run(args: &ReportArgs) -> Result<()> {
    let plan = Plan::new(args.quick);
    let stamp = Stamp::now();
    let start = Instant::now();
    let dir = std::env::temp_dir().join(format!("torso-bench-report-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let measured = measure(&plan, stamp, &dir, args.quick, start);
    std::fs::remove_dir_all(&dir).ok();
    let measured = measured?;
    let text = markdown(&measured);
    if let Some(parent) = args.out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent).map_err(|e| Error::io(parent, e))?;
    }
    std::fs::write(&args.out, text).map_err(|e| Error::io(&args.out, e))?;
    println!(
        "wrote {} ({:.0} s)",
        args.out.display(),
        start.elapsed().as_secs_f64()
    );
    Ok(())
}

fn measure(plan: &Plan, stamp: Stamp, dir: &Path, quick: bool, start: Instant) -> Result<Measured> {
    let mut loops = Vec::new();
    for &(lod, repeats) in &plan.loops {
        for method in METHODS {
            println!(
                "frame loops: level of detail {lod}, {}, {} frames, {repeats} runs each",
                method.name(),
                plan.frames
            );
            loops.push(frame_loops(lod, method, plan.frames, repeats)?);
        }
    }
    let (rhs_lods, rhs_calls) = &plan.rhs;
    let mut rhs = Vec::new();
    for &lod in rhs_lods {
        println!("right-hand side: level of detail {lod}");
        rhs.push(rhs_cost(&quiet(lod, Method::Dopri5)?, *rhs_calls, 5)?);
    }
    println!("fits");
    let (synth_command, noise_mm, fits) = fits(plan, dir)?;
    let mut fmu = Vec::new();
    let (lod, frames, repeats) = plan.fmu;
    for method in METHODS {
        println!("FMU loops: level of detail {lod}, {}", method.name());
        fmu.push(fmu_overhead(method, lod, frames, repeats)?);
    }
    Ok(Measured {
        stamp,
        quick,
        frames: plan.frames,
        loops,
        rhs_calls: *rhs_calls,
        rhs,
        synth_command,
        noise_mm,
        fits,
        fmu,
        load_end: load_average(),
        total_s: start.elapsed().as_secs_f64(),
    })
}

/// The command that reproduces a frame-loop row.
fn core_command(lod: u32, method: Method, frames: usize, repeats: usize) -> String {
    let frames = if frames == 1000 {
        String::new()
    } else {
        format!(" --frames {frames}")
    };
    format!(
        "`torso bench core --lod {lod} --solver {} --repeats {repeats}{frames}`",
        method.name()
    )
}

fn markdown(m: &Measured) -> String {
    let mut s = String::new();
    let s_ = &mut s;
    let regenerate = if m.quick {
        "target/release/torso bench report --quick"
    } else {
        "target/release/torso bench report"
    };
    let _ = writeln!(s_, "# Benchmarks\n");
    if m.quick {
        let _ = writeln!(
            s_,
            "**Quick run** (`--quick`): tiny workloads that check the report runs; these are not \
             the project's figures.\n"
        );
    }
    let _ = writeln!(
        s_,
        "The current figures, from one run of `{regenerate}` (after `cargo build --release`) on \
         one machine; each table gives the command that reproduces it alone. Counts \
         (right-hand-side evaluations, steps, fit evaluations) are exact; wall times are \
         medians over the runs stated. How the figures got here: [CHANGELOG.md](CHANGELOG.md).\n"
    );
    let _ = writeln!(
        s_,
        "| commit | tree | date | CPU | cores | load average at start / end | run time [s] |\n|---|---|---|---|---|---|---|"
    );
    let _ = writeln!(
        s_,
        "| {} | {} | {} | {} | {} | {} / {} | {:.0} |\n",
        m.stamp.commit,
        m.stamp.tree,
        m.stamp.date,
        m.stamp.cpu,
        m.stamp.cores,
        m.stamp.load_start,
        m.load_end,
        m.total_s
    );
    let _ = writeln!(
        s_,
        "The machine is shared with other work: a load average above the core count means the \
         run competed for the cores, and its wall times are longer than a quiet machine's. \
         Compare wall times within one report; the counts do not depend on the load.\n"
    );

    let _ = writeln!(s_, "## {}\n", SECTIONS[0]);
    let _ = writeln!(
        s_,
        "{} frames at 56 Hz of the quiet drive, default subject (male, 30 y, 1.75 m, 75 kg, \
         standing), rtol 1e-6: the four volumes read after every frame, then the volumes and \
         the 60 markers. The quasi-static mode (`solver.method` 4) solves the positions at \
         every frame in both loops. Model and marker-model builds are outside the loop times.\n",
        m.frames
    );
    let _ = writeln!(
        s_,
        "| level | solver | runs | volumes only [s] | + 60 markers [s] | markers / volumes | RHS evaluations | steps | rejected | wall per RHS [us] | command |\n|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in &m.loops {
        let _ = writeln!(
            s_,
            "| {} | {} | {} | {:.4} | {:.4} | {:.2} | {} | {} | {} | {:.1} | {} |",
            r.lod,
            r.method.name(),
            r.volumes.runs,
            r.volumes.median_wall_s,
            r.markers.median_wall_s,
            r.markers.median_wall_s / r.volumes.median_wall_s,
            r.markers.rhs_evaluations,
            r.markers.steps,
            r.markers.rejected,
            r.markers.ns_per_rhs * 1e-3,
            core_command(r.lod, r.method, m.frames, r.volumes.runs)
        );
    }
    let _ = writeln!(
        s_,
        "\nThe quasi-static mode against the inertial one in the same run (60 markers):\n\n| level | wall, quasi-static / inertial | RHS evaluations, quasi-static / inertial |\n|---|---|---|"
    );
    for pair in m.loops.chunks(2) {
        if let [a, b] = pair {
            let _ = writeln!(
                s_,
                "| {} | {:.2} | {:.3} |",
                a.lod,
                b.markers.median_wall_s / a.markers.median_wall_s,
                b.markers.rhs_evaluations as f64 / a.markers.rhs_evaluations as f64
            );
        }
    }
    let _ = writeln!(s_);

    let _ = writeln!(s_, "## {}\n", SECTIONS[1]);
    let _ = writeln!(
        s_,
        "One call of the inertial equations' right-hand side (`Torso::rhs`), median of 5 \
         batches of {} calls, at the rest state and after 1.5 s of quiet breathing; beside it \
         the wall time per evaluation of the Dormand-Prince frame loop with 60 markers (above), \
         which adds the integrator's and the reads' work.\n",
        m.rhs_calls
    );
    let _ = writeln!(
        s_,
        "| level | state length | rest [us] | breathing [us] | frame loop per RHS [us] | loop / breathing call | command |\n|---|---|---|---|---|---|---|"
    );
    for r in &m.rhs {
        let in_loop = m
            .loops
            .iter()
            .find(|l| l.lod == r.level_of_detail && l.method == Method::Dopri5)
            .map(|l| l.markers.ns_per_rhs * 1e-3);
        let (loop_us, ratio) = match in_loop {
            Some(us) => (
                format!("{us:.1}"),
                format!("{:.2}", us * 1e3 / r.ns_breathing),
            ),
            None => ("-".into(), "-".into()),
        };
        let _ = writeln!(
            s_,
            "| {} | {} | {:.1} | {:.1} | {loop_us} | {ratio} | `torso bench core --rhs-calls {}` (its right-hand-side lines) |",
            r.level_of_detail,
            r.state_dim,
            r.ns_rest * 1e-3,
            r.ns_breathing * 1e-3,
            m.rhs_calls
        );
    }
    let _ = writeln!(s_);

    let _ = writeln!(s_, "## {}\n", SECTIONS[2]);
    let _ = writeln!(
        s_,
        "`Torso::new`: the model compiled for the subject and level of detail, then its start \
         state, the static equilibrium of the drive's start; timed before each frame loop above \
         (the median over that row's builds).\n"
    );
    let _ = writeln!(
        s_,
        "| level | solver | builds | `Torso::new` [s] | command |\n|---|---|---|---|---|"
    );
    for r in &m.loops {
        let _ = writeln!(
            s_,
            "| {} | {} | {} | {:.3} | {} (its `Torso::new` line) |",
            r.lod,
            r.method.name(),
            r.builds.len(),
            crate::bench::median(&r.builds),
            core_command(r.lod, r.method, m.frames, r.volumes.runs)
        );
    }
    let _ = writeln!(s_);

    let _ = writeln!(s_, "## {}\n", SECTIONS[3]);
    let _ = writeln!(
        s_,
        "A synthetic recording of the 10 x 6 grid made by `{}` (level of detail 0, 0.5 mm \
         noise, noise floor {:.3} mm), fitted by `torso fit` at its defaults on one thread \
         (`--threads 1`: the second thread evaluates ahead and saves wall time on a second \
         core). \"Search\" is the fit's own wall time (`wall_s` in its JSON); \"command\" the \
         whole `torso fit` (the subject's size estimate, the search, the fitted breath and the \
         report files). One fit each.\n",
        m.synth_command, m.noise_mm
    );
    let _ = writeln!(
        s_,
        "| level | evaluations | search [s] | per evaluation [s] | whole command [s] | cost [mm] | command |\n|---|---|---|---|---|---|---|"
    );
    for f in &m.fits {
        let _ = writeln!(
            s_,
            "| {} | {} | {:.2} | {:.3} | {:.2} | {:.3} | `{}` |",
            f.lod,
            f.evaluations,
            f.search_s,
            f.search_s / f.evaluations.max(1) as f64,
            f.command_s,
            f.cost_mm,
            f.command
        );
    }
    let _ = writeln!(s_);

    let _ = writeln!(s_, "## {}\n", SECTIONS[4]);
    let _ = writeln!(
        s_,
        "The FMU's instance (what every `fmi2*`/`fmi3*` call of its library acts on) at its \
         start values, the default subject breathing the quiet drive, stepped by `do_step` \
         and read by one `get_real` of the 4 volumes and 180 marker coordinates, against the \
         model facade stepped by `advance_to_with` with the physiological check (as \
         `bt_advance_to`) and read by `read` and `markers`; the loops alternate, each step reads \
         everything twice, so the second read is the layer's own cost. Microseconds per \
         communication step, medians over the loops. Through the shared library and the \
         official FMI headers, with the C ABI beside it: `bash scripts/bench-fmu-overhead.sh \
         [FRAMES] [REPEATS] [METHOD]` (needs gcc and the venv of `scripts/python-env.sh`).\n"
    );
    let _ = writeln!(
        s_,
        "| solver | level | steps | loops | `do_step` [us] | `advance_to_with` [us] | first `get_real` [us] | first native read [us] | `get_real` again [us] | native read again [us] | FMI loop [s] | native loop [s] | identical | command |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"
    );
    for f in &m.fmu {
        let _ = writeln!(
            s_,
            "| {} | {} | {} | {} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.2} | {:.4} | {:.4} | {} | `torso bench fmu --lod {} --solver {} --frames {} --repeats {}` |",
            f.method,
            f.level_of_detail,
            f.frames,
            f.repeats,
            f.fmi_step_us,
            f.native_step_us,
            f.fmi_first_read_us,
            f.native_first_read_us,
            f.fmi_read_again_us,
            f.native_read_again_us,
            f.fmi_loop_s,
            f.native_loop_s,
            if f.identical { "yes" } else { "no" },
            f.level_of_detail,
            f.method,
            f.frames,
            f.repeats
        );
    }
    let _ = writeln!(s_);
    let _ = writeln!(
        s_,
        "## Not in this run\n\n\
         Longer measurements, run by their own commands (`torso bench --help`): \
         `torso bench work-precision` (wall time and evaluations against error for every \
         method and tolerance, with plots), `torso bench soak` (random scenes from the declared \
         ranges), `torso bench stress` (square waves, held activation, an hour's drift, \
         communication steps), `torso bench core` (also the whole skin read every frame), \
         `torso fit-sweep` (the acceptance recordings, `--mismatch` for another model's). \
         Figures measured along the way, with their dates and commits, are in \
         [CHANGELOG.md](CHANGELOG.md)."
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn civil_dates_of_known_days() {
        assert_eq!(civil_date(0), (1970, 1, 1));
        assert_eq!(civil_date(-1), (1969, 12, 31));
        // 2000-02-29, a leap day of a century year divisible by 400
        assert_eq!(civil_date(11_016), (2000, 2, 29));
        assert_eq!(civil_date(11_017), (2000, 3, 1));
        // 2100-03-01 follows 2100-02-28 (2100 is not a leap year)
        assert_eq!(civil_date(47_540), (2100, 2, 28));
        assert_eq!(civil_date(47_541), (2100, 3, 1));
    }
}
