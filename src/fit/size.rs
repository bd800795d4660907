//! The subject's size from a recording's first frame. A fit of another person with the
//! default subject's torso carries the size difference into every figure it reports: the
//! same chest-wall motion on a larger trunk displaces more volume (a recording of a man 8 %
//! taller and heavier than the model, fitted at level of detail 1 with each marker compared
//! about its own mean, gave tidal volumes 11-13 % low with the default subject and 0-6 % low
//! with his own; CHANGELOG.md, issue 19's fitting entry). When stature and mass are not
//! known, they are searched here: a bounded Nelder-Mead over the stature and mass factors
//! (sex, age, breast size and posture held) minimises the rigid registration residual of the
//! first frame to the model's rest markers (the grid: correspondence, Kabsch) or rest skin
//! (any other marker set: trimmed ICP without scale,
//! [`crate::anatomy::skin::register_to_surface`]). The model's trunk shape follows stature
//! and mass (its girths grow with body mass index), so the residual separates a taller
//! subject from a heavier one; a uniform scale of the registration would not.

use super::{MarkerSource, TorsoMarkers};
use crate::anatomy::Subject;
use crate::anatomy::skin::{
    RigidTransform, Skin, SkinOptions, SurfaceOptions, register_rigid, register_to_surface,
};
use crate::numeric::optimize::{Bounds, NelderMeadOptions, nelder_mead};
use crate::{Config, Error, Result};
use nalgebra::Point3;

/// Settings of [`estimate_size`].
#[derive(Clone, Debug, PartialEq)]
pub struct SizeOptions {
    /// Range of the stature factor searched (relative to the configuration's subject).
    pub stature_factor: (f64, f64),
    /// Range of the mass factor searched.
    pub mass_factor: (f64, f64),
    /// Largest number of model builds (one registration each).
    pub max_evals: usize,
}

impl Default for SizeOptions {
    fn default() -> Self {
        SizeOptions {
            // +-15 % of stature and -30/+40 % of mass span the adult range around a guess
            // within one category (short/tall, lean/heavy) of the person.
            stature_factor: (0.85, 1.15),
            mass_factor: (0.7, 1.4),
            max_evals: 40,
        }
    }
}

/// What the search found.
#[derive(Clone, Debug, PartialEq)]
pub struct SizeEstimate {
    /// The configuration's subject with the estimated stature and mass.
    pub subject: Subject,
    /// Registration residual of the first frame with the estimated subject [m] (root mean
    /// square over the markers; the named sets' trimmed value).
    pub rms_m: f64,
    /// The same residual with the configuration's subject [m].
    pub start_rms_m: f64,
    /// Model builds (registrations) the search made.
    pub evaluations: usize,
}

/// Residual of a subject whose build fails its own checks (outside the allowed body-mass
/// index, say): larger than any registration residual of a trunk.
const INVALID_SUBJECT_RMS: f64 = 1.0;

/// Registration residual [m] of `first` (the recording's first frame, any frame) to the
/// rest markers (`grid`: by correspondence, in the grid's order) or to the rest skin of the
/// torso `config` builds, and for the skin the registration found. `start`: a registration
/// of the same frame to a nearby skin to refine instead of scanning (the skin only).
pub fn registration_residual(
    config: &Config,
    first: &[Option<Point3<f64>>],
    grid: bool,
    surface: &SurfaceOptions,
    start: Option<RigidTransform>,
) -> Result<(f64, Option<RigidTransform>)> {
    if grid {
        // built at the rest pose ([`TorsoMarkers::new`]): no start equilibrium is solved
        let mut source = TorsoMarkers::new(config.clone())?;
        let rest = source.rest_markers()?;
        let (_, rms) = register_rigid(&rest, first, false)?;
        Ok((rms, None))
    } else {
        // The skin needs the anatomy only, not the compiled dynamics.
        config.validate()?;
        let anatomy = crate::anatomy::Anatomy::build_on(
            &config.subject,
            config.scene.level_of_detail,
            config.subject_mesh_dir.as_deref(),
        )?;
        let skin = Skin::for_anatomy(&anatomy, &SkinOptions::default())?;
        let options = SurfaceOptions {
            with_scale: false,
            start,
            ..surface.clone()
        };
        let r = register_to_surface(&skin.vertices, &skin.triangles, first, &options)?;
        Ok((r.trimmed_rms, Some(r.to_model)))
    }
}

/// Searches the stature and mass of `config`'s subject that best match the recording's first
/// frame `first` (see the module doc). `grid`: the frame is the model's grid in order;
/// otherwise any marker set, registered to the skin. The configuration's own subject is the
/// start; the result is never worse than it.
pub fn estimate_size(
    config: &Config,
    first: &[Option<Point3<f64>>],
    grid: bool,
    surface: &SurfaceOptions,
    options: &SizeOptions,
) -> Result<SizeEstimate> {
    let (s, m) = (options.stature_factor, options.mass_factor);
    if !(s.0 > 0.0 && s.0 <= 1.0 && s.1 >= 1.0 && m.0 > 0.0 && m.0 <= 1.0 && m.1 >= 1.0) {
        return Err(Error::invalid(
            "size search ranges",
            format!("stature {s:?}, mass {m:?}"),
            "factor ranges that contain 1",
        ));
    }
    if options.max_evals < 5 {
        return Err(Error::invalid(
            "size search evaluations",
            options.max_evals,
            "at least 5",
        ));
    }
    let base = config.subject.clone();
    let subject_of = |x: &[f64]| Subject {
        stature: base.stature * x[0],
        mass: base.mass * x[1],
        ..base.clone()
    };
    // The configuration's subject is registered first, with the full scan (or from
    // `surface.start`, a pose already chosen, [`crate::fit::orient`]); every other size
    // refines that registration (the same markers on a trunk a few per cent larger or
    // smaller), so the residual is a function of the size alone.
    let mut start: Option<RigidTransform> = surface.start;
    let mut objective = |x: &[f64]| -> Result<f64> {
        let subject = subject_of(x);
        if subject.validate().is_err() {
            return Ok(INVALID_SUBJECT_RMS);
        }
        let mut c = config.clone();
        c.subject = subject;
        let (rms, t) = registration_residual(&c, first, grid, surface, start)?;
        start = start.or(t);
        Ok(rms)
    };
    let bounds = Bounds::new(&[s, m])?;
    let nm = NelderMeadOptions {
        max_evals: options.max_evals,
        // A first simplex of a quarter of each range (about 7 % of stature, 17 % of mass),
        // stopping at 0.5 % of each range (0.15 % of stature, 0.35 % of mass).
        initial_step: 0.25,
        x_tol: 5e-3,
        f_tol: 1e-6,
        f_rel_tol: 0.0,
    };
    let min = nelder_mead(&mut objective, &[1.0, 1.0], &bounds, &nm, &mut |_, _| {})?;
    let (x, rms) = if min.f <= min.f_start {
        (min.x.clone(), min.f)
    } else {
        (vec![1.0, 1.0], min.f_start)
    };
    Ok(SizeEstimate {
        subject: subject_of(&x),
        rms_m: rms,
        start_rms_m: min.f_start,
        evaluations: min.evaluations,
    })
}
