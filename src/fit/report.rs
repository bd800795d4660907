//! Outputs of a fit and of a synthetic recording: the result JSON (drive parameters under
//! their FMI names, and the per-breath report of [`super::clinical`] when it was made),
//! the fitted lung volume (and compartment volumes) as CSV, a PNG/SVG figure (lung volume
//! over time, a few markers recorded vs fitted), the ground-truth JSON of a synthetic
//! recording, and the text summary printed by the CLI.

use super::clinical::BreathReport;
use super::{Fit, Synthetic};
use crate::anatomy::Subject;
use crate::model::Drive;
use crate::model::run::BreathSummary;
use crate::{Error, Result};
use serde_json::{Value, json};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The drive under the FMI parameter names (`drive.frequency`, `drive.ribs.amplitude`, ...).
pub fn drive_fmi(drive: &Drive) -> serde_json::Map<String, Value> {
    let mut m = serde_json::Map::new();
    m.insert("drive.frequency".into(), json!(drive.frequency));
    m.insert(
        "drive.inspiratory_fraction".into(),
        json!(drive.inspiratory_fraction),
    );
    for (name, w) in [
        ("ribs", drive.ribs),
        ("diaphragm", drive.diaphragm),
        ("abdominals", drive.abdominals),
    ] {
        m.insert(format!("drive.{name}.amplitude"), json!(w.amplitude));
        m.insert(format!("drive.{name}.phase"), json!(w.phase));
    }
    m
}

/// The subject under the FMI parameter names.
pub fn subject_fmi(subject: &Subject) -> Value {
    json!({
        "subject.sex": subject.sex,
        "subject.age": subject.age,
        "subject.stature": subject.stature,
        "subject.mass": subject.mass,
        "subject.breast_size": subject.breast_size,
        "posture": subject.posture,
    })
}

/// The model a fit ran, other than its subject and drive, under the FMI parameter names: the
/// level of detail, the marker grid, the lung ratio, the skin reference (`slp.reference`: the
/// rest-pose grid of a `--skin-fit`, empty otherwise) and the subject mesh folder
/// (`subject.mesh_dir`, empty for the generated geometry), and the laws it ran under
/// (`muscle_law`, `gravity`, `gravity_loads`, `postural_tone`, as FMI codes). With `subject`
/// and the drive this is what `torso fmu build --subject` bakes into a personalised FMU.
pub fn model_fmi(config: &crate::Config) -> Value {
    let path = |p: &Option<PathBuf>| {
        p.as_ref()
            .map(|p| p.display().to_string())
            .unwrap_or_default()
    };
    json!({
        "scene.level_of_detail": config.scene.level_of_detail,
        "grid.rows": config.scene.grid_rows,
        "grid.cols": config.scene.grid_cols,
        "lung.ratio": config.lung_ratio,
        "slp.reference": path(&config.scene.slp_reference),
        "subject.mesh_dir": path(&config.subject_mesh_dir),
        "muscle_law": config.muscle_law.code(),
        "gravity": config.gravity,
        "gravity_loads": config.gravity_loads.code(),
        "postural_tone": crate::model::postural_tone_code(config.postural_tone),
    })
}

/// The provenance key of the level of detail a recording was made at.
pub const LOD_KEY: &str = "scene.level_of_detail";

/// The model a recording was made with, as the provenance entries `torso synth` writes and
/// `torso fit` compares: the level of detail and the subject under their FMI names (sex
/// and posture spelt as the command line takes them).
pub fn model_provenance(subject: &Subject, level_of_detail: u32) -> Vec<(String, String)> {
    let name = |d: &dyn std::fmt::Debug| format!("{d:?}").to_ascii_lowercase();
    vec![
        (LOD_KEY.into(), level_of_detail.to_string()),
        ("subject.sex".into(), name(&subject.sex)),
        ("subject.age".into(), subject.age.to_string()),
        ("subject.stature".into(), subject.stature.to_string()),
        ("subject.mass".into(), subject.mass.to_string()),
        (
            "subject.breast_size".into(),
            subject.breast_size.to_string(),
        ),
        ("posture".into(), name(&subject.posture)),
    ]
}

/// The entries of `model` (from [`model_provenance`]) that `recorded` names with another
/// value, as `key recorded (fit: value)`; numbers compare as numbers.
pub fn provenance_differences(
    recorded: &[(String, String)],
    model: &[(String, String)],
) -> Vec<String> {
    model
        .iter()
        .filter_map(|(k, v)| {
            let r = recorded.iter().find(|(rk, _)| rk == k)?.1.as_str();
            let same = match (r.parse::<f64>(), v.parse::<f64>()) {
                (Ok(a), Ok(b)) => a == b,
                _ => r.eq_ignore_ascii_case(v),
            };
            (!same).then(|| format!("{k} {r} (fit: {v})"))
        })
        .collect()
}

/// Where a fit's outputs went.
#[derive(Clone, Debug, PartialEq)]
pub struct FitOutputs {
    /// result.json.
    pub json: PathBuf,
    /// Fitted lung volume CSV.
    pub volume_csv: PathBuf,
    /// PNG report (an SVG twin sits beside it).
    pub png: PathBuf,
}

/// The result JSON of a fit of the model configured by `model` (its drive aside).
/// `breaths` (the per-breath report of the fitted model) fills the `breaths` array and
/// `breaths_summary`; without it the array is empty and the summary null. The recording's
/// own breath timing is `recording_breaths`.
pub fn fit_json(
    fit: &Fit,
    recording: &Path,
    model: &crate::Config,
    volume_csv: &Path,
    breath: Option<&BreathSummary>,
    breaths: Option<&BreathReport>,
) -> Value {
    let mut m = drive_fmi(&fit.drive);
    let q = super::quality::quality(fit);
    let noise_floor = q.noise.floor_m;
    let rot = fit.to_model.rotation.angle().to_degrees();
    let extra = json!({
        "cost_m": fit.cost_m,
        "noise_floor_estimate_m": noise_floor,
        "cost_over_noise_floor_estimate": fit.cost_m / noise_floor,
        "quality": quality_json(&q),
        "drift": fit.drift_knots.as_ref().map(|k| json!({
            "method": "per marker coordinate a linear spline in time, knots at least three breaths apart, projected out of the cost in closed form at each evaluation (variable projection)",
            "knots_s": k,
        })),
        "sensitivity": fit.sensitivity.iter().map(|p| json!({
            "parameter": p.name,
            "rms_marker_displacement_per_unit_m": p.raw_m,
            "after_drift_projection_m": p.projected_m,
            "kept_by_projection": p.projected_m / p.raw_m,
        })).collect::<Vec<_>>(),
        "sway": fit.sway.as_ref().map(|s| s.json()),
        "repairs": fit.repairs,
        "initial_cost_m": fit.initial_cost_m,
        "skin_fit_error_m": match fit.skin_fit {
            Some((before, after)) => json!({"before": before, "after": after, "skin_fitted": true}),
            // Rigid registration only: the remaining first-frame distance, before = after.
            None => json!({
                "before": fit.registration_mean_m,
                "after": fit.registration_mean_m,
                "skin_fitted": false,
            }),
        },
        "evaluations": fit.evaluations,
        "evaluations_ahead_unused": fit.unused_ahead,
        "converged": fit.converged,
        "converged_means": "the search met its tolerances (simplex size and cost spread); it says nothing of how well the model explains the recording (see quality)",
        "wall_s": fit.wall_s,
        "delta_phase": fit.delta_phase,
        "breaths": breaths.map_or(json!([]), |r| r.json_breaths()),
        "breaths_summary": breaths.map(|r| r.json_summary()),
        "recording_breaths": {
            "source": "principal displacement of the recording (onsets at its minima)",
            "median_ti_ttot": fit.breathing.ti_ttot,
            "onset_s": fit.breathing.onsets,
            "ti_s": fit.breathing.breaths.iter().map(|b| b.ti).collect::<Vec<_>>(),
            "te_s": fit.breathing.breaths.iter().map(|b| b.te).collect::<Vec<_>>(),
            "ttot_s": fit.breathing.breaths.iter().map(|b| b.ttot).collect::<Vec<_>>(),
            "depth_relative_to_median": fit.breathing.depths,
        },
        "fitted_breath": breath.map(|b| json!({
            "source": "the fitted model breathing its fitted drive, three breaths from rest, the last two summarised",
            "tidal_volume_l": b.tidal_volume,
            "end_expiratory_volume_l": b.end_expiratory_volume,
            "rib_cage_share": b.rib_cage_share,
            "abdominal_share": 1.0 - b.rib_cage_share,
            "dome_excursion_m": b.dome_excursion,
        })),
        "lung_volume_csv": volume_csv.display().to_string(),
        "method": fit.method.name(),
        "recording": recording.display().to_string(),
        "frequency": {
            "hz": fit.frequency.frequency_hz,
            "spectral_hz": fit.frequency.spectral_hz,
            "autocorrelation_hz": fit.frequency.autocorrelation_hz,
            "from_autocorrelation": fit.frequency.from_autocorrelation,
        },
        "registration": {
            "rms_m": fit.registration_rms_m,
            "mean_m": fit.registration_mean_m,
            "rotation_deg": rot,
            "translation_m": [fit.to_model.translation.x, fit.to_model.translation.y, fit.to_model.translation.z],
        },
        "subject": subject_fmi(&model.subject),
        "model": model_fmi(model),
    });
    if let Value::Object(e) = extra {
        m.extend(e);
    }
    Value::Object(m)
}

/// The `quality` entry of the result JSON (see [`super::quality`]).
pub fn quality_json(q: &super::quality::Quality) -> Value {
    let finite = |v: f64| if v.is_finite() { json!(v) } else { Value::Null };
    json!({
        "noise": {
            "method": "local cubic fits over an eighth of a breath per marker coordinate (Savitzky-Golay residual, MAD), checked against second differences",
            "sigma_m": finite(q.noise.sigma_m),
            "floor_m": finite(q.noise.floor_m),
            "second_difference_sigma_m": finite(q.noise.second_difference_sigma_m),
            "prefiltered": q.noise.prefiltered,
            "window_samples": q.noise.window,
            "residuals": q.noise.samples,
        },
        "variance_explained": {
            "about": "the recorded motion about each marker's mean",
            "overall": finite(q.explained.overall),
            "above_noise": finite(q.explained.above_noise),
            "per_marker": q.explained.per_marker.iter().map(|v| finite(*v)).collect::<Vec<_>>(),
            "motion_rms_m": q.explained.motion_rms_m,
            "residual_rms_m": q.explained.residual_rms_m,
            "split": match (&q.drift_share, &q.after_drift) {
                (Some(d), Some(a)) => json!({
                    "drift": finite(*d),
                    "drive": finite(a.above_noise),
                    "drive_overall": finite(a.overall),
                    "residual_rms_m": a.residual_rms_m,
                    "sway": q.sway_share.map(finite),
                    "note": if q.sway_share.is_some() {
                        "sway: its share of the recorded motion about the means, removed before the fit; drift: its share of the motion (after the sway) about the means; drive: its share of the motion left after the drift, above the noise"
                    } else {
                        "drift: its share of the motion about the means; drive: its share of the motion left after the drift, above the noise; sway is not removed by this fit (see sway)"
                    },
                }),
                _ => json!({
                    "drive": finite(q.explained.above_noise),
                    "residual_rms_m": q.explained.residual_rms_m,
                    "sway": q.sway_share.map(finite),
                    "drift": Value::Null,
                    "note": if q.sway_share.is_some() {
                        "sway: its share of the recorded motion about the means, removed before the fit; drift is not removed: the drive's share is of the motion after the sway, above the noise"
                    } else {
                        "sway and drift are not removed by this fit: the drive's share is of all the motion above the noise"
                    },
                }),
            },
        },
        "cardiac": q.cardiac.map(|c| json!({
            "method": "periodogram of the residual (recorded minus fitted, after the drift) summed over the marker coordinates, 0.8-2.5 Hz, each bin against the mean of the others (F test, Bonferroni over the bins, 1 %); reported, not fitted",
            "frequency_hz": c.frequency_hz,
            "beats_per_min": 60.0 * c.frequency_hz,
            "amplitude_rms_m": c.amplitude_rms_m,
            "amplitude_max_m": c.amplitude_max_m,
            "marker_index": c.marker,
            "power_ratio": c.ratio,
            "false_alarm_probability": c.false_alarm,
        })),
        "drive_parameters_at_bounds": q.at_bounds,
        "explains_recording": q.explains,
        "notes": q.notes,
    })
}

fn create_parent(path: &Path) -> Result<()> {
    if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
    }
    Ok(())
}

/// Writes result JSON at `json_path` of a fit of the model configured by `model`, the lung
/// volume CSV and the figure beside it (`<stem>_lung_volume.csv`, `<stem>_report.png` /
/// `.svg`).
pub fn write_fit(
    fit: &Fit,
    json_path: &Path,
    recording: &Path,
    model: &crate::Config,
    breath: Option<&BreathSummary>,
) -> Result<FitOutputs> {
    write_fit_report(fit, json_path, recording, model, breath, None)
}

/// [`write_fit`] with the per-breath report of the fitted model: its breaths in the JSON,
/// the rib-cage and abdominal displaced volumes as two more columns of the CSV
/// (`volume.rib_cage_displaced`, `volume.abdomen_displaced`, as the FMU names them).
pub fn write_fit_report(
    fit: &Fit,
    json_path: &Path,
    recording: &Path,
    model: &crate::Config,
    breath: Option<&BreathSummary>,
    breaths: Option<&BreathReport>,
) -> Result<FitOutputs> {
    create_parent(json_path)?;
    let dir = json_path
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."))
        .to_path_buf();
    let stem = json_path
        .file_stem()
        .map(|s| s.to_string_lossy().into_owned())
        .unwrap_or_else(|| "result".into());
    let volume_csv = dir.join(format!("{stem}_lung_volume.csv"));
    let png = dir.join(format!("{stem}_report.png"));

    let io = |p: &Path| {
        let p = p.to_path_buf();
        move |e| Error::io(p.clone(), e)
    };
    let mut w =
        std::io::BufWriter::new(std::fs::File::create(&volume_csv).map_err(io(&volume_csv))?);
    match breaths.map(|r| &r.compartments) {
        Some(c) => {
            writeln!(
                w,
                "time,volume.lung,volume.rib_cage_displaced,volume.abdomen_displaced"
            )
            .map_err(io(&volume_csv))?;
            for (k, t) in fit.times.iter().enumerate() {
                let v = fit.fitted.lung_volume.get(k).copied().unwrap_or(f64::NAN);
                let r = c.rib_cage.get(k).copied().unwrap_or(f64::NAN);
                let a = c.abdomen.get(k).copied().unwrap_or(f64::NAN);
                writeln!(w, "{t:.6},{v:.6},{r:.7},{a:.7}").map_err(io(&volume_csv))?;
            }
        }
        None => {
            writeln!(w, "time,volume.lung").map_err(io(&volume_csv))?;
            for (t, v) in fit.times.iter().zip(&fit.fitted.lung_volume) {
                writeln!(w, "{t:.6},{v:.6}").map_err(io(&volume_csv))?;
            }
        }
    }
    w.flush().map_err(io(&volume_csv))?;

    let value = fit_json(fit, recording, model, &volume_csv, breath, breaths);
    let text = serde_json::to_string_pretty(&value)
        .map_err(|e| Error::State(format!("result JSON: {e}")))?;
    std::fs::write(json_path, text + "\n").map_err(io(json_path))?;

    super::figure::write_report_figure(&dir, &format!("{stem}_report"), fit, breaths)?;
    Ok(FitOutputs {
        json: json_path.to_path_buf(),
        volume_csv,
        png,
    })
}

/// The ground-truth JSON of a synthetic recording.
pub fn truth_json(
    s: &Synthetic,
    subject: &Subject,
    level_of_detail: u32,
    options: &super::SynthOptions,
) -> Value {
    let mut m = drive_fmi(&s.truth);
    let q = s.camera.rotation;
    let r = q.to_rotation_matrix();
    let rows: Vec<Vec<f64>> = (0..3)
        .map(|i| (0..3).map(|j| r[(i, j)]).collect())
        .collect();
    let extra = json!({
        "delta_phase": super::fitting::wrap_angle(s.truth.diaphragm.phase - s.truth.ribs.phase),
        "subject": subject_fmi(subject),
        "posture": subject.posture,
        "scene.level_of_detail": level_of_detail,
        "grid.rows": s.recording.grid.0,
        "grid.cols": s.recording.grid.1,
        "rate_hz": options.rate,
        "duration_s": options.duration,
        "noise_m": options.noise,
        "noise_floor_m": s.noise_floor_m,
        "variability": options.variability,
        "dropout": options.dropout,
        "seed": options.seed,
        "camera": {
            "description": "model frame -> camera frame: p_camera = R p_model + t; registration recovers the inverse",
            "rotation_matrix": rows,
            "quaternion_wxyz": [q.w, q.i, q.j, q.k],
            "translation_m": [s.camera.translation.x, s.camera.translation.y, s.camera.translation.z],
        },
        "model_start_time_s": s.start_time,
        "nominal_drive": drive_fmi(&options.drive),
        "breaths": s.schedule.len().saturating_sub(1),
        "breath_schedule": s.breaths.0.iter().map(|b| json!({
            "start_s": b.start - s.start_time,
            "period_s": b.period,
            "depth": b.depth,
        })).collect::<Vec<_>>(),
    });
    if let Value::Object(e) = extra {
        m.extend(e);
    }
    Value::Object(m)
}

/// The text summary of a fit.
pub fn summary(fit: &Fit) -> String {
    let d = &fit.drive;
    let q = super::quality::quality(fit);
    let sway = match q.sway_share {
        Some(s) => format!(
            "sway removed before, {:.0} % of the recorded motion",
            100.0 * s
        ),
        None => "sway not removed".to_string(),
    };
    let explained = if let (Some(d), Some(a)) = (q.drift_share, &q.after_drift) {
        format!(
            "{:.0} % of the markers' motion about their means is drift; the drive explains {:.0} % of the rest ({:.0} % above the noise; {sway})",
            100.0 * d,
            100.0 * a.overall,
            100.0 * a.above_noise
        )
    } else if q.explained.above_noise.is_finite() {
        format!(
            "{:.0} % of the markers' motion about their means ({:.0} % above the noise; {sway}, drift not removed)",
            100.0 * q.explained.overall,
            100.0 * q.explained.above_noise
        )
    } else {
        format!(
            "{:.0} % of the markers' motion about their means (it does not rise above the noise)",
            100.0 * q.explained.overall
        )
    };
    let noise = format!(
        "{:.3} mm (local cubic fits; sigma {:.3} mm per coordinate), cost {:.2} x the floor{}",
        q.noise.floor_m * 1e3,
        q.noise.sigma_m * 1e3,
        fit.cost_m / q.noise.floor_m,
        if q.noise.prefiltered {
            "; filtered before export?"
        } else {
            ""
        }
    );
    let mut notes: String = q
        .notes
        .iter()
        .map(|n| format!("\nquality               {n}"))
        .collect();
    for r in &fit.repairs {
        notes.push_str(&format!("\nrepaired              {r}"));
    }
    if let Some(sway) = fit.sway.as_ref().filter(|s| s.removed) {
        notes.push('\n');
        notes.push_str(&sway.summary());
    }
    for p in &fit.sensitivity {
        notes.push_str(&format!(
            "\nsensitivity           {}: {:.2} mm per unit, {:.2} after the drift is projected out ({:.0} % kept)",
            p.name,
            p.raw_m * 1e3,
            p.projected_m * 1e3,
            100.0 * p.projected_m / p.raw_m
        ));
    }
    format!(
        "breathing frequency   {:.4} Hz ({:.1} breaths/min)\n\
         drive.ribs.amplitude      {:.4}\n\
         drive.diaphragm.amplitude {:.4}\n\
         drive.ribs.phase          {:+.4} rad\n\
         drive.diaphragm.phase     {:+.4} rad\n\
         delta phase (diaphragm - ribs) {:+.4} rad\n\
         registration          mean {:.2} mm, rms {:.2} mm, rotation {:.1} deg (the camera's turn \
         relative to the model's axes; about 180 deg for a camera facing the chest)\n\
         cost                  {:.3} mm (start {:.3} mm)\n\
         evaluations           {} ({}){}{}\n\
         wall time             {:.2} s\n\
         explained             {}\n\
         noise floor           {}{}",
        d.frequency,
        d.frequency * 60.0,
        d.ribs.amplitude,
        d.diaphragm.amplitude,
        d.ribs.phase,
        d.diaphragm.phase,
        fit.delta_phase,
        fit.registration_mean_m * 1e3,
        fit.registration_rms_m * 1e3,
        fit.to_model.rotation.angle().to_degrees(),
        fit.cost_m * 1e3,
        fit.initial_cost_m * 1e3,
        fit.evaluations,
        fit.method.name(),
        if fit.converged {
            ", search converged"
        } else {
            ", search stopped on its budget"
        },
        if fit.unused_ahead > 0 {
            format!(
                "; {} more evaluated ahead on a second thread and not used (the points the \
                 search was likely to need next, which it did not take; not counted)",
                fit.unused_ahead
            )
        } else {
            String::new()
        },
        fit.wall_s,
        explained,
        noise,
        notes
    )
}

/// The `marker_set` entry of a fit of a marker set other than the grid: the registration of
/// its first frame to the skin (similarity transform recording -> model, residuals), the
/// bound markers' bindings on the rest skin (`bindings`, which `torso fmu build --subject`
/// carries into a personalised FMU) and the markers left out; `recorded` is the number of
/// markers in the file.
pub fn marker_set_json(bound: &super::BoundRecording, recorded: usize) -> Value {
    let r = &bound.registration;
    let t = &r.to_model;
    let rot = t.rotation.to_rotation_matrix();
    let rows: Vec<Vec<f64>> = (0..3)
        .map(|i| (0..3).map(|j| rot[(i, j)]).collect())
        .collect();
    json!({
        "method": "principal-axes start (24 axis orderings), trimmed ICP (best 80 %) against the skin surface, Umeyama similarity",
        "pose": pose_json(&bound.orientation),
        "markers_recorded": recorded,
        "markers_bound": bound.set.len(),
        "labels_bound": bound.set.labels,
        "bindings": bound.set.bindings_json(),
        "transform": {
            "description": "recording frame -> model frame: p_model = scale R p_recording + t",
            "rotation_matrix": rows,
            "rotation_deg": t.rotation.angle().to_degrees(),
            "translation_m": [t.translation.x, t.translation.y, t.translation.z],
            "scale": t.scale,
        },
        "cost": "each marker's trajectory about its own mean over the recording (its constant offset from the skin point it is bound to left out)",
        "rms_m": r.rms,
        "trimmed_rms_m": r.trimmed_rms,
        "iterations": r.iterations,
        "excluded": bound.excluded.iter().map(|(l, d)| json!({
            "label": l,
            "distance_m": if d.is_finite() { json!(d) } else { Value::Null },
            "reason": if d.is_finite() { "farther than 3 cm from the registered skin" } else { "not tracked in the first frame" },
        })).collect::<Vec<_>>(),
    })
}

/// How the pose of a marker set was chosen: every candidate pose with its registration
/// score, the share of its inspiratory motion pointing forwards, its short-fit residual
/// and its rotation from the chosen one.
pub fn pose_json(o: &super::Orientation) -> Value {
    json!({
        "method": "distinct poses within the registration score margin; those whose inspiratory motion (signed outward) points forwards, or that put the --anterior markers on the front; the smallest residual of the linearised fit",
        "chosen": o.chosen,
        "frequency_hz": o.frequency_hz,
        "candidates": o.candidates.iter().map(|c| json!({
            "registration_score_m2": c.registration.score,
            "registration_rms_m": c.registration.rms,
            "markers_bound": c.registration.attached.len(),
            "front_share": c.front,
            "anterior_markers_in_front": c.anterior_ok,
            "short_fit_rms_m": c.short_fit.rms_m(),
            "short_fit_unexplained": c.short_fit.unexplained(),
            "rotation_from_chosen_deg": c.from_chosen_deg,
        })).collect::<Vec<_>>(),
        "warnings": o.warnings,
    })
}

/// A few lines on the registration of a marker set (see [`marker_set_json`]).
pub fn marker_set_summary(bound: &super::BoundRecording, recorded: usize) -> String {
    let r = &bound.registration;
    let mut s = format!(
        "marker set            {} of {} markers bound to the skin; registration rms {:.2} mm, scale {:.4}, rotation {:.1} deg",
        bound.set.len(),
        recorded,
        r.rms * 1e3,
        r.to_model.scale,
        r.to_model.rotation.angle().to_degrees()
    );
    let o = &bound.orientation;
    let c = &o.candidates[o.chosen];
    s.push_str(&format!(
        "\npose                  chosen of {} candidate poses by the breathing motion: front share {:+.2}, short-fit residual {:.2} mm ({:.0} % of the motion unexplained)",
        o.candidates.len(),
        c.front,
        c.short_fit.rms_m() * 1e3,
        100.0 * c.short_fit.unexplained()
    ));
    for (l, d) in &bound.excluded {
        if d.is_finite() {
            s.push_str(&format!(
                "\nleft out              {l}: {:.1} mm from the skin",
                d * 1e3
            ));
        } else {
            s.push_str(&format!(
                "\nleft out              {l}: not tracked in the first frame"
            ));
        }
    }
    s
}
