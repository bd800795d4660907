//! `torso fit` (fit the model to an SLP recording) and `torso demo` (package the FMU,
//! simulate the default subject, fit the bundled synthetic recording, print the report).

use super::common::{
    SolverArgs, SubjectArgs, flag_error, parse_grid_flag, prepare_output_dir, prepare_output_file,
};
use super::progress::Progress;
use crate::anatomy::skin::SurfaceOptions;
use crate::fit::clinical::BreathReport;
use crate::fit::fitting::fit_with_skin;
use crate::fit::report::{
    LOD_KEY, marker_set_json, marker_set_summary, model_provenance, provenance_differences,
    summary, write_fit_report,
};
use crate::fit::size::{SizeOptions, estimate_size, registration_residual};
use crate::fit::{
    FitOptions, Method, PoseOptions, TorsoMarkers, bind_recording, fit_any_markers, fit_recording,
};
use crate::model::Drive;
use crate::recording::{Markers, ReadOptions, Recording, Units};
use crate::{Error, Result};
use clap::Args;
use std::path::{Path, PathBuf};

/// The subject and the model built for a fit or a synthetic recording.
#[derive(Args, Debug, Clone)]
pub struct ModelArgs {
    /// The subject and the level of detail.
    #[command(flatten)]
    pub subject: SubjectArgs,
    /// The ODE solver. At the default rtol 1e-6 the step is held by stability at level of
    /// detail 0, so looser tolerances save nothing (1e-4 took as many evaluations with 12 x
    /// the rejected steps: `cargo run --release --example fast_dynamics -- 0 1e-4`), and the
    /// markers of a fit's periodic run agree with an rtol 1e-9 run within 0.1 um
    /// (tests/sampled_runs.rs).
    #[command(flatten)]
    pub solver: SolverArgs,
    /// Marker grid of the model, ROWSxCOLS (1..16 each).
    #[arg(long, default_value = "10x6")]
    pub grid: String,
}

impl ModelArgs {
    /// The configuration (with `drive` and the grid); an error names the flag.
    pub fn config(&self, drive: Drive) -> Result<crate::Config> {
        let mut c = self.subject.config(&self.solver, drive)?;
        let (r, k) = self.grid()?;
        c.scene.grid_rows = r;
        c.scene.grid_cols = k;
        c.validate().map_err(flag_error)?;
        Ok(c)
    }

    /// The marker grid `--grid` (rows, columns).
    pub fn grid(&self) -> Result<(usize, usize)> {
        parse_grid_flag("--grid", &self.grid)
    }
}

/// A fit's absolute tolerance relative to its relative one (atol = rtol / 100, the
/// convention of the work-precision benchmark): at the default rtol 1e-6 the markers of a
/// fit's periodic run agree with an rtol 1e-9 run within 0.1 um (tests/sampled_runs.rs),
/// and the step stays at the stability limit.
pub const FIT_ATOL_PER_RTOL: f64 = 1e-2;

/// Options of `torso fit`.
#[derive(Args, Debug)]
pub struct FitArgs {
    /// The recording: `.c3d`, `.trc` or `.csv` (the grid CSV or named markers). Markers
    /// labelled `marker[1]`..`marker[R*C]` are the model's grid; any other labels are a
    /// marker set registered to the model's skin without correspondences, each marker bound
    /// to its nearest skin point, those over 3 cm away left out (docs/recordings.md).
    #[arg(long)]
    pub slp: PathBuf,
    /// Units and frame rate of a recording that does not state them.
    #[command(flatten)]
    pub read: ReadArgs,
    /// The subject and the model.
    #[command(flatten)]
    pub model: ModelArgs,
    /// Result JSON (the lung-volume CSV and the PNG report are written beside it).
    #[arg(long, default_value = "out/fit/result.json")]
    pub out: PathBuf,
    /// Search method: nelder-mead, multistart or cmaes.
    #[arg(long, default_value = "nelder-mead")]
    pub method: String,
    /// Largest number of cost evaluations.
    #[arg(long, default_value_t = 120)]
    pub max_evals: usize,
    /// Seed of the randomised methods.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// Threads for the Nelder-Mead search: 2 evaluates ahead, on a second instance of the
    /// model, the point the search is likely to need next (same search and result as 1).
    /// Default: 2 when the machine has two or more cores.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Fit the model's skin to the recording (thesis 3.2, `slp.reference`) rather than a
    /// rigid registration alone; for subjects whose shape differs from the model's. A first
    /// fit with rigid registration gives the rest-pose grid the recording implies (each
    /// frame minus the fitted model's displacement from rest, averaged over frames), written
    /// beside the result as `<stem>_reference.csv`; the model fits its skin to that grid,
    /// and a polish from the first optimum follows (both within --max-evals).
    #[arg(long)]
    pub skin_fit: bool,
    /// Compare each grid marker's trajectory about its own mean over the recording, as named
    /// marker sets always are: the subject's static shape then stays out of the cost and only
    /// the markers' motion is fitted (for a subject whose shape differs from the model's).
    /// Always so for named sets; for the grid, the default when neither --stature nor
    /// --mass is given (a stranger's shape), otherwise the thesis's eq. 3.1. The result
    /// JSON's `cost_basis` says which and why.
    #[arg(long)]
    pub marker_offsets: bool,
    /// Estimate the subject's stature and mass from the recording's first frame before the
    /// fit, starting from --stature and --mass (sex, age, breast size and posture as given):
    /// the pair whose model registers best to the markers (docs/recordings.md). The result
    /// JSON's `subject_size` says what was found and why; its `model` carries the estimate.
    /// Done by default when neither --stature nor --mass is given, or when the first frame
    /// registers to the given subject's model with rms over 5 mm (a warning says so).
    #[arg(long, conflicts_with = "no_fit_size")]
    pub fit_size: bool,
    /// Keep the given (or default) stature and mass: no size estimate even when neither is
    /// given or the first frame registers with rms over 5 mm.
    #[arg(long)]
    pub no_fit_size: bool,
    /// Keep each marker's slow drift in the cost. By default a fit that compares each
    /// marker about its own mean (named sets, a stranger's grid, --marker-offsets) also
    /// removes each marker coordinate's drift, a linear spline with knots at least three
    /// breaths apart, in closed form at each evaluation (docs/fit_report.md).
    #[arg(long)]
    pub no_drift: bool,
    /// Keep the whole trunk's sway in the recording. By default a named marker set with
    /// markers over the back (more than 6 markers, at least 3 of them facing backwards on
    /// the registered skin) has the trunk's rigid motion removed first: the back markers'
    /// per-frame rigid registration to their mean shape, its part slower than the breath
    /// (docs/recordings.md, "Sway"). The grid and front-only sets get none, and the report
    /// says so.
    #[arg(long)]
    pub no_sway: bool,
    /// Labels of quasi-rigid markers (over the spine, the back, the pelvis), comma separated:
    /// the sway's reference instead of the markers over the back.
    #[arg(long, value_delimiter = ',', conflicts_with = "no_sway")]
    pub reference: Vec<String>,
    /// Marker radius [mm] of a named marker set: each recorded marker's centre stands this
    /// far off the skin along the skin's outward normal (half the marker's diameter plus
    /// its base; 5-7 mm for 10-14 mm markers). Default 0: the recorded points are taken as
    /// skin points, and the report says so.
    #[arg(long, default_value_t = 0.0)]
    pub marker_radius: f64,
    /// Labels of markers on the front of the trunk, comma separated (a named marker set):
    /// the pose is the one that puts them on the skin facing forwards, rather than the one
    /// the breathing motion points to (docs/recordings.md, "The pose of a marker set").
    #[arg(long, value_delimiter = ',')]
    pub anterior: Vec<String>,
    /// Inspiratory fraction Ti/Ttot of the fitted drive, held fixed by the search: a number
    /// (0.2-0.8; 0.5 is the sine of thesis eq. 2.4) or `auto`, the median Ti/Ttot of the
    /// recording's breaths (docs/drive.md).
    #[arg(long, default_value = "0.5", allow_hyphen_values = true)]
    pub ti_ttot: String,
}

/// What a CSV of named markers may leave unsaid.
#[derive(Args, Debug, Clone, Default)]
pub struct ReadArgs {
    /// Length unit of a CSV of named markers without a `# units:` line: mm, cm or m.
    #[arg(long)]
    pub units: Option<String>,
    /// Frame rate [Hz] of a CSV of named markers without a time column.
    #[arg(long)]
    pub rate: Option<f64>,
}

impl ReadArgs {
    /// The reader's options; an error names the flag.
    pub fn options(&self) -> Result<ReadOptions> {
        let units = match &self.units {
            None => None,
            Some(u) => {
                Some(Units::parse(u).ok_or_else(|| Error::invalid("--units", u, "mm, cm or m"))?)
            }
        };
        if let Some(r) = self.rate
            && !(r.is_finite() && r > 0.0)
        {
            return Err(Error::invalid("--rate", r, "a frame rate in Hz > 0"));
        }
        Ok(ReadOptions {
            units,
            rate: self.rate,
        })
    }
}

/// What `torso fit` fits: a recording of the model's grid, or of another marker set.
pub enum ForFit {
    /// Labelled `marker[1]`..`marker[R*C]`: the grid, registered by correspondence.
    Grid(Recording),
    /// Any other labels: registered to the skin without correspondences and bound.
    Named(Markers),
}

/// Whether a recording's markers are meant as the model's grid: a `grid` provenance entry
/// or any label of the form `marker[k]`.
fn is_grid_recording(markers: &Markers) -> bool {
    markers.provenance_value("grid").is_some()
        || markers
            .labels
            .iter()
            .any(|l| l.starts_with("marker[") && l.ends_with(']'))
}

/// Reads a recording and the configuration to fit it with. When the recording names the
/// level of detail it was made at and `--lod` is not given, the fit runs at the recording's
/// (a note on stderr says so); any other difference between the model that made the
/// recording and the fitting model is one warning line on stderr. A recording whose labels
/// are the grid's (any `marker[k]` label, or a `grid` entry) must be the model's grid;
/// any other is returned as [`ForFit::Named`].
pub fn read_for_fit(
    path: &Path,
    read: &ReadOptions,
    model: &ModelArgs,
) -> Result<(ForFit, crate::Config)> {
    // The flags are checked before the file is read, so that a bad flag is named first.
    model.config(Drive::default())?;
    let markers = Markers::read(path, read)?;
    let mut model = model.clone();
    let recorded_lod = match markers.provenance_value(LOD_KEY) {
        None => None,
        Some(v) => Some(v.trim().parse::<u32>().map_err(|_| {
            Error::State(format!(
                "{}: provenance `{LOD_KEY}: {v}` is not a level of detail 0, 1 or 2",
                path.display()
            ))
        })?),
    };
    if let (Some(lod), None) = (recorded_lod, model.subject.lod) {
        model.subject.lod = Some(lod);
        eprintln!(
            "note: fitting at level of detail {lod}, the one {} was made at; pass --lod to choose another",
            path.display()
        );
    }
    let config = model.config(Drive::default())?;
    let differences = provenance_differences(
        &markers.provenance,
        &model_provenance(&config.subject, config.scene.level_of_detail),
    );
    if !differences.is_empty() {
        eprintln!(
            "warning: {} was made with another model than this fit's: {}; fitting with this fit's \
             model{}",
            path.display(),
            differences.join(", "),
            if model.subject.size_given() {
                ""
            } else {
                " (its stature and mass estimated from the recording)"
            }
        );
    }
    if !is_grid_recording(&markers) {
        return Ok((ForFit::Named(markers), config));
    }
    let grid = (config.scene.grid_rows, config.scene.grid_cols);
    if let Some((r, c)) = markers.grid_shape()
        && (r, c) != grid
        && r * c == markers.markers()
    {
        return Err(Error::State(format!(
            "{} has a {r}x{c} grid ({} points), the model's marker grid is {}x{} ({} points); \
             pass --grid {r}x{c}",
            path.display(),
            r * c,
            grid.0,
            grid.1,
            grid.0 * grid.1
        )));
    }
    let recording = markers
        .to_recording(grid)
        .map_err(|e| Error::State(format!("{}: {e}", path.display())))?;
    Ok((ForFit::Grid(recording), config))
}

/// Registration residual of the first frame to the given subject's model above which
/// `torso fit` estimates the subject's size itself [m] (the 5 mm: the grid of a
/// subject 8 % taller and heavier registers with 8.09 mm to the default model and 2.66 mm
/// after the estimate, docs/recordings.md).
pub const SIZE_TRIGGER_RMS_M: f64 = 5e-3;

/// What `torso fit` does beyond the search's options.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct FitFlags {
    /// Fit the model's skin to the grid (`--skin-fit`).
    pub skin_fit: bool,
    /// Estimate the subject's stature and mass first (`--fit-size`; also when no size is
    /// given or the given one registers with rms over [`SIZE_TRIGGER_RMS_M`]).
    pub fit_size: bool,
    /// Never estimate the size (`--no-fit-size`).
    pub no_fit_size: bool,
    /// Keep each marker's drift in the cost (`--no-drift`).
    pub no_drift: bool,
    /// Keep the trunk's sway in the recording (`--no-sway`).
    pub no_sway: bool,
    /// What the user says of a named marker set's pose (`--anterior`).
    pub pose: PoseOptions,
}

/// Fits `recording_path` with a model from `model` and writes the outputs at `out`.
pub fn fit_file(
    recording_path: &Path,
    read: &ReadOptions,
    model: &ModelArgs,
    out: &Path,
    options: &FitOptions,
    flags: &FitFlags,
) -> Result<crate::fit::Fit> {
    fit_file_observed(recording_path, read, model, out, options, flags, None)
}

/// [`fit_file`] reporting to `observer` (evaluations so far, best cost [m]) at every
/// evaluation the search reports, on the calling thread, instead of drawing the progress
/// bar on stderr and printing the summary on stdout (the Python package's fit: its progress
/// callback and its Ctrl-C check; the result is the JSON). Warnings still go to stderr.
pub fn fit_file_observed(
    recording_path: &Path,
    read: &ReadOptions,
    model: &ModelArgs,
    out: &Path,
    options: &FitOptions,
    flags: &FitFlags,
    mut observer: Option<&mut dyn FnMut(usize, f64)>,
) -> Result<crate::fit::Fit> {
    // With an observer the caller reads the result from the JSON: nothing is printed.
    let quiet = observer.is_some();
    let FitFlags {
        skin_fit,
        fit_size,
        no_fit_size,
        pose,
        ..
    } = flags;
    let skin_fit = *skin_fit;
    let (recording, mut config) = read_for_fit(recording_path, read, model)?;
    prepare_output_file(out)?;
    let in_file = |e: Error| Error::State(format!("{}: {e}", recording_path.display()));
    let size_given = model.subject.size_given();
    let (first, grid) = match &recording {
        ForFit::Grid(r) => (&r.frames[0], true),
        ForFit::Named(m) => (&m.frames[0], false),
    };
    // A named set's pose at the given size: the start of the size search (the shape alone
    // may prefer the pose turned about the long axis) and its registration residual.
    let named_pose = match &recording {
        ForFit::Grid(_) => None,
        ForFit::Named(m) if !no_fit_size => {
            let torso = crate::Torso::new_at_rest(config.clone())?;
            let bound =
                bind_recording(&torso, m, &SurfaceOptions::default(), pose).map_err(in_file)?;
            Some((
                unscaled(&bound.registration.to_model, &m.frames[0]),
                bound.registration.rms,
            ))
        }
        ForFit::Named(_) => None,
    };
    let why_size = if *no_fit_size {
        None
    } else if *fit_size {
        Some("--fit-size".to_string())
    } else if !size_given {
        Some("no --stature or --mass was given".to_string())
    } else {
        let rms = match named_pose {
            Some((_, rms)) => rms,
            None => {
                registration_residual(&config, first, true, &SurfaceOptions::default(), None)
                    .map_err(in_file)?
                    .0
            }
        };
        (rms > SIZE_TRIGGER_RMS_M).then(|| {
            eprintln!(
                "warning: the first frame registers to the given subject's model with rms {:.1} mm \
                 (over {:.0} mm): estimating the subject's stature and mass from the recording \
                 (pass --no-fit-size to keep the given ones)",
                rms * 1e3,
                SIZE_TRIGGER_RMS_M * 1e3
            );
            format!(
                "the registration rms with the given subject, {:.1} mm, is over {:.0} mm",
                rms * 1e3,
                SIZE_TRIGGER_RMS_M * 1e3
            )
        })
    };
    let size = if let Some(why) = why_size {
        let size = estimate_size(
            &config,
            first,
            grid,
            &SurfaceOptions {
                start: named_pose.map(|p| p.0),
                ..SurfaceOptions::default()
            },
            &SizeOptions::default(),
        )
        .map_err(in_file)?;
        if !quiet {
            println!(
                "subject size          estimated ({why}): stature {:.3} -> {:.3} m, mass {:.1} -> {:.1} kg (registration rms {:.2} -> {:.2} mm, {} model builds)",
                config.subject.stature,
                size.subject.stature,
                config.subject.mass,
                size.subject.mass,
                size.start_rms_m * 1e3,
                size.rms_m * 1e3,
                size.evaluations
            );
        }
        let json = serde_json::json!({
            "method": "stature and mass minimising the first frame's rigid registration residual (bounded Nelder-Mead)",
            "why": why,
            "stature_given_m": config.subject.stature,
            "mass_given_kg": config.subject.mass,
            "stature_m": size.subject.stature,
            "mass_kg": size.subject.mass,
            "registration_rms_given_m": size.start_rms_m,
            "registration_rms_m": size.rms_m,
            "model_builds": size.evaluations,
        });
        config.subject = size.subject;
        Some(json)
    } else {
        None
    };
    // Each marker about its own mean: always for a named set; for the grid when asked or
    // when the subject is a stranger (a shape the model does not have stays out of the cost).
    let about_means = match &recording {
        ForFit::Named(_) => Some("a named marker set (each marker stands off its skin point)"),
        ForFit::Grid(_) if options.marker_offsets => Some("--marker-offsets"),
        ForFit::Grid(_) if !size_given => Some("no --stature or --mass was given"),
        ForFit::Grid(_) => None,
    };
    if matches!(recording, ForFit::Grid(_)) && options.marker_radius != 0.0 {
        return Err(Error::invalid(
            "--marker-radius",
            options.marker_radius * 1e3,
            "0 for the grid (its points are on the skin surface itself)",
        ));
    }
    if matches!(recording, ForFit::Grid(_)) && !options.reference.is_empty() {
        return Err(Error::invalid(
            "--reference",
            options.reference.join(","),
            "labels of a named marker set's markers (the grid covers the front only: no sway is removed from it)",
        ));
    }
    let options = &FitOptions {
        marker_offsets: about_means.is_some(),
        drift: about_means.is_some() && !flags.no_drift,
        sway: !flags.no_sway,
        ..options.clone()
    };
    let radius_assumption = if options.marker_radius > 0.0 {
        format!(
            "each marker's centre taken {:.1} mm off its skin point along the rest skin's outward normal there, the same in every frame (--marker-radius)",
            options.marker_radius * 1e3
        )
    } else if matches!(recording, ForFit::Grid(_)) {
        "0: the grid's points are on the skin surface".to_string()
    } else {
        "0: the recorded points are taken as skin points (a motion-capture marker's centre stands half its diameter and its base off the skin, 5-7 mm for 10-14 mm markers; --marker-radius MM says so)".to_string()
    };
    println!("marker radius         {radius_assumption}");
    let cost_json = serde_json::json!({
        "marker_radius_m": options.marker_radius,
        "marker_radius_assumption": radius_assumption,
        "about_marker_means": about_means.is_some(),
        "drift_removed": options.drift,
        "why": about_means.unwrap_or("the grid of a given subject: the thesis's eq. 3.1 after one rigid pose correction"),
    });
    if !quiet {
        println!(
            "cost basis            {}",
            match about_means {
                Some(why) => format!(
                    "each marker's motion about its own mean ({why}){}",
                    if options.drift {
                        ", each marker's slow drift removed (--no-drift keeps it)"
                    } else {
                        ""
                    }
                ),
                None => "marker positions after one rigid pose correction (thesis eq. 3.1)".into(),
            }
        );
    }
    config.solver.atol = FIT_ATOL_PER_RTOL * config.solver.rtol;
    let mut model = config.clone();
    let bar = match observer {
        None => Progress::new("fit", options.max_evals, "evaluations"),
        Some(_) => Progress::to_writer(
            "fit",
            options.max_evals,
            "evaluations",
            false,
            std::time::Duration::from_secs(3600),
            Box::new(std::io::sink()),
        ),
    }
    .up_to();
    let mut report = |n: usize, b: f64| {
        bar.update(n, format!("best cost {:.3} mm", b * 1e3));
        if let Some(o) = observer.as_mut() {
            o(n, b);
        }
    };
    let recording = match recording {
        ForFit::Grid(r) => r,
        ForFit::Named(markers) => {
            if skin_fit {
                return Err(Error::invalid(
                    "--skin-fit",
                    "given for a recording of named markers",
                    "a recording of the model's grid (marker[1]..): the skin is fitted to the grid",
                ));
            }
            let set_fit = fit_any_markers(
                config.clone(),
                &markers,
                &SurfaceOptions::default(),
                pose,
                options,
                &mut report,
            )
            .map_err(|e| Error::State(format!("{}: {e}", recording_path.display())))?;
            let named_set = (set_fit.bound, markers.markers());
            return finish_fit(
                set_fit.fit,
                &config,
                &model,
                recording_path,
                out,
                &bar,
                FitExtras {
                    named_set: Some(&named_set),
                    size: size.as_ref(),
                    cost: &cost_json,
                    quiet,
                },
            );
        }
    };
    let fit = if skin_fit {
        let stem = out.file_stem().and_then(|s| s.to_str()).unwrap_or("result");
        let reference = out.with_file_name(format!("{stem}_reference.csv"));
        let fit = fit_with_skin(&config, &recording, &reference, options, &mut report)?;
        if !quiet {
            println!("rest-pose reference grid: {}", reference.display());
        }
        model.scene.slp_reference = Some(reference);
        fit
    } else {
        let mut source = TorsoMarkers::new(config.clone())?;
        fit_recording(&mut source, &recording, options, &mut report)?
    };
    finish_fit(
        fit,
        &config,
        &model,
        recording_path,
        out,
        &bar,
        FitExtras {
            named_set: None,
            size: size.as_ref(),
            cost: &cost_json,
            quiet,
        },
    )
}

/// The rigid transform (scale 1) with the rotation of `t` that maps the centroid of the
/// tracked points of `frame` where `t` does: a pose found with a scale, as the start of a
/// registration without one.
fn unscaled(
    t: &crate::anatomy::skin::RigidTransform,
    frame: &[Option<nalgebra::Point3<f64>>],
) -> crate::anatomy::skin::RigidTransform {
    let tracked: Vec<nalgebra::Vector3<f64>> = frame.iter().flatten().map(|p| p.coords).collect();
    let mean = nalgebra::Point3::from(
        tracked.iter().sum::<nalgebra::Vector3<f64>>() / tracked.len().max(1) as f64,
    );
    crate::anatomy::skin::RigidTransform {
        rotation: t.rotation,
        translation: t.apply(&mean).coords - t.rotation * mean.coords,
        scale: 1.0,
    }
}

/// What a fit adds to its result JSON beyond the fit itself.
struct FitExtras<'a> {
    /// The registration of a named marker set and the number of markers recorded.
    named_set: Option<&'a (crate::fit::BoundRecording, usize)>,
    /// The subject-size search (`--fit-size`), as written under `subject_size`.
    size: Option<&'a serde_json::Value>,
    /// What the cost compares and why, as written under `cost_basis`.
    cost: &'a serde_json::Value,
    /// Print nothing on stdout (the result is read from the JSON).
    quiet: bool,
}

/// Ends a fit of `recording_path`: closes the progress bar, runs the fitted model's breaths
/// (`model`: the model as fitted, its skin fitted under --skin-fit), writes the result JSON
/// with its CSV and figure at `out` (with the registration of a named marker set, when one
/// was fitted) and prints the summary.
fn finish_fit(
    fit: crate::fit::Fit,
    config: &crate::Config,
    model: &crate::Config,
    recording_path: &Path,
    out: &Path,
    bar: &Progress,
    extras: FitExtras,
) -> Result<crate::fit::Fit> {
    let FitExtras {
        named_set,
        size,
        cost,
        quiet,
    } = extras;
    // The search's count leaves out the linearised start's runs; the fit's count is whole.
    bar.update(fit.evaluations, "");
    bar.finish(format!("best cost {:.3} mm", fit.cost_m * 1e3));
    let breath = fitted_breath(config, &fit)?;
    let breaths = BreathReport::of_fit(model, &fit)?;
    let outputs = write_fit_report(
        &fit,
        out,
        recording_path,
        model,
        Some(&breath),
        Some(&breaths),
    )?;
    let mut extra = vec![("cost_basis", cost.clone())];
    if let Some((bound, recorded)) = named_set {
        extra.push(("marker_set", marker_set_json(bound, *recorded)));
    }
    if let Some(size) = size {
        extra.push(("subject_size", size.clone()));
    }
    {
        let text =
            std::fs::read_to_string(&outputs.json).map_err(|e| Error::io(&outputs.json, e))?;
        let mut json: serde_json::Value = serde_json::from_str(&text)
            .map_err(|e| Error::State(format!("{}: {e}", outputs.json.display())))?;
        for (key, value) in extra {
            json[key] = value;
        }
        let text = serde_json::to_string_pretty(&json)
            .map_err(|e| Error::State(format!("result JSON: {e}")))?;
        std::fs::write(&outputs.json, text + "\n").map_err(|e| Error::io(&outputs.json, e))?;
    }
    if let Some((bound, recorded)) = named_set {
        if !quiet {
            println!("{}", marker_set_summary(bound, *recorded));
        }
        for w in &bound.orientation.warnings {
            eprintln!("warning: {w}");
        }
    }
    if quiet {
        return Ok(fit);
    }
    println!("{}", summary(&fit));
    println!(
        "breaths of the fitted model (phase: abdomen vs rib cage, + abdomen leads):\n{}",
        breaths.table()
    );
    let svg = outputs.png.with_extension("svg");
    let mut files = vec![
        outputs.json.display().to_string(),
        outputs.volume_csv.display().to_string(),
        outputs.png.display().to_string(),
    ];
    if svg.is_file() {
        files.push(svg.display().to_string());
    }
    let last = files.pop().unwrap_or_default();
    println!("wrote {} and {last}", files.join(", "));
    Ok(fit)
}

/// The fitted model breathing its fitted drive: three breaths from rest, the last two
/// summarised (tidal volume, compartment shares, excursion) for the result JSON.
fn fitted_breath(
    config: &crate::Config,
    fit: &crate::fit::Fit,
) -> Result<crate::model::run::BreathSummary> {
    breath_of(config, fit.drive)
}

/// `config`'s torso breathing `drive`: three breaths from rest, the last two summarised.
pub fn breath_of(config: &crate::Config, drive: Drive) -> Result<crate::model::run::BreathSummary> {
    let mut c = config.clone();
    c.drive = drive;
    c.drive.enabled = true;
    let period = 1.0 / c.drive.frequency;
    let mut torso = crate::Torso::new(c)?;
    let frames = crate::model::run::run(&mut torso, 3.0 * period, 28.0)?;
    Ok(crate::model::run::summarise(&frames, period))
}

/// What `torso fit`'s flags ask of the search, the reader and the fit (an error names the
/// flag).
pub fn fit_settings(args: &FitArgs) -> Result<(FitOptions, ReadOptions, FitFlags)> {
    let options = FitOptions {
        method: Method::from_name(&args.method)?,
        max_evals: args.max_evals,
        seed: args.seed,
        threads: args.threads.unwrap_or_else(default_threads),
        inspiratory_fraction: inspiratory_fraction(&args.ti_ttot)?,
        marker_offsets: args.marker_offsets,
        reference: args.reference.clone(),
        marker_radius: args.marker_radius * 1e-3,
        ..FitOptions::default()
    };
    if !(1..=2).contains(&options.threads) {
        return Err(Error::invalid("--threads", options.threads, "1 or 2"));
    }
    let flags = FitFlags {
        skin_fit: args.skin_fit,
        fit_size: args.fit_size,
        no_fit_size: args.no_fit_size,
        no_drift: args.no_drift,
        no_sway: args.no_sway,
        pose: PoseOptions {
            anterior: args.anterior.clone(),
        },
    };
    Ok((options, args.read.options()?, flags))
}

/// Runs `torso fit`.
pub fn main(args: &FitArgs) -> Result<()> {
    let (options, read, flags) = fit_settings(args)?;
    fit_file(&args.slp, &read, &args.model, &args.out, &options, &flags).map(|_| ())
}

/// `--ti-ttot`: `auto` (None) or a number in the drive's range.
fn inspiratory_fraction(text: &str) -> Result<Option<f64>> {
    let (lo, hi) = crate::model::drive::INSPIRATORY_FRACTION_RANGE;
    if text == "auto" {
        return Ok(None);
    }
    match text.parse::<f64>() {
        Ok(v) if (lo..=hi).contains(&v) => Ok(Some(v)),
        _ => Err(Error::invalid(
            "--ti-ttot",
            text,
            format!("auto or a number in [{lo}, {hi}]"),
        )),
    }
}

/// 2 threads for a fit's search when the machine has two or more cores, otherwise 1.
pub fn default_threads() -> usize {
    std::thread::available_parallelism()
        .map(|n| n.get().min(2))
        .unwrap_or(1)
}

/// Options of `torso demo`.
#[derive(Args, Debug)]
pub struct DemoArgs {
    /// Output directory (the FMU, the simulation, the fit and its report).
    #[arg(long, default_value = "out/demo")]
    pub out: PathBuf,
    /// The recording to fit [default: the bundled data/recordings/demo_quiet.csv, looked up
    /// from the working directory, then from the executable's folder upwards, then in the
    /// source tree the executable was built from].
    #[arg(long)]
    pub recording: Option<PathBuf>,
}

/// The bundled demo recording's path relative to a repository's root.
const DEMO_RECORDING: &str = "data/recordings/demo_quiet.csv";

/// Finds the bundled demo recording: in the working directory, in the executable's folder or
/// any folder above it (a `target/release/torso` of a clone), or in the source tree the
/// executable was built from; the error lists where it looked.
fn bundled_recording() -> Result<PathBuf> {
    let mut places = vec![PathBuf::from(DEMO_RECORDING)];
    if let Ok(exe) = std::env::current_exe() {
        places.extend(exe.ancestors().skip(1).map(|d| d.join(DEMO_RECORDING)));
    }
    places.push(Path::new(env!("CARGO_MANIFEST_DIR")).join(DEMO_RECORDING));
    places.iter().find(|p| p.is_file()).cloned().ok_or_else(|| {
        let looked: Vec<String> = places.iter().map(|p| p.display().to_string()).collect();
        Error::State(format!(
            "the bundled recording {DEMO_RECORDING} was not found (looked at {}); pass one with --recording",
            looked.join(", ")
        ))
    })
}

/// Packages `<out>/BreathingTorso.fmu` from the shared library beside this executable (as
/// `torso fmu build` does). A missing library is reported and skipped, not fatal: the rest
/// of the demo does not need the FMU.
fn package_fmu(out: &Path) -> Result<Option<PathBuf>> {
    let lib = crate::fmi::package::default_library()?;
    if !lib.exists() {
        println!(
            "FMU: skipped ({} not found; build it with `cargo build --release --lib`)",
            lib.display()
        );
        return Ok(None);
    }
    let p = crate::fmi::package::build_fmu(&lib, None, &out.join("BreathingTorso.fmu"))?;
    Ok(Some(p.path))
}

/// What the figures of a fit mean, one line each, printed by `torso demo` under the fit.
pub const FIT_NOTES: [&str; 4] = [
    "registration: the recording's first frame (end-expiration) rigidly moved onto the \
     model's rest markers; mean and rms are the distances left, rotation is the camera's \
     turn relative to the model",
    "cost: the mean distance between the model's markers and the recorded points over every \
     frame and point (thesis eq. 3.1), after one rigid correction over all frames",
    "noise floor: the mean length of the noise in the recording, the cost a perfect fit \
     reaches (a synthetic recording's truth file states it)",
    "phases: of each muscle family's sine, activation A/2 (sin(2 pi f t + phase) + 1), at the \
     recording's first frame, in (-pi, pi]; delta phase > 0: the diaphragm leads the rib cage",
];

/// The mean tidal volume of the fitted model's breaths [L], as the fit's JSON records it.
fn fitted_tidal_volume(json: &Path) -> Option<f64> {
    let text = std::fs::read_to_string(json).ok()?;
    let value: serde_json::Value = serde_json::from_str(&text).ok()?;
    value["breaths_summary"]["mean"]["tidal_volume_l"].as_f64()
}

/// Runs `torso demo`.
pub fn demo(args: &DemoArgs) -> Result<()> {
    let start = std::time::Instant::now();
    prepare_output_dir(&args.out)?;
    println!("== 1. FMU");
    if let Some(fmu) = package_fmu(&args.out)? {
        println!("wrote {}", fmu.display());
    }

    println!(
        "== 2. simulate the default subject (quiet breathing, 20 s) at level of detail 0 and \
         rtol 1e-4, the settings of the bundled recording"
    );
    let model = ModelArgs {
        subject: SubjectArgs {
            sex: "male".into(),
            age: 30.0,
            stature: Some(1.75),
            mass: Some(75.0),
            breast_size: 0.0,
            posture: "standing".into(),
            lod: Some(0),
            muscle_law: "thesis".into(),
            gravity: crate::dynamics::GRAVITY,
            gravity_loads: "preloaded".into(),
            postural_tone: "on".into(),
        },
        solver: SolverArgs {
            solver: "dopri5".into(),
            // The bundled recording was made at this tolerance; 1.5x faster than 1e-6 with
            // the same tidal volume to 1 mL.
            rtol: 1e-4,
        },
        grid: "10x6".into(),
    };
    let mut torso = crate::Torso::new(model.config(Drive::quiet())?)?;
    let frames = crate::model::run::run(&mut torso, 20.0, 56.0)?;
    let s = crate::model::run::summarise(&frames, 8.0);
    let sim = args.out.join("simulation.csv");
    super::simulate::write_csv(&sim, &frames)?;
    println!(
        "tidal volume {:.3} L, end-expiratory volume {:.3} L, rib-cage share {:.0} %; wrote {}",
        s.tidal_volume,
        s.end_expiratory_volume,
        100.0 * s.rib_cage_share,
        sim.display()
    );
    let (readme, _) = super::simulate::default_summary()?;
    println!(
        "`torso simulate` at its defaults (level of detail 1, rtol 1e-6), whose figures the \
         README quotes, gives a tidal volume of {:.3} L: level 0's coarser diaphragm moves less \
         air for the same drive (docs/anatomy.md)",
        readme.tidal_volume
    );

    let recording = match &args.recording {
        Some(r) => r.clone(),
        None => bundled_recording()?,
    };
    println!("== 3. fit {}", recording.display());
    if !recording.exists() {
        return Err(Error::State(format!(
            "{} is missing: generate it with `torso synth --lod 0 --rtol 1e-4 --duration 8 --seed 7 --out {} --truth {}`",
            recording.display(),
            recording.display(),
            recording.with_extension("truth.json").display()
        )));
    }
    let fit = fit_file(
        &recording,
        &ReadOptions::default(),
        &model,
        &args.out.join("fit.json"),
        &FitOptions {
            threads: default_threads(),
            ..FitOptions::default()
        },
        &FitFlags::default(),
    )?;
    println!("what these figures mean:");
    for note in FIT_NOTES {
        println!("  {note}");
    }
    if let Some(vt) = fitted_tidal_volume(&args.out.join("fit.json")) {
        println!(
            "  VT: the tidal volume of the model breathing the fitted drive, {vt:.3} L; step 2's \
             {:.3} L is the same model breathing the quiet drive, and the two differ by what the \
             fitted frequency, amplitudes and phases differ from it (the drive the recording \
             was made with is compared below when its truth file is there)",
            s.tidal_volume
        );
    }
    let truth_path = recording.with_extension("truth.json");
    if let Ok(text) = std::fs::read_to_string(&truth_path)
        && let Ok(truth) = serde_json::from_str::<serde_json::Value>(&text)
    {
        let got = crate::fit::report::drive_fmi(&fit.drive);
        println!(
            "== 4. fitted against the truth the recording was synthesised with ({})",
            truth_path.display()
        );
        println!(
            "{:<26} {:>9} {:>9} {:>9}",
            "parameter", "fitted", "truth", "error"
        );
        for key in [
            "drive.frequency",
            "drive.ribs.amplitude",
            "drive.diaphragm.amplitude",
            "drive.ribs.phase",
            "drive.diaphragm.phase",
        ] {
            let (f, t) = (
                got[key].as_f64().unwrap_or(f64::NAN),
                truth[key].as_f64().unwrap_or(f64::NAN),
            );
            let error = if key.ends_with("phase") {
                crate::fit::fitting::wrap_angle(f - t)
            } else {
                f - t
            };
            println!("{key:<26} {f:>9.4} {t:>9.4} {error:>+9.4}");
        }
        let floor = truth["noise_floor_m"].as_f64().unwrap_or(f64::NAN);
        println!(
            "cost {:.3} mm against the recording's noise floor {:.3} mm ({:.2} x the floor)",
            fit.cost_m * 1e3,
            floor * 1e3,
            fit.cost_m / floor
        );
    }
    println!("demo done in {:.1} s", start.elapsed().as_secs_f64());
    Ok(())
}

/// Options of `torso fit-sweep`.
#[derive(Args, Debug)]
pub struct SweepArgs {
    /// Output directory: the recordings with their truth, sweep.json and sweep.md.
    #[arg(long, default_value = "out/fit_sweep")]
    pub out: PathBuf,
    /// Recording length [s].
    #[arg(long, default_value_t = 18.0)]
    pub duration: f64,
    /// Level of detail 0, 1 or 2.
    #[arg(long, default_value_t = 0)]
    pub lod: u32,
    /// Relative tolerance of the solver.
    #[arg(long, default_value_t = 1e-6)]
    pub rtol: f64,
    /// Search method: nelder-mead, multistart or cmaes.
    #[arg(long, default_value = "nelder-mead")]
    pub method: String,
    /// Largest number of cost evaluations per fit [default: 120; 200 with --mismatch].
    #[arg(long)]
    pub max_evals: Option<usize>,
    /// Recordings fitted at once (threads).
    #[arg(long, visible_alias = "threads", default_value_t = 1)]
    pub jobs: usize,
    /// Run only the cases whose label contains this text (e.g. `woman`, `supine forced`).
    #[arg(long)]
    pub only: Option<String>,
    /// The sweep under model mismatch instead (docs/fit_report.md): recordings made at
    /// --truth-lod by a subject 8 % taller and heavier, Ti/Ttot drawn in 0.38-0.45, 10 %
    /// breath-to-breath variation, 0.5 mm noise, 2 % dropped points, for each of
    /// --marker-sets, each fitted at every --fit-lods with the default subject and the
    /// Ti/Ttot read off the recording; --lod and --only do not apply.
    #[arg(long)]
    pub mismatch: bool,
    /// With --mismatch: level of detail of the model making the recordings.
    #[arg(long, default_value_t = 2)]
    pub truth_lod: u32,
    /// With --mismatch: levels of detail the recordings are fitted at, comma separated.
    #[arg(long, default_value = "0,1")]
    pub fit_lods: String,
    /// With --mismatch: marker sets, comma separated (grid, chest30, oep89).
    #[arg(long, default_value = "grid,chest30,oep89")]
    pub marker_sets: String,
    /// With --mismatch: base seed of the recordings (marker set k uses seed + k).
    #[arg(long, default_value_t = 301)]
    pub seed: u64,
    /// With --mismatch: fit the grid as `torso fit --skin-fit` does (the rest-pose reference
    /// grids are written to --out) rather than with rigid registration alone.
    #[arg(long)]
    pub skin_fit: bool,
    /// With --mismatch: fit the grid with each marker compared about its own mean (as
    /// `torso fit --marker-offsets`).
    #[arg(long)]
    pub marker_offsets: bool,
    /// With --mismatch: estimate the subject's stature and mass from each recording's first
    /// frame before fitting (as `torso fit --fit-size`).
    #[arg(long, conflicts_with = "no_fit_size")]
    pub fit_size: bool,
    /// Keep the given (or default) stature and mass: no size estimate even when neither is
    /// given or the first frame registers with rms over 5 mm.
    #[arg(long)]
    pub no_fit_size: bool,
}

/// Runs `torso fit-sweep --mismatch`.
fn sweep_mismatch(args: &SweepArgs) -> Result<()> {
    use crate::fit::mismatch::{MismatchOptions, run_mismatch, table};
    let fit_lods = args
        .fit_lods
        .split(',')
        .map(|t| {
            t.trim().parse::<u32>().map_err(|_| {
                Error::invalid(
                    "--fit-lods",
                    &args.fit_lods,
                    "levels 0, 1, 2 separated by commas",
                )
            })
        })
        .collect::<Result<Vec<_>>>()?;
    let options = MismatchOptions {
        duration: args.duration,
        truth_lod: args.truth_lod,
        fit_lods,
        marker_sets: args
            .marker_sets
            .split(',')
            .map(|t| t.trim().to_string())
            .collect(),
        max_evals: args
            .max_evals
            .unwrap_or(crate::fit::mismatch::ACCEPT_EVALUATIONS),
        rtol: args.rtol,
        jobs: args.jobs,
        seed: args.seed,
        grid_skin_fit: args.skin_fit.then(|| args.out.clone()),
        grid_marker_offsets: args.marker_offsets,
        fit_size: args.fit_size,
        ..MismatchOptions::default()
    };
    options.validate()?;
    Method::from_name(&args.method)?;
    if args.method != "nelder-mead" {
        return Err(Error::invalid(
            "--method",
            &args.method,
            "nelder-mead with --mismatch",
        ));
    }
    prepare_output_dir(&args.out)?;
    let start = std::time::Instant::now();
    let (truths, rows) = run_mismatch(&options, &|m| println!("{m}"))?;
    let mut recordings = Vec::new();
    for t in &truths {
        let path = args.out.join(format!("mismatch_{}.csv", t.marker_set));
        if t.labels.is_empty() {
            t.synthetic.recording.write(&path)?;
        } else {
            Markers {
                labels: t.labels.clone(),
                times: t.synthetic.recording.times.clone(),
                frames: t.synthetic.recording.frames.clone(),
                units: Units::Metres,
                format: crate::recording::Format::MarkerCsv,
                provenance: Vec::new(),
            }
            .write(&path)?;
        }
        recordings.push(serde_json::json!({
            "marker_set": t.marker_set,
            "recording": path.display().to_string(),
            "ti_ttot": t.ti_ttot,
            "noise_floor_m": t.synthetic.noise_floor_m,
            "drive_breaths": t.breaths.iter().map(|b| serde_json::json!({"onset_s": b.0, "period_s": b.1})).collect::<Vec<_>>(),
            "truth_tidal_volumes_l": t.tidal_volumes_l,
            "truth_mean_tidal_volume_l": t.mean_tidal_volume_l(),
            "truth_drive": crate::fit::report::drive_fmi(&t.synthetic.truth),
            "wall_s": t.wall_s,
        }));
    }
    let text = table(&rows);
    let command = format!(
        "torso fit-sweep --mismatch{}{} --duration {} --truth-lod {} --fit-lods {} --marker-sets {} --max-evals {} --rtol {} --seed {} --jobs {}",
        if args.skin_fit { " --skin-fit" } else { "" },
        if args.marker_offsets {
            " --marker-offsets"
        } else {
            ""
        },
        args.duration,
        args.truth_lod,
        args.fit_lods,
        args.marker_sets,
        options.max_evals,
        args.rtol,
        args.seed,
        args.jobs
    );
    let md = args.out.join("mismatch.md");
    std::fs::write(&md, format!("{command}\n\n{text}")).map_err(|e| Error::io(&md, e))?;
    let js = args.out.join("mismatch.json");
    let body = serde_json::to_string_pretty(&serde_json::json!({
        "command": command,
        "truth_subject": crate::fit::report::subject_fmi(&crate::fit::mismatch::truth_subject()),
        "variability": options.variability,
        "noise_m": options.noise,
        "dropout": options.dropout,
        "recordings": recordings,
        "cases": rows.iter().map(|r| r.json()).collect::<Vec<_>>(),
    }))
    .map_err(|e| Error::State(format!("mismatch JSON: {e}")))?;
    std::fs::write(&js, body + "\n").map_err(|e| Error::io(&js, e))?;
    println!("{text}");
    let failed = rows.iter().filter(|r| !r.failures().is_empty()).count();
    println!(
        "{} of {} cases meet every criterion; {:.1} s; wrote {} and {}",
        rows.len() - failed,
        rows.len(),
        start.elapsed().as_secs_f64(),
        md.display(),
        js.display()
    );
    Ok(())
}

/// Runs `torso fit-sweep`.
pub fn sweep(args: &SweepArgs) -> Result<()> {
    use crate::fit::sweep::{SweepOptions, case_config, default_cases, run_sweep_with, table};
    if args.mismatch {
        return sweep_mismatch(args);
    }
    let max_evals = args
        .max_evals
        .unwrap_or(crate::fit::sweep::ACCEPT_EVALUATIONS);
    let options = SweepOptions {
        duration: args.duration,
        level_of_detail: args.lod,
        rtol: args.rtol,
        fit: FitOptions {
            method: Method::from_name(&args.method)?,
            max_evals,
            ..FitOptions::default()
        },
        jobs: args.jobs,
    };
    crate::fit::SynthOptions {
        duration: args.duration,
        ..Default::default()
    }
    .validate()?;
    let cases: Vec<_> = default_cases()
        .into_iter()
        .filter(|c| {
            args.only
                .as_ref()
                .is_none_or(|o| c.label.contains(o.as_str()))
        })
        .collect();
    if cases.is_empty() {
        return Err(Error::invalid(
            "--only",
            args.only.clone().unwrap_or_default(),
            "text found in a case label such as `man standing quiet`",
        ));
    }
    for c in &cases {
        case_config(c, &options)?;
    }
    prepare_output_dir(&args.out)?;
    let start = std::time::Instant::now();
    // Progress over every case's evaluations; a finished case counts its whole budget.
    let bar = Progress::new("fit-sweep", cases.len() * max_evals, "evaluations").up_to();
    let counts = std::sync::Mutex::new(vec![0usize; cases.len()]);
    let finished = std::sync::atomic::AtomicUsize::new(0);
    let show = |counts: &[usize]| {
        bar.update(
            counts.iter().sum(),
            format!(
                "{} of {} recordings fitted",
                finished.load(std::sync::atomic::Ordering::SeqCst),
                counts.len()
            ),
        )
    };
    let rows = run_sweep_with(
        &cases,
        &options,
        &|r| {
            if let (Ok(mut c), Some(i)) = (
                counts.lock(),
                cases.iter().position(|c| c.label == r.case.label),
            ) {
                c[i] = max_evals;
                finished.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
                show(&c);
            }
            bar.message(&format!(
                "{}: {} evaluations, {:.1} s, cost {:.3} mm (floor {:.3})",
                r.case.label,
                r.evaluations,
                r.wall_s,
                r.cost_m * 1e3,
                r.synthetic.noise_floor_m * 1e3
            ));
        },
        &|i, n| {
            if let Ok(mut c) = counts.lock() {
                c[i] = n.min(max_evals);
                show(&c);
            }
        },
    )?;
    bar.finish(format!("{} recordings fitted", rows.len()));
    let mut json_rows = Vec::new();
    for (i, r) in rows.iter().enumerate() {
        let stem = format!("rec{}_{}", i + 1, r.case.label.replace(' ', "_"));
        let rec = args.out.join(format!("{stem}.csv"));
        r.synthetic.recording.write(&rec)?;
        let synth = crate::fit::SynthOptions {
            drive: crate::fit::sweep::case_drive(r.case.forced),
            duration: args.duration,
            seed: r.case.seed,
            ..Default::default()
        };
        let truth = crate::fit::report::truth_json(&r.synthetic, &r.case.subject, args.lod, &synth);
        let tpath = args.out.join(format!("{stem}.truth.json"));
        let text = serde_json::to_string_pretty(&truth)
            .map_err(|e| Error::State(format!("truth JSON: {e}")))?;
        std::fs::write(&tpath, text + "\n").map_err(|e| Error::io(&tpath, e))?;
        json_rows.push(serde_json::json!({
            "case": r.case.label,
            "recording": rec.display().to_string(),
            "truth": truth,
            "fitted": crate::fit::report::drive_fmi(&r.fitted),
            "delta_phase": r.delta_phase,
            "errors": {
                "ribs_amplitude_rel": r.ribs_error(),
                "diaphragm_amplitude_rel": r.diaphragm_error(),
                "delta_phase_rad": r.phase_error(),
                "frequency_rel": r.frequency_error(),
                "cost_over_noise_floor": r.cost_ratio(),
            },
            "cost_m": r.cost_m,
            "noise_floor_m": r.synthetic.noise_floor_m,
            "evaluations": r.evaluations,
            "converged": r.converged,
            "wall_s": r.wall_s,
            "failures": r.failures(),
        }));
    }
    let text = table(&rows);
    let header = format!(
        "torso fit-sweep --duration {} --lod {} --rtol {} --method {} --max-evals {} --jobs {}\n\n",
        args.duration, args.lod, args.rtol, args.method, max_evals, args.jobs
    );
    let md = args.out.join("sweep.md");
    std::fs::write(&md, header + &text).map_err(|e| Error::io(&md, e))?;
    let js = args.out.join("sweep.json");
    let body = serde_json::to_string_pretty(&serde_json::json!({
        "duration_s": args.duration,
        "level_of_detail": args.lod,
        "rtol": args.rtol,
        "method": args.method,
        "max_evals": max_evals,
        "jobs": args.jobs,
        "cases": json_rows,
    }))
    .map_err(|e| Error::State(format!("sweep JSON: {e}")))?;
    std::fs::write(&js, body + "\n").map_err(|e| Error::io(&js, e))?;
    println!("{text}");
    let failed = rows.iter().filter(|r| !r.failures().is_empty()).count();
    println!(
        "{} of {} recordings meet every acceptance item; {:.1} s; wrote {} and {}",
        rows.len() - failed,
        rows.len(),
        start.elapsed().as_secs_f64(),
        md.display(),
        js.display()
    );
    Ok(())
}
