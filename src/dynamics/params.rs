//! Physical constants of the model, with their sources. Stiffness and damping are physical
//! (N/m per element, Pa, N m/rad) rather than the thesis's unit gains, so that the default
//! activations produce physiological volumes. Each constant's doc comment gives where its
//! value comes from: a literature source, the measurement it was calibrated against (with the
//! commit that set it), or "set by hand; no source". How much each hand-set passive stiffness
//! changes the relaxed chest wall's compliance is measured by `cargo run --release --example
//! chest_wall_sensitivity` (docs/dynamics.md, "What sets the passive chest wall").

use crate::anatomy::Posture;
use serde::{Deserialize, Serialize};

/// Largest contraction of the diaphragm's fibres from their standing rest length: they can
/// shorten by 30-40 % (seed thesis 2.3, after Hamid, Shannon & Martin 2006, Physiologic Basis
/// of Respiratory Disease, BC Decker); the model takes the upper end, set in the calibration
/// commit aeb7bbe against the tidal volumes and diaphragm excursions of `tests/physiology.rs`.
/// Source: seed thesis 2.3 after Hamid, Shannon & Martin 2006: the diaphragm shortens by
/// 30-40 %; ours 0.4, the upper end (agrees).
pub const DIAPHRAGM_CONTRACTION_UPRIGHT: f64 = 0.4;

/// Total rest length of the diaphragm's muscle fibres at end-expiration in `posture`, relative
/// to standing, in the generated anatomy. Lying supine, the abdominal contents are no longer
/// pulled caudally by gravity and push the relaxed dome cranially (a higher dome, a lower FRC:
/// `anatomy::abdomen`'s apex rise), so the fibres start longer, with a larger zone of
/// apposition; sitting, the dome sits slightly higher than standing. Measured on the generated
/// anatomy by `cargo run --release --example posture_breathing -- --lengths`: supine
/// x1.138-1.160, sitting x1.022-1.026 over three subjects (1.63-1.95 m) and the three levels of
/// detail; the values here are the default subject's at level of detail 1 (a test checks them
/// against the geometry).
/// Derived: measured on the model's own generated anatomy (command above), which
/// [`crate::anatomy`]'s calibrated apex rise sets; not a physiological measurement.
pub fn diaphragm_length_ratio(posture: Posture) -> f64 {
    match posture {
        Posture::Standing => 1.0,
        Posture::Sitting => 1.024,
        Posture::Supine => 1.145,
    }
}

/// Largest contraction of the diaphragm in `posture` as a fraction of that posture's rest
/// length. The fully contracted diaphragm is flattened against the abdominal contents at TLC
/// whatever the posture, so its fibres reach the same shortest length, (1 - beta_up) l_up;
/// starting from a longer rest length l = rho l_up (rho: [`diaphragm_length_ratio`]) they can
/// shorten by the fraction beta = 1 - (1 - beta_up) / rho. This is how the supine diaphragm's
/// better length-tension position (longer fibres at FRC) gives a stronger descent for the same
/// activation, which makes supine quiet breathing abdominal (Sharp 1975, via the seed thesis;
/// optoelectronic plethysmography supine, Aliverti et al. 2001: abdomen 63 +- 11 % of tidal
/// volume).
pub fn diaphragm_contraction(posture: Posture) -> f64 {
    match posture {
        Posture::Standing => DIAPHRAGM_CONTRACTION_UPRIGHT,
        _ => 1.0 - (1.0 - DIAPHRAGM_CONTRACTION_UPRIGHT) / diaphragm_length_ratio(posture),
    }
}

/// Compliances of the rib cage and of the diaphragm-abdomen compartment, seated then supine
/// [L/cmH2O], in 52 relaxed healthy adults (Estenne, Yernault & De Troyer 1985, J Appl
/// Physiol 59:1842, from the relaxation lines of magnetometer pairs): rib cage 0.141 +- 0.043
/// seated, 0.088 +- 0.038 supine; diaphragm-abdomen 0.025 +- 0.012 seated, 0.070 +- 0.025
/// supine; the whole chest wall's compliance did not change. Lying down thus stiffens the rib
/// cage (x1.60), which the model applies to the rib joints' stiffness, and softens the abdomen
/// (x2.8; see [`SUPINE_WALL_COMPLIANCE`]).
/// Source: Estenne, Yernault & De Troyer 1985, J Appl Physiol 59:1842, the four means above
/// (agrees: copied).
pub const SEATED_SUPINE_COMPLIANCES: [[f64; 2]; 2] = [[0.141, 0.088], [0.025, 0.070]];

/// Abdominal wall compliance sitting relative to standing: a small factor of the model, not a
/// measured ratio (the seed thesis 2.3 only orders the postures: supine is more compliant than
/// seated); sitting is the reference posture of [`SEATED_SUPINE_COMPLIANCES`]. Set by hand;
/// no source: the value of the first dynamics (commit cfbd824), unchanged since.
/// Unsourced: no source: chosen for a small sitting/standing difference. No measured
/// sitting-to-standing ratio of the abdominal wall's compliance was found: the relaxation
/// characteristics of six subjects (Konno & Mead 1968, J Appl Physiol 24:544) put the abdomen
/// nearly as compliant as the rib cage over the tidal range standing and somewhat more supine,
/// with no figure for sitting against standing.
pub const SITTING_WALL_COMPLIANCE: f64 = 1.1;

/// Abdominal wall compliance supine relative to standing (x1.64 from sitting), for a wall whose
/// membrane edges are linear (the thesis law's; the hill law's tension-only wall takes
/// [`TENSION_ONLY_SUPINE_WALL_COMPLIANCE`]). The measured
/// seated-to-supine ratio of the diaphragm-abdomen compliance is x2.8 (Estenne, Yernault & De
/// Troyer 1985, J Appl Physiol 59:1842: 0.025 +- 0.012 seated, 0.070 +- 0.025 L/cmH2O supine in
/// 52 relaxed adults; [`SEATED_SUPINE_COMPLIANCES`]), which would make this factor 3.08
/// ([`SITTING_WALL_COMPLIANCE`] x 2.8). Commit a69b5a9 found forced supine breathing stalled
/// with it; under the thesis's law it now runs (`cargo run --release --example
/// posture_breathing -- --probe 1 1.711`: 15 s, 953 steps), and it moves the supine quiet
/// breath little (level 1: tidal volume 0.610 -> 0.617 L, abdominal share 61.3 -> 62.2 %,
/// respiratory-system compliance 0.0694 -> 0.0753 L/cmH2O). But under the passive-and-active
/// law with its cited maximal forces the relaxed supine chest wall then has no equilibrium
/// 0.15 L above FRC (the path folds at 3.027 L; `cargo test --release --test muscle_law
/// the_relaxed_recoil_rises_with_volume` with this constant set to 3.08), so the model keeps
/// the 1.8 of its first dynamics
/// (commit cfbd824), set by hand, not fitted. That fold was the abdominal wall's wrinkling:
/// with its edges tension only (the hill law's, [`abdominal_wall_tension_only`]) x3.08 spans
/// RV to TLC supine (C_cw 0.1494 L/cmH2O, supine abdominal share of quiet breathing 72.5 %;
/// `torso bench relaxation --muscle-law hill --posture supine` and `torso bench physiology
/// --muscle-law hill`), which [`TENSION_ONLY_SUPINE_WALL_COMPLIANCE`] now gives that law. It
/// stays 1.8 for the thesis law's linear-edged wall, which wrinkles with 3.08 (level 0's
/// relaxed supine curve stops at 2.424 L instead of reaching 1.677 L), and whose figures were
/// measured with 1.8. Peritoneal dialysis fills
/// raise the abdominal pressure by 3.1 mmHg supine and 4.5 mmHg erect for the same fill in
/// 25 patients (Al-Hwiesh et al. 2011, "Intraperitoneal pressure and intra-abdominal
/// pressure: are they the same?", abstract; the fill volume not read): x1.45 from erect to
/// supine, between ours and Estenne et al.'s. Konno & Mead 1968 (J Appl Physiol 24:544) found
/// the abdomen over the tidal range nearly as compliant as the rib cage standing and somewhat
/// more compliant supine (the same direction, no ratio).
/// Unsourced: no source: chosen by hand, kept for the thesis law's measured figures. Literature: x2.8 from
/// seated to supine (Estenne et al. 1985); ours x1.64 from sitting (1.8 / 1.1): disagrees.
pub const SUPINE_WALL_COMPLIANCE: f64 = 1.8;

/// Abdominal wall compliance supine relative to standing when the wall's membrane edges carry
/// tension only ([`Params::abdominal_wall_tension_only`], the passive-and-active law's): the
/// hand-set sitting factor [`SITTING_WALL_COMPLIANCE`] times Estenne et al.'s measured
/// seated-to-supine ratio of the diaphragm-abdomen compartment's compliance, x2.8
/// ([`SEATED_SUPINE_COMPLIANCES`]), so 3.08. The ratio is the compartment's, applied to the
/// wall's foundation (not the same quantity, [`Params::abdominal_wall_compliance`]). Such a
/// wall does not wrinkle when the supine relaxed chest wall is deflated or inflated (hill law, level 1, against [`SUPINE_WALL_COMPLIANCE`]'s 1.8: relaxed supine
/// C_cw 0.1453 -> 0.1494 L/cmH2O, C_rs 0.083 -> 0.084, abdominal share of quiet breathing 71.3
/// -> 72.5 %, quiet tidal volume 0.369 -> 0.374 L; `torso bench relaxation --muscle-law hill
/// --posture supine`, `torso bench physiology --muscle-law hill`). The thesis law's wall, its
/// edges linear, keeps 1.8: with 3.08 its relaxed supine curve at level 0 stops at 2.424 L
/// (the wall wrinkling) where with 1.8 it reaches 1.677 L. Giving the thesis law's wall
/// tension-only edges too was tried and not kept: its relaxed curves then span RV to TLC, but
/// its quasi-static quiet breathing at level 2 buckles at the end of the first expiration
/// (3.24 s, `torso simulate --lod 2 --solver quasi-static` with
/// [`Params::abdominal_wall_tension_only`] set in the configuration's params; the least stable
/// mode of the stiffness there lies on the dome's slack top).
/// Derived: [`SITTING_WALL_COMPLIANCE`] x [`SEATED_SUPINE_COMPLIANCES`]'s diaphragm-abdomen
/// ratio, supine over seated (Estenne et al. 1985).
pub const TENSION_ONLY_SUPINE_WALL_COMPLIANCE: f64 =
    SITTING_WALL_COMPLIANCE * SEATED_SUPINE_COMPLIANCES[1][1] / SEATED_SUPINE_COMPLIANCES[1][0];

/// Default [`Params::pleural_barrier_pressure`]: 0.5 cmH2O [Pa]. Small enough that the
/// lungs stay within 5 % of linear over a forced breath (1 L below rest, the barrier adds
/// 0.1 cmH2O to 5 cmH2O of recoil for the default subject), large enough that the recoil
/// passes 30 cmH2O a few percent of the way from the residual volume to rest.
/// Numerical: a shape parameter of the barrier that keeps the lungs' volume between RV and
/// TLC; chosen by the two measured criteria above, not a tissue property.
pub const PLEURAL_BARRIER_PRESSURE: f64 = 0.5 * 98.0665;

/// Default [`Params::pleural_barrier_margin`]: the tangent takes over 1 % of the way from
/// each asymptote to rest, where the barrier alone is about 48 cmH2O (beyond any quiet or
/// forced breath). With 2 % the strongest soak scene (seed 2011, scene 35) was squeezed 6 %
/// below its residual volume along the tangent; with 1 % it stops at it.
/// Numerical: where the barrier is continued by its tangent; chosen by the soak scene above.
pub const PLEURAL_BARRIER_MARGIN: f64 = 0.01;

/// Default [`Params::inertia_frequency`] [Hz]: ten times the fastest breathing the drive
/// supports (2 Hz, `model::drive::FREQUENCY_RANGE`) and a little more, so that inertia changes
/// the response to any drive by well under 1 % (the inertial force relative to the elastic one
/// goes as (f / f_inertia)^2: (2 / 25)^2 = 0.6 % at the fastest drive, 1e-4 at quiet breathing).
/// Numerical: selective mass scaling's target frequency, chosen by the criterion above
/// (inertia under 1 % of the elastic force at the fastest drive).
pub const INERTIA_FREQUENCY: f64 = 25.0;

/// Default [`Params::specific_airway_conductance`] [1/(Pa s)]: 0.2 /(cmH2O s). Airway
/// conductance grows in proportion to lung volume, so that its ratio to the volume, the
/// specific conductance, is nearly constant between subjects (Briscoe & DuBois 1958, J Clin
/// Invest 37:1279: sGaw about 0.13-0.35 /(cmH2O s) in healthy adults). At the default man's
/// functional residual capacity (3.3 L, ECSC 1993) it gives an airway resistance of
/// 1.5 cmH2O s/L, inside the 0.5-2.5 cmH2O s/L of healthy adults (West, Respiratory
/// Physiology).
/// Source: Briscoe & DuBois 1958, J Clin Invest 37:1279: sGaw about 0.13-0.35 /(cmH2O s);
/// ours 0.2 (agrees).
pub const SPECIFIC_AIRWAY_CONDUCTANCE: f64 = 0.2 / 98.0665;

/// Default [`Params::lung_recoil_at_frc`] [Pa]: 5 cmH2O. At the functional residual capacity,
/// with no flow, the pleural pressure is minus the lungs' elastic recoil, about -5 cmH2O in
/// upright adults (oesophageal balloon; Milic-Emili et al. 1964, J Appl Physiol 19:207;
/// Agostoni & Hyatt 1986, Handbook of Physiology, The Respiratory System III, ch. 9).
/// Source: Milic-Emili et al. 1964, J Appl Physiol 19:207: pleural pressure about -5 cmH2O
/// at FRC upright; ours 5 cmH2O recoil (agrees).
pub const LUNG_RECOIL_AT_FRC: f64 = 5.0 * 98.0665;

/// Default [`Params::tension_toe`] [N]: the width of the smooth toe of the tension-only law.
/// 0.1 N is about 1 % of the smallest muscle element's tension in quiet breathing and a few
/// thousandths of its largest; it is measured, not cited: halving it changes the default
/// subject's quiet tidal volume by under 0.1 % (`cargo run --release --example
/// fast_dynamics -- toe`). Under gravity acting with the hill law it is not only numerical:
/// the tissues carrying the reference loads sit near their slack, and halved the standing
/// relaxed curve finds no equilibrium 0.19 L above or 0.04 L below FRC (3.686 and 3.456 L),
/// the supine one none above 3.984 L; at 0.3 and 1 N the standing curve reaches 6.455 L and
/// TLC where at 0.1 N it stops at 5.763 L, its compliance 0.149 and 0.137 against 0.172
/// L/cmH2O (`torso bench relaxation --muscle-law hill --gravity-loads acting` with the constant
/// changed).
/// Numerical: the smoothing width of the tension-only law, chosen by the measurement above.
pub const TENSION_TOE: f64 = 0.1;

/// Default [`Params::transverse_fraction`]: 0.1, the sin^2 of an 18 degree tilt. Each
/// two-point element's added inertia and damping act in its transverse directions with this
/// fraction of their axial values, so that an element that tilts by up to 18 degrees from its
/// rest direction as the cavities deform still finds as much inertia as the stiffness it
/// turns into the new direction. It is a numerical constant, chosen by measurement
/// (`cargo run --release --example fast_dynamics -- 1 1e-6 tilt=F`, docs/dynamics.md): at
/// level of detail 1, 0 leaves the step bound by the dome's central-tendon pole (29,090 RHS
/// evaluations per 1000 frames), 0.1 frees it; it changes the quiet tidal volume by under 1 %.
/// Numerical: chosen by the step-size measurement above.
pub const TRANSVERSE_FRACTION: f64 = 0.1;

/// Default [`Params::abdominal_wall_resistance`] [Pa s/m^3]: 1.0 cmH2O s/L. The whole
/// respiratory system's resistance at breathing frequencies is about 2-3 cmH2O s/L, airways and
/// tissue together, and the airways' about 0.5-2.5 (West, Respiratory Physiology); the default
/// man's airway resistance is 1.5 cmH2O s/L ([`SPECIFIC_AIRWAY_CONDUCTANCE`]), which leaves
/// 0.5-1.5 cmH2O s/L to the tissues, and the model gives the middle of that to the abdominal
/// wall (the rib cage's joints and the lungs' tissue carry their own damping).
/// Unsourced: no source gives the abdominal wall's own tissue resistance; 1.0 cmH2O s/L is
/// chosen inside the 0.5-1.5 cmH2O s/L left to the tissues by the cited totals above (West,
/// Respiratory Physiology: respiratory system 2-3, airways 0.5-2.5 cmH2O s/L). The chest wall's
/// resistance, measured whole in anaesthetised paralysed supine adults, is entirely
/// viscoelastic (D'Angelo et al. 1991, J Appl Physiol 70:2602); the respiratory system's
/// viscoelastic resistance there is 3.7 +- 0.7 cmH2O s/L (Jonson et al., "Mechanics of
/// respiratory system in healthy anesthetized humans with emphasis on viscoelastic
/// properties"): neither separates the abdominal wall. Literature, for the whole relaxed
/// chest wall at breathing frequencies: in five healthy subjects during voluntary apnea the
/// respiratory system's resistance fell from 0.47 +- 0.06 kPa s/L (4.8 cmH2O s/L) at 0.25 Hz
/// to 0.17 +- 0.01 at 1 Hz, the fall due almost only to the chest wall's resistance (Hantos et
/// al. 1986, J Appl Physiol 60:123, PMID 2935519), so the relaxed chest wall's resistance at
/// quiet breathing's 0.25 Hz exceeds its 1 Hz value by about 3 cmH2O s/L; six relaxed seated
/// subjects forced at 0.2-0.6 Hz had a respiratory system resistance of 3.07-4.43 cmH2O s/L
/// ("Dependencies of respiratory system resistance and elastance on amplitude and frequency in
/// the normal range of breathing", Am Rev Respir Dis 1991, 143:240,
/// doi:10.1164/ajrccm/143.2.240), which leaves 1.6-2.9 cmH2O s/L to the tissues beside the
/// default man's 1.5 of airway. Ours, 1.0 cmH2O s/L for the abdominal wall alone and
/// independent of frequency, is not the same quantity as either: no comparison.
pub const ABDOMINAL_WALL_RESISTANCE: f64 = 1.0 * 98.0665e3;

/// Default [`Params::gravity`] [m/s^2]: standard gravity, 9.80665 m/s^2 (3rd CGPM, 1901),
/// rounded.
/// Source: standard gravity 9.80665 m/s^2 (3rd CGPM, 1901); ours 9.81 (agrees).
pub const GRAVITY: f64 = 9.81;

/// Largest gravitational acceleration the model accepts ([`Params::gravity`], FMI `gravity`)
/// [m/s^2]: three times [`GRAVITY`], a few g, the order of sustained accelerations in human
/// centrifuge studies, far beyond any posture on the ground. Nothing in the model is checked
/// above it.
/// Numerical: the upper end of the accepted input range, not a property of the body.
pub const GRAVITY_MAX: f64 = 3.0 * GRAVITY;

/// Density of the abdominal contents as a fluid [kg/m^3], for their hydrostatic pressure
/// gradient rho g under [`GravityLoads::Acting`]. Pressures measured next to the ventral
/// abdominal wall (saline-filled catheters, anaesthetised dogs in several postures) rise
/// with depth by about 0.89 cmH2O per cm of height (Loring et al. 1994, J Appl Physiol
/// 77:1375), a fluid of 0.89 times water's density (water's gradient is 1 cmH2O/cm): the
/// contents are mostly water-like tissue with some gas (100-300 mL, seed thesis 2.3).
/// Source: Loring et al. 1994, J Appl Physiol 77:1375: a gravitational gradient of about
/// 0.89 cmH2O/cm next to the abdominal wall; ours 890 kg/m^3 x g = 0.89 cmH2O/cm at
/// standard gravity (agrees: copied).
pub const ABDOMINAL_CONTENTS_DENSITY: f64 = 890.0;

/// How gravity loads the model ([`Params::gravity_loads`]).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum GravityLoads {
    /// Each posture's generated anatomy is its rest: gravity acts on the true masses (the
    /// abdominal contents lumped on the free vertices of their surface), and constant
    /// preloads computed on that posture's rest cancel every load there, so the posture
    /// effects come from the posture tables (the dome's apex rise, the wall's compliance
    /// factors, the diaphragm's length ratio). The default.
    #[default]
    Preloaded,
    /// Gravity acts: the abdominal contents are a fluid of density
    /// [`ABDOMINAL_CONTENTS_DENSITY`] whose hydrostatic pressure rho g . (x - x_c) acts on
    /// the cavity's surfaces on top of its mean pressure (their weight, no longer lumped on
    /// the vertices); the tissues' rest tensions are derived once, on the standing anatomy
    /// under standard gravity; every posture is that anatomy with gravity turned, and its
    /// rest is the equilibrium under the loads.
    Acting,
}

impl GravityLoads {
    /// Both, by code (FMI `gravity_loads`: 0 preloaded, 1 acting).
    pub const ALL: [GravityLoads; 2] = [GravityLoads::Preloaded, GravityLoads::Acting];

    /// The code (FMI `gravity_loads`).
    pub fn code(self) -> i32 {
        match self {
            GravityLoads::Preloaded => 0,
            GravityLoads::Acting => 1,
        }
    }

    /// The variant of code `code`; the error names `gravity_loads` and the codes.
    pub fn from_code(code: i64) -> crate::Result<GravityLoads> {
        usize::try_from(code)
            .ok()
            .and_then(|c| GravityLoads::ALL.get(c).copied())
            .ok_or_else(|| crate::Error::invalid("gravity_loads", code, "0 preloaded or 1 acting"))
    }

    /// The variant named `name` (`preloaded` or `acting`).
    pub fn parse(name: &str) -> crate::Result<GravityLoads> {
        match name {
            "preloaded" => Ok(GravityLoads::Preloaded),
            "acting" => Ok(GravityLoads::Acting),
            other => Err(crate::Error::invalid(
                "gravity_loads",
                other,
                "preloaded or acting",
            )),
        }
    }
}

fn default_abdominal_wall_resistance() -> f64 {
    ABDOMINAL_WALL_RESISTANCE
}

fn default_transverse_fraction() -> f64 {
    TRANSVERSE_FRACTION
}

fn default_inertia_frequency() -> f64 {
    INERTIA_FREQUENCY
}

fn default_specific_airway_conductance() -> f64 {
    SPECIFIC_AIRWAY_CONDUCTANCE
}

fn default_lung_recoil_at_frc() -> f64 {
    LUNG_RECOIL_AT_FRC
}

fn default_tension_toe() -> f64 {
    TENSION_TOE
}

fn default_pleural_barrier_pressure() -> f64 {
    PLEURAL_BARRIER_PRESSURE
}

fn default_pleural_barrier_margin() -> f64 {
    PLEURAL_BARRIER_MARGIN
}

/// Constants of the dynamics. `Params::for_posture` gives the defaults.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Params {
    /// Largest contraction of a muscle element's rest length at full activation and unit
    /// gain: r = 1 - beta_max a g >= 0.7 (thesis 2.4 after Klute et al.: r in [0.7, 1.2]).
    /// The default 0.3 is the contraction to that lower bound, 1 - 0.7 (Klute, Czerniecki &
    /// Hannaford 2002, Int J Robot Res 21:295, the artificial-muscle range the thesis adopts). It also sets
    /// the relaxed muscles' stiffness, F_max / (beta_max l0): doubling both betas raises the
    /// relaxed chest wall's compliance by 10 % at +5 cmH2O and 26 % at -5 cmH2O
    /// (docs/dynamics.md, "What sets the passive chest wall").
    /// Source: seed thesis 2.4 after Klute, Czerniecki & Hannaford 2002: r in [0.7, 1.2], so
    /// beta_max = 1 - 0.7 = 0.3 (agrees: the bound itself).
    pub beta_max: f64,
    /// The same for the diaphragm, which can shorten by 30-40 % from its upright rest length
    /// (seed thesis 2.3, after Hamid et al. 2006; [`DIAPHRAGM_CONTRACTION_UPRIGHT`]): r >= 0.6
    /// standing. In the other postures the fibres start longer and reach the same shortest
    /// length (see [`diaphragm_length_ratio`]), so their fraction is larger.
    /// Derived: [`diaphragm_contraction`] of [`DIAPHRAGM_CONTRACTION_UPRIGHT`] and
    /// [`diaphragm_length_ratio`].
    pub beta_max_diaphragm: f64,
    /// Damping ratio zeta of the model's inertial modes at the inertia frequency
    /// ([`Params::inertia_frequency`]): every spring-damper element, vector spring and rib
    /// joint has the damping coefficient beta k of its stiffness k, beta = 2 zeta /
    /// (2 pi f_inertia) (stiffness-proportional damping, Rayleigh; thesis 2.4 asks for
    /// critically damped elements, zeta = 1). The default 1 is that aim; the thesis set its
    /// gains empirically, to avoid oscillation when elements are activated (section 2.4). It
    /// is a numerical choice, not a tissue measurement.
    /// Numerical: critical damping of the scaled inertial modes (thesis 2.4's aim), a solver
    /// choice.
    pub damping_ratio: f64,
    /// Inertia frequency f_i [Hz]: the masses and inertias of the ribs, the sternum and the
    /// cavity vertices gain the local stiffness over (pi f_i)^2 (selective mass scaling,
    /// `dynamics::inertia`), so that the modes that stretch stiff elements lie between
    /// f_i / 2 and about f_i, and the stiffness-proportional damping is tuned to f_i. Breathing is quasi-static: the
    /// respiratory system's inertance (0.01-0.02 cmH2O s^2/L, Mead 1956) makes its inertial
    /// pressure about 0.3 % of the elastic recoil at 0.25 Hz, so the bodies' true masses only
    /// set vibration modes (80-130 Hz for single ribs and dome vertices) that breathing never
    /// excites but that would bound an explicit solver's step. Configurations written before
    /// it existed read [`INERTIA_FREQUENCY`].
    /// Derived: default [`INERTIA_FREQUENCY`].
    #[serde(default = "default_inertia_frequency")]
    pub inertia_frequency: f64,
    /// The true masses: no selective mass scaling, so the mass matrix holds the bodies' and
    /// vertices' own masses and inertias and the airways' gas inertance only (the damping
    /// keeps its coefficients, tuned to [`Params::inertia_frequency`]). For validating the
    /// quasi-static mode against the inertial formulation (docs/dynamics.md, "Quasi-static
    /// mechanics"), not for running: an explicit step then shrinks to the true vibration
    /// modes (80-130 Hz and above). Off by default.
    #[serde(default)]
    pub true_masses: bool,
    /// Specific airway conductance [1/(Pa s)]: the airway resistance between the alveoli and
    /// the mouth is 1 / (sGaw FRC) for the subject's functional residual capacity, and the
    /// pleural pressure carries the pressure drop R dV/dt of the flow through it.
    /// Configurations written before it existed read [`SPECIFIC_AIRWAY_CONDUCTANCE`].
    /// Derived: default [`SPECIFIC_AIRWAY_CONDUCTANCE`].
    #[serde(default = "default_specific_airway_conductance")]
    pub specific_airway_conductance: f64,
    /// Width [N] of the smooth toe of the tension-only law of the muscles: the tension is
    /// eps ln(1 + exp(f / eps)) of the linear spring-damper force f (softplus), so that it is
    /// smooth where a muscle goes slack. Configurations written before it existed read
    /// [`TENSION_TOE`].
    /// Derived: default [`TENSION_TOE`].
    #[serde(default = "default_tension_toe")]
    pub tension_toe: f64,
    /// Fraction of each two-point element's added inertia and damping given to its
    /// transverse directions (`dynamics::inertia`; [`TRANSVERSE_FRACTION`]): the element
    /// damps the relative velocity of its ends across it with this fraction of its axial
    /// damping coefficient, and its ends' mass blocks carry the same fraction of its
    /// stiffness over omega_b^2 across it. Configurations written before it existed read
    /// [`TRANSVERSE_FRACTION`].
    /// Derived: default [`TRANSVERSE_FRACTION`].
    #[serde(default = "default_transverse_fraction")]
    pub transverse_fraction: f64,
    /// Bulk modulus K of the abdominal contents [Pa] (thesis eq. 2.5: P = K (V0/V - 1)).
    /// Default 3e5 Pa, calibrated, not measured: raised from 1e5 in the calibration commit
    /// aeb7bbe against the checks of `tests/physiology.rs` it added (the quiet breath moves
    /// the abdominal volume by under 1 %, with tidal volumes and diaphragm excursions in
    /// range). The thesis's own value, 0.3 "satisfactory" (section 2.4.2), is in its animation
    /// package's units and does not carry over. For scale: 3e5 Pa is the compressibility of
    /// 4.4 L of gas at 1 atm in the default man's 13.0 L abdominal cavity, where the abdomen
    /// holds 100-300 mL (thesis 2.3), so the model's contents are far softer than real ones
    /// (`cargo run --release --example chest_wall_sensitivity` prints both figures); halving
    /// it moves the relaxed chest wall's compliance by 0-2 %.
    /// Calibrated: set by hand in commit aeb7bbe against `tests/physiology.rs`; no command
    /// reproduces a fit. Literature: contents holding 100-300 mL of gas (thesis 2.3) in the 13.0 L
    /// cavity, compressed isothermally at 1 atm, have K = 101.3 kPa x 13.0 / (0.1-0.3) =
    /// 4.4e6-1.3e7 Pa; abdominal CT of 37 healthy adults found a median 95 mL of gut gas, IQR
    /// 71-141 mL (Bendezú et al. 2015, "Intestinal gas content and distribution in health and in
    /// patients with functional gut symptoms", Neurogastroenterol Motil 27(9)), K = 1.39e7 Pa
    /// (IQR 9.3e6-1.86e7 Pa). Ours, 3e5 Pa, is 15-46x softer: disagrees. It cannot be adopted
    /// yet: with 1.4e7, 9.3e6 or 4.4e6 Pa the hill law's upright rest under gravity acting at
    /// level 1 cannot be followed to 0.1 L above its FRC (the static equilibrium stops 81-87 %
    /// of the way; `cargo test --release --test gravity upright_rest_is_stable_under_gravity_acting
    /// -- --nocapture`, which passes at 3e5), and the hill law's frame loop costs 2-3x the
    /// right-hand sides (1000 frames of quiet breathing at level 1: 9410 -> 19280; level 0: 5534
    /// -> 17498; `torso bench core --muscle-law hill`); the thesis law's is unchanged (4082).
    pub bulk_modulus: f64,
    /// Lung elastance [Pa/m^3]: pleural pressure change per volume change of the lungs (the
    /// thorax's, one to one), 1 / (0.2 L/cmH2O) (lung compliance, physiology reference). The
    /// default 1 / (2.0e-6 m^3/Pa) is 1 / (0.196 L/cmH2O), which `cargo run --release
    /// --example relaxation` measures back as C_L = 0.195-0.196 L/cmH2O.
    /// Source: lung compliance about 0.2 L/cmH2O in adults (West, Respiratory Physiology: The
    /// Essentials); ours 0.196 L/cmH2O (agrees).
    pub lung_elastance: f64,
    /// The lungs' elastic recoil at rest, the functional residual capacity [Pa]
    /// ([`LUNG_RECOIL_AT_FRC`]): the pleural pressure read out is minus it at rest. The
    /// dynamics work with changes from rest (the chest wall's rest forces balance it), so it
    /// sets only the absolute pleural pressure. Configurations written before it existed
    /// read [`LUNG_RECOIL_AT_FRC`].
    /// Derived: default [`LUNG_RECOIL_AT_FRC`].
    #[serde(default = "default_lung_recoil_at_frc")]
    pub lung_recoil_at_frc: f64,
    /// Barrier pressure p_b [Pa] of the pleural pressure-volume law
    /// ([`super::pleural::PleuralLaw`]): the recoil added near the residual volume (and the
    /// total lung capacity) is about p_b x0 / x at a distance x from it (x0 from rest). > 0;
    /// configurations written before it existed read [`PLEURAL_BARRIER_PRESSURE`].
    /// Derived: default [`PLEURAL_BARRIER_PRESSURE`].
    #[serde(default = "default_pleural_barrier_pressure")]
    pub pleural_barrier_pressure: f64,
    /// Margin of the pleural pressure-volume law's barriers, as a fraction of the distance
    /// from the rest volume to each asymptote (residual volume below, total lung capacity
    /// above): within it the law follows its tangent (see [`super::pleural::PleuralLaw`]), so
    /// that it is finite for every volume an overshooting solver stage may probe. In (0, 0.5);
    /// configurations written before it existed read [`PLEURAL_BARRIER_MARGIN`].
    /// Derived: default [`PLEURAL_BARRIER_MARGIN`].
    #[serde(default = "default_pleural_barrier_margin")]
    pub pleural_barrier_margin: f64,
    /// Stiffness of a cartilage ball joint [N/m]: the zero-length spring that joins the end
    /// of a costal cartilage to the sternum (ribs 1-7) or to the cartilage above (ribs
    /// 8-10). Default 1e4 N/m, set by hand; no source: lowered from 3e4 in the first
    /// calibration (commit 16087cb, whose message names no target). With the rib joints and
    /// the relaxed muscles it makes the rib cage's passive stiffness. The model's relaxed
    /// chest wall is 0.050 L/cmH2O at -5 cmH2O and 0.086 at +5 against about 0.2 in adults;
    /// halving this constant raises it by 13 % and 3 % (docs/dynamics.md, "What sets the
    /// passive chest wall").
    /// Unsourced: no source: chosen by hand in commit 16087cb (see above). Literature gives the
    /// costal cartilage's material, not this joint: Young's modulus 32.9 +- 17.9 MPa in
    /// compression and 11-15 MPa in indentation (Weber, Rothschild & Niehoff 2021, Sci Rep,
    /// doi:10.1038/s41598-021-93176-x); no stiffness of the sternocostal junction was found.
    pub cartilage_stiffness: f64,
    /// Stiffness of the first rib's cartilage joint [N/m]; 0 (the default): the same as
    /// [`Params::cartilage_stiffness`]. The first costal cartilage meets the manubrium in a
    /// synchondrosis, a cartilaginous joint without a joint cavity, where the second to
    /// seventh meet the sternum in synovial joints (Gray's Anatomy, 41st ed., 2016, ch. 53,
    /// "sternocostal joints"), and the first rib moves with the manubrium. So under the
    /// passive-and-active law the compartments' factor on the cartilage
    /// ([`HILL_CARTILAGE_FACTOR`], fitted to the relaxed rib cage's compliance, a softness
    /// standing for the synovial joints' sliding and the cartilages' bending) leaves it at the
    /// passive wall's cartilage stiffness ([`Params::before_compartments`]).
    /// Derived: 0 by default; under the hill law `cartilage_stiffness` x
    /// [`HILL_PASSIVE_WALL_SCALE`], before the compartments' factor.
    #[serde(default)]
    pub first_cartilage_stiffness: f64,
    /// Rotational stiffness of a costovertebral joint with its share of chest-wall recoil
    /// [N m/rad]. Default 2 N m/rad upright, set by hand; no source: 20 in the first dynamics
    /// (commit cfbd824), lowered to 2 in the first calibration (commit 16087cb, whose message
    /// names no target). Supine it is multiplied by the measured fall of rib-cage compliance
    /// (x1.60, `SEATED_SUPINE_COMPLIANCES`). The model's relaxed chest wall is 0.050
    /// L/cmH2O at -5 cmH2O and 0.086 at +5 against about 0.2 in adults; halving this constant
    /// raises it by only 6 % and 2 % (docs/dynamics.md, "What sets the passive chest wall").
    /// Unsourced: no source: chosen by hand in commit 16087cb. Literature, for the isolated
    /// costovertebral articulation: +-0.1 N m turned it by a median 13.2 deg (6.4-20.9 deg; Lebschy
    /// et al. 2024, J Biomech 163:111923), a secant stiffness of 0.87 (0.55-1.8) N m/rad; ours, 2
    /// N m/rad, also carries a share of the chest wall's recoil, so it is not the same quantity.
    /// Under the hill law it is 0.88 N m/rad (x [`HILL_PASSIVE_WALL_SCALE`]), Lebschy et al.'s
    /// figure, but that secant spans only +-6.6 deg about neutral (the abstract; 2 bodies, 4
    /// rib levels): the law's rib 3 turns 13.6 deg in full inspiration, beyond the tested
    /// range. Costovertebral units load non-linearly, a low-stiffness zone then stiffer
    /// quasi-linear zones (Lemosse et al. 1998, Eur Spine J 7:16, 27 units from 9 cadavers;
    /// abstract, no numbers read): a joint that stiffens beyond the neutral zone is not
    /// modelled.
    pub rib_joint_stiffness: f64,
    /// In-plane stiffness of an abdominal membrane edge [N/m] (2D modulus about 1.15 k).
    /// Default 400 N/m, set by hand; no source (the value of the first dynamics, commit
    /// cfbd824): the in-plane tension of the abdominal wall's surface, in parallel with the
    /// wall's foundation ([`Params::abdominal_wall_compliance`]). Halving it raises the
    /// relaxed chest wall's compliance by 10 % at +5 cmH2O and 3 % at -5 cmH2O.
    /// Unsourced: no source: chosen by hand in commit cfbd824. Literature: at 20 kPa of abdominal
    /// pressure the wall near the linea alba carries 3.4 N/mm transversely and 1.5 N/mm
    /// longitudinally at about 6 % strain (Foerstemann et al. 2011, J Biomech), a secant 2D
    /// modulus of 25,000-57,000 N/m against ours, about 460 N/m: disagrees by two orders of
    /// magnitude at that load (breathing loads the wall far less, in its softer toe region, where
    /// no in-plane modulus was found).
    pub membrane_stiffness: f64,
    /// In-plane stiffness of a membrane edge of the diaphragm dome [N/m]: the dome's passive
    /// stiffness is low along its fibres, so that their shortening can lower it like a piston.
    /// Default 40 N/m (a tenth of the abdominal membrane's), set by hand; no source (first
    /// calibration, commit 16087cb). Halving it raises the relaxed chest wall's compliance by
    /// 2-3 %.
    /// Unsourced: no source: chosen by hand in commit 16087cb. Literature: the passive diaphragm
    /// is much stiffer across its fibres than along them (rat, "Shape and tension distribution
    /// of the passive rat diaphragm", PMID 11124131: along-fibre tension 6-10 g/cm at 15 cmH2O
    /// transdiaphragmatic pressure; Boriek & Rodarte 1997, J Appl Physiol 82:1626); no in-plane
    /// modulus to compare with ours (isotropic) was found.
    pub dome_membrane_stiffness: f64,
    /// In-plane stiffness of a membrane edge of the central tendon [N/m] (stiff: it carries the
    /// radial fibres' pull across the top of the dome). Default 2000 N/m (fifty times the
    /// muscular dome's), set by hand; no source (first calibration, commit 16087cb). Halving it
    /// lowers the relaxed chest wall's compliance by 3 % at +5 cmH2O and raises it by 2 % at
    /// -5 cmH2O.
    /// Unsourced: no source: chosen by hand in commit 16087cb. Literature: the central tendon is
    /// not stretched by physiological stresses (their earlier measurements, summarised by Boriek &
    /// Rodarte 1997, J Appl Physiol 82:1626) and is essentially inextensible along and across the fibres near the muscle (dog; Hwang,
    /// Kelly & Boriek, "Passive mechanics of muscle tendinous junction of canine diaphragm"):
    /// much stiffer than the muscle, as ours is (x50), but no modulus was found.
    pub tendon_stiffness: f64,
    /// Horizontal support of the diaphragm dome by the rib cage and lungs [N/m^3] (foundation
    /// stiffness per area of dome). Default 2e5 N/m^3, set by hand; no source (first
    /// calibration, commit 16087cb). Halving it raises the relaxed chest wall's compliance by
    /// 15 % at -5 cmH2O and 3 % at +5 cmH2O.
    /// Unsourced: no source: chosen by hand in commit 16087cb.
    pub dome_support: f64,
    /// Compliance of the abdominal wall [m^3/Pa] (elastic support of the wall by its muscles,
    /// fascia and skin), spread over the free wall vertices as a foundation stiffness.
    /// Default 2.0e-6 m^3/Pa standing (0.196 L/cmH2O; x1.1 sitting and x1.8 supine,
    /// `SITTING_WALL_COMPLIANCE`, `SUPINE_WALL_COMPLIANCE`; x3.08 supine under the hill law,
    /// `TENSION_ONLY_SUPINE_WALL_COMPLIANCE`), calibrated, not measured: raised from 1.5e-6 in
    /// the calibration commit aeb7bbe against the checks of `tests/physiology.rs` it added
    /// (tidal volumes, diaphragm excursion, rib-cage share). The only measured compliance of
    /// the abdomen in the sources, Estenne et al. 1985's diaphragm-abdomen compartment
    /// (0.025 L/cmH2O seated, `SEATED_SUPINE_COMPLIANCES`), is not the same quantity: the
    /// model's wall has its membrane and relaxed muscles in parallel with this foundation.
    /// With the relaxed diaphragm carrying no pressure, as in people (Agostoni & Rahn 1960,
    /// J Appl Physiol 15:1087), it is the abdomen's own compliance, which the hill law's
    /// relaxed model puts at 0.33 / 0.35 / 0.61 L/cmH2O standing / sitting / supine (`torso
    /// bench relaxation --muscle-law hill --posture standing,sitting,supine`; 0.46 supine with
    /// the thesis law's supine factor): ten and nine times Estenne et al.'s seated 0.032 +- 0.012 (aged 24-39) and supine 0.070 +- 0.025.
    /// Peritoneal dialysis fills in awake supine patients raise the abdominal pressure by 2.2
    /// cmH2O per litre above 2 L (Durand et al. 1996, Perit Dial Int 16 Suppl 1:S84) or 1-3
    /// cmH2O/L (Pérez Díaz et al. 2017, Nefrología 37(6)): 0.33-1.0 L/cmH2O for the whole
    /// abdomen, the diaphragm's side included, a different load and quantity again.
    /// Doubling it raises the relaxed chest wall's compliance by 31 % at +5 cmH2O and 5 % at
    /// -5 cmH2O, the largest effect at +5 cmH2O of any single passive constant.
    /// Calibrated: set by hand in commit aeb7bbe against `tests/physiology.rs`; no command
    /// reproduces a fit, and no measurement of the same quantity was found (see above).
    pub abdominal_wall_compliance: f64,
    /// Tissue resistance of the abdominal wall [Pa s/m^3]: the viscous counterpart of its
    /// compliance, spread over the free wall vertices the same way (a uniform pressure P moves
    /// the wall's volume at P / R_w). Configurations written before it existed read
    /// [`ABDOMINAL_WALL_RESISTANCE`].
    /// Derived: default [`ABDOMINAL_WALL_RESISTANCE`].
    #[serde(default = "default_abdominal_wall_resistance")]
    pub abdominal_wall_resistance: f64,
    /// Gravitational acceleration [m/s^2], 0 to [`GRAVITY_MAX`] (FMI `gravity`, C ABI
    /// `BtConfig.gravity`, CLI `--gravity`). Default [`GRAVITY`]: standard gravity, 9.80665
    /// m/s^2 (3rd CGPM, 1901), rounded. It acts on the true masses. Under
    /// [`GravityLoads::Preloaded`] (the default) constant preloads hold each posture's rest
    /// pose against it (the rest state is the generated anatomy, not an equilibrium found under
    /// gravity; docs/dynamics.md, "Lungs follow the chest wall"), so the posture effects come
    /// from the tables above; under [`GravityLoads::Acting`] it also loads the abdominal
    /// contents' hydrostatic pressure and each posture's rest is found under it.
    /// Derived: default [`GRAVITY`].
    pub gravity: f64,
    /// The muscle law ([`super::muscle::MuscleLaw`]): the seed thesis's shortening spring
    /// (the default) or passive and active parts. Configurations written before it existed
    /// read the thesis's.
    #[serde(default)]
    pub muscle_law: super::muscle::MuscleLaw,
    /// How gravity loads the model ([`GravityLoads`]): preloads cancelling it at each
    /// posture's generated rest (the default), or acting, with the abdominal contents'
    /// hydrostatic pressure and the rest found under the loads. Configurations written
    /// before it existed read the preloaded model.
    #[serde(default)]
    pub gravity_loads: GravityLoads,
    /// Tonic activation of the four abdominal wall muscles (transversus, rectus, external and
    /// internal obliques), a fraction of their maximal force in [0, 1], added to their applied
    /// activation (inputs plus drive) on both sides: the postural tone of the abdominal wall
    /// ([`abdominal_tone`]). Configurations written before it existed read 0.
    /// Derived: default [`STANDING_ABDOMINAL_TONE`] standing under the hill law, else 0
    /// ([`abdominal_tone`]).
    #[serde(default)]
    pub abdominal_tone: f64,
    /// Whether the drive's expiratory rib-cage group (the internal intercostals) follows the
    /// abdominal family's wave rather than the rib family's
    /// ([`expiration_with_abdominals`]): supine under the hill law, where quiet expiration is
    /// passive and the rib cage's expiratory muscles are recruited with the abdominal ones.
    /// Configurations written before it existed read `false` (the rib family's wave).
    #[serde(default)]
    pub expiration_with_abdominals: bool,
    /// Whether the abdominal wall's membrane edges carry tension only, as the dome's do
    /// ([`abdominal_wall_tension_only`]): a membrane wrinkles rather than carry compression,
    /// and a compressed linear edge's negative transverse stiffness buckles the softer wall.
    /// Configurations written before it existed read `false` (linear edges).
    #[serde(default)]
    pub abdominal_wall_tension_only: bool,
    /// Whether the abdominal wall's foundation softens as the wall unloads: each wall vertex
    /// carries at rest the contents' pressure there, and moving inwards from its rest it gives
    /// that load up along an exponential, its normal force k lambda (1 - exp(u / lambda)) for
    /// an outward displacement u < 0 (linear, k u, outwards), with lambda the load over the
    /// foundation's stiffness per area ([`wall_load_at_lowest`] less the contents'
    /// hydrostatic fall, [`ABDOMINAL_CONTENTS_DENSITY`]). A tissue that carries a load is on
    /// the stiff limb of its J-shaped curve and softens as it unloads (Fung 1967, Am J
    /// Physiol 213:1532): an upright wall stiff enough for the seated partition can still
    /// let the contents in when lying down unloads it. Serde default false (linear).
    #[serde(default)]
    pub abdominal_wall_unloading: bool,
}

/// The abdominal wall's tonic activity upright, a fraction of maximal voluntary contraction:
/// the trunk flexors' and extensors' co-activation around a neutral upright spine with no
/// load, 1.7 +- 0.8 % MVC (Cholewicki, Panjabi & Khachatryan 1997, Spine 22:2207, surface EMG
/// of the rectus, external and internal obliques and back extensors in 10 healthy adults, read
/// from the abstract, which does not say whether the subjects stood; a pooled figure, no
/// per-muscle value found). The abdominal muscles are tonically active
/// standing in most subjects, more in the lower abdomen, and silent supine (De Troyer 1983,
/// Respir Physiol 53:341: 8 of 10 subjects; Strohl et al. 1981, J Appl Physiol 51:1471).
/// Source: Cholewicki et al. 1997, 1.7 +- 0.8 % MVC; ours 0.017 of the maximal force (EMG
/// taken as proportional to force).
pub const STANDING_ABDOMINAL_TONE: f64 = 0.017;

/// The abdominal wall's tone ([`Params::abdominal_tone`]) in `posture` under `law` at standard
/// gravity ([`crate::model::Config::model_params`] scales it with gravity: the tone holds the
/// trunk against its weight, and the co-activation rises with the load carried, to 2.9 +- 1.4
/// % MVC with 32 kg on the torso, Cholewicki et al. 1997): [`STANDING_ABDOMINAL_TONE`]
/// standing under the passive-and-active law, where an activation is a fraction of the maximal
/// force; none supine (silent: De Troyer 1983, Strohl et al. 1981)
/// nor sitting (lower than standing for the obliques, Snijders et al. 1995, with no figure
/// found), and none under the thesis's law, whose drives and figures were calibrated without
/// it.
pub fn abdominal_tone(posture: Posture, law: super::muscle::MuscleLaw) -> f64 {
    match (posture, law) {
        (Posture::Standing, super::muscle::MuscleLaw::Hill) => STANDING_ABDOMINAL_TONE,
        _ => 0.0,
    }
}

/// Whether, in `posture` under `law`, the drive's expiratory rib-cage muscles (the model's
/// internal intercostals, standing for the rib cage's expiratory muscles: the internal
/// interosseous intercostals of the caudal interspaces and the triangularis sterni) follow the
/// abdominal family's expiratory wave instead of the rib family's
/// ([`Params::expiration_with_abdominals`]).
///
/// - Supine, quiet expiration is passive: the triangularis sterni is usually silent in resting
///   breathing and is recruited, with its activation largely coupled to the abdominal
///   muscles', in active expiration, expulsive efforts, speech and cough (De Troyer, Ninane,
///   Gilmartin, Lemerre & Estenne 1987, J Appl Physiol 62:919, needle EMG in 12 supine
///   adults); the triangularis sterni and the abdominal muscles are usually silent supine
///   (Estenne, Ninane & De Troyer 1988, Respir Physiol 74:151, 20 adults). So supine the
///   group moves with the abdominal family: silent in quiet breathing (the quiet drive has no
///   abdominal wave), active when a forced drive recruits the abdominal muscles.
/// - Standing, 16 of the same 20 adults had triangularis sterni activity in quiet breathing,
///   confined to expiration in 15 (Estenne et al. 1988): the group keeps the rib family's
///   antiphase wave (the drive's structure, thesis 2.4.1). Sitting was not studied there; it
///   is treated as upright.
/// - Under the thesis's law, whose drives were calibrated with the rib family's wave in
///   every posture, the structure is unchanged.
pub fn expiration_with_abdominals(posture: Posture, law: super::muscle::MuscleLaw) -> bool {
    posture == Posture::Supine && law == super::muscle::MuscleLaw::Hill
}

/// The pressure of the abdominal contents at the abdominal wall's lowest point at rest,
/// relative to the body surface [Pa], at gravity `gravity` [m/s^2] (scaled from 9.81).
/// Source: bladder pressure of healthy adults, the lowest point of the cavity: standing 20
/// mmHg (27.2 cmH2O) and sitting 16.7 mmHg (22.7 cmH2O), 20 adults aged up to 30 (Cobb et
/// al. 2005, J Surg Res 129:231, abstract); supine 10.5 +- 4.7 cmH2O (standing 31.0 +- 6.4),
/// 39 continent women (Am J Obstet Gynecol 2005, 192:1722, abstract).
pub fn wall_load_at_lowest(posture: Posture, gravity: f64) -> f64 {
    let cmh2o = match posture {
        Posture::Standing => 27.2,
        Posture::Sitting => 22.7,
        Posture::Supine => 10.5,
    };
    cmh2o * 98.0665 * gravity / GRAVITY
}

/// The smallest load a wall vertex is taken to carry at rest [Pa] (0.5 cmH2O), so that its
/// unloading length stays positive where the contents' hydrostatic fall reaches the surface
/// pressure ([`Params::abdominal_wall_unloading`]).
/// Numerical: a floor, not a property of the body.
pub const WALL_LOAD_FLOOR: f64 = 0.5 * 98.0665;

/// Whether the abdominal wall's membrane edges carry tension only under `law`
/// ([`Params::abdominal_wall_tension_only`]).
///
/// - Under the passive-and-active law: yes. A membrane wrinkles rather than carry compression
///   (tension-field theory: Stein & Hedgepeth 1961, NASA TN D-813; Mansfield 1969, Proc R Soc
///   A 311:1), and a compressed linear edge has a negative transverse stiffness, -|f| / L. The
///   law's soft passive wall (its foundation scaled by [`HILL_PASSIVE_WALL_SCALE`]) no longer
///   holds the wall's vertices against it: with linear edges, deflating the relaxed standing
///   chest wall below FRC wrinkled the lowest ring of the abdominal wall, each vertex snapping
///   through by 1-2 mm between -4 and -6.5 cmH2O at the airway opening under the inertial
///   solver, and the quasi-static relaxation curve ended 0.28 L below FRC standing and 0.04 L
///   supine; with tension-only edges it spans RV to TLC in both postures (`torso bench
///   relaxation --muscle-law hill`, docs/dynamics.md, "The relaxed wall below FRC").
/// - Under the thesis's law: no. Its level-1 relaxed curve stops at the same 3.225 L
///   (`tests/relaxation.rs`, `relaxation_curve_reaches_residual_volume`, ignored), and with
///   tension-only edges it spans RV to TLC too (measured: C_cw 0.0923 to 0.0954 L/cmH2O, the
///   default quiet tidal volume 0.536 to 0.546 L). But its quasi-static quiet breathing at
///   level 2 then buckles at the end of the first expiration (3.24 s; the least stable mode
///   lies on the dome's slack top; docs/dynamics.md, "The relaxed wall below FRC"), where with
///   linear edges it runs.
///
/// The toe of the tension-only law ([`TENSION_TOE`]) sits at the rest's zero force: halving
/// it moves the hill law's relaxed chest wall by +0.15 % standing and +2.3 % supine (gravity
/// preloaded; `torso bench relaxation --muscle-law hill` with the constant changed).
pub fn abdominal_wall_tension_only(law: super::muscle::MuscleLaw) -> bool {
    law == super::muscle::MuscleLaw::Hill
}

/// The factor on the passive chest wall's hand-set stiffnesses (and divisor of the abdominal
/// wall's compliance, [`Params::scale_passive_wall`]) under the passive-and-active muscle law
/// ([`super::muscle::MuscleLaw::Hill`]): with it the relaxed chest wall of the default subject
/// standing at level of detail 1 has the adult's compliance, 0.2 L/cmH2O over the tidal range
/// above FRC (Agostoni & Mead 1964, Handbook of Physiology, Respiration I, ch. 13).
/// Fitted with the law's cited maximal forces (`super::muscle::HILL_DIAPHRAGM_FORCE`,
/// `super::muscle::HILL_INTERCOSTAL_TENSION`; 0.349 with the thesis law's 600 N and 1200 N/m)
/// and the abdominal wall's tension-only edges ([`abdominal_wall_tension_only`]; 0.421 with
/// linear ones).
/// Fitted: `torso bench relaxation --muscle-law hill --fit --posture standing` (secant on the
/// compliance of the relaxation curve, `bench::relaxation::fit_passive_wall`), which prints
/// "fitted factor on the passive wall (Hill law): 0.440".
pub const HILL_PASSIVE_WALL_SCALE: f64 = 0.440;

/// The factor on the cartilage joints' stiffness under the passive-and-active law, after
/// [`HILL_PASSIVE_WALL_SCALE`] ([`Params::scale_compartments`]): with it and
/// [`HILL_ABDOMINAL_WALL_FACTOR`] the relaxed rib cage and diaphragm-abdomen of the default
/// subject seated at level of detail 1 have young seated adults' compliances over the tidal
/// range, 0.164 and 0.032 L/cmH2O (Estenne, Yernault & De Troyer 1985, J Appl Physiol
/// 59:1842; `bench::relaxation::SEATED_COMPARTMENTS`). In the model's closed loop of rigid
/// ribs and sternum the cartilage, not the rib joints, sets the rib cage's compliance; the
/// fitted joint, 50 N/m, stands for the synovial sternocostal joints' sliding and the
/// cartilages' and ribs' bending that rigid ribs lack (the first rib's synchondrosis keeps
/// the passive wall's 4400 N/m, [`Params::first_cartilage_stiffness`]).
/// Fitted: `torso bench relaxation --muscle-law hill --fit-compartments --posture sitting`
/// (Newton steps on the logarithms, `bench::relaxation::fit_compartments`), which prints
/// "fitted factors on the compartments (Hill law): cartilage 0.0113, abdominal wall 9.314".
pub const HILL_CARTILAGE_FACTOR: f64 = 0.0113;

/// The factor on the abdominal wall's stiffness (its membranes times, its foundation's
/// compliance divided) under the passive-and-active law, after [`HILL_PASSIVE_WALL_SCALE`];
/// fitted with [`HILL_CARTILAGE_FACTOR`], which see.
/// Fitted: `torso bench relaxation --muscle-law hill --fit-compartments --posture sitting`,
/// which prints "abdominal wall 9.314".
pub const HILL_ABDOMINAL_WALL_FACTOR: f64 = 9.314;

/// Whether the abdominal wall's foundation softens as it unloads under `law`
/// ([`Params::abdominal_wall_unloading`]): under the passive-and-active law, whose upright
/// wall is fitted stiff ([`HILL_ABDOMINAL_WALL_FACTOR`]).
pub fn abdominal_wall_unloading(law: super::muscle::MuscleLaw) -> bool {
    law == super::muscle::MuscleLaw::Hill
}

/// The adult relaxed chest wall's compliance over the tidal range above FRC [L/cmH2O], the
/// target of [`HILL_PASSIVE_WALL_SCALE`]'s fit.
/// Source: Agostoni & Mead 1964, Handbook of Physiology, Respiration I, ch. 13: about 0.2
/// L/cmH2O (Estenne et al. 1985, J Appl Physiol 59:1842: 0.166 seated, 0.158 supine).
pub const CHEST_WALL_COMPLIANCE: f64 = 0.2;

impl Params {
    /// Defaults for a posture under muscle law `law`: [`Params::for_posture`], and under the
    /// passive-and-active law the passive wall scaled by [`HILL_PASSIVE_WALL_SCALE`], fitted to
    /// the relaxed chest wall's compliance once the muscles no longer carry its stiffness, its
    /// cartilage and abdominal wall then scaled apart by [`HILL_CARTILAGE_FACTOR`] and
    /// [`HILL_ABDOMINAL_WALL_FACTOR`], fitted to the seated compartments, the wall that softens
    /// as it unloads ([`abdominal_wall_unloading`]), and
    /// the posture's abdominal tone ([`abdominal_tone`]), its expiratory rib-cage drive
    /// ([`expiration_with_abdominals`]), the abdominal wall's tension-only edges
    /// ([`abdominal_wall_tension_only`]) and with them, supine, the wall's factor
    /// `TENSION_ONLY_SUPINE_WALL_COMPLIANCE`.
    pub fn for_posture_and_law(posture: Posture, law: super::muscle::MuscleLaw) -> Params {
        let mut p = Params::before_compartments(posture, law);
        if law == super::muscle::MuscleLaw::Hill {
            p.scale_compartments(HILL_CARTILAGE_FACTOR, HILL_ABDOMINAL_WALL_FACTOR);
        }
        p
    }

    /// [`Params::for_posture_and_law`] before its compartments are fitted apart: under the
    /// passive-and-active law the passive wall scaled by [`HILL_PASSIVE_WALL_SCALE`] alone,
    /// the first rib's cartilage held at that stiffness ([`Params::first_cartilage_stiffness`]);
    /// what the fit of [`HILL_CARTILAGE_FACTOR`] and [`HILL_ABDOMINAL_WALL_FACTOR`] scales
    /// (`torso bench relaxation --fit-compartments`).
    pub fn before_compartments(posture: Posture, law: super::muscle::MuscleLaw) -> Params {
        let mut p = Params::unscaled_for_posture_and_law(posture, law);
        if law == super::muscle::MuscleLaw::Hill {
            p.scale_passive_wall(HILL_PASSIVE_WALL_SCALE);
            // the synchondrosis keeps the passive wall's stiffness
            p.first_cartilage_stiffness = p.cartilage_stiffness;
        }
        p
    }

    /// [`Params::for_posture_and_law`] before its passive wall is scaled: what the fit of
    /// [`HILL_PASSIVE_WALL_SCALE`] scales (`torso bench relaxation --fit`).
    pub fn unscaled_for_posture_and_law(posture: Posture, law: super::muscle::MuscleLaw) -> Params {
        let mut p = Params::for_posture(posture);
        p.muscle_law = law;
        p.abdominal_tone = abdominal_tone(posture, law);
        p.expiration_with_abdominals = expiration_with_abdominals(posture, law);
        p.abdominal_wall_tension_only = abdominal_wall_tension_only(law);
        p.abdominal_wall_unloading = abdominal_wall_unloading(law);
        if p.abdominal_wall_tension_only && posture == Posture::Supine {
            p.abdominal_wall_compliance *=
                TENSION_ONLY_SUPINE_WALL_COMPLIANCE / SUPINE_WALL_COMPLIANCE;
        }
        p
    }

    /// Scales the passive chest wall's hand-set constants by `factor`: the stiffnesses of the
    /// rib joints, cartilage, abdominal and dome membranes, central tendon and dome support
    /// times `factor`, the abdominal wall's compliance divided by it (their ratios, set by
    /// hand, are kept; `docs/dynamics.md`, "What sets the passive chest wall").
    pub fn scale_passive_wall(&mut self, factor: f64) {
        self.rib_joint_stiffness *= factor;
        self.cartilage_stiffness *= factor;
        self.first_cartilage_stiffness *= factor;
        self.membrane_stiffness *= factor;
        self.dome_membrane_stiffness *= factor;
        self.tendon_stiffness *= factor;
        self.dome_support *= factor;
        self.abdominal_wall_compliance /= factor;
    }

    /// Scales the passive chest wall's two compartments apart: the cartilage joints' stiffness
    /// (which, in the closed loop of ribs and sternum, sets most of the relaxed rib cage's
    /// compliance) times `cartilage`, and the abdominal wall (its membranes' stiffness times
    /// `abdominal_wall`, its compliance divided by it). The rib joints, the dome's membrane,
    /// central tendon and support keep their values. What
    /// `bench::relaxation::fit_compartments` fits to the relaxed compartments' compliances.
    pub fn scale_compartments(&mut self, cartilage: f64, abdominal_wall: f64) {
        self.cartilage_stiffness *= cartilage;
        self.membrane_stiffness *= abdominal_wall;
        self.abdominal_wall_compliance /= abdominal_wall;
    }

    /// Largest contraction of an element of `group` (see [`Params::beta_max`]): the
    /// diaphragm's own, [`Params::beta_max`] for every other group (the scalenes and the
    /// sternocleidomastoids alike).
    pub fn beta_for(&self, group: crate::anatomy::MuscleGroup) -> f64 {
        match group {
            crate::anatomy::MuscleGroup::Diaphragm => self.beta_max_diaphragm,
            _ => self.beta_max,
        }
    }

    /// Defaults for a posture. Supine increases the abdominal compliance (thesis 2.3: "a change
    /// from the seated to the supine position increases the abdominal compliance") and
    /// decreases the rib cage's (Estenne et al. 1985: [`SEATED_SUPINE_COMPLIANCES`]); the
    /// diaphragm, whose fibres are longer at the lower supine FRC, has a larger range of
    /// shortening ([`Params::beta_max_diaphragm`], [`diaphragm_length_ratio`]).
    pub fn for_posture(posture: Posture) -> Params {
        let [rib_cage, _] = SEATED_SUPINE_COMPLIANCES;
        // Abdominal wall compliance relative to standing; rib-joint stiffness relative to
        // upright (sitting and standing alike for the rib cage).
        let (compliance_factor, rib_stiffness_factor) = match posture {
            Posture::Standing => (1.0, 1.0),
            Posture::Sitting => (SITTING_WALL_COMPLIANCE, 1.0),
            Posture::Supine => (SUPINE_WALL_COMPLIANCE, rib_cage[0] / rib_cage[1]),
        };
        Params {
            beta_max: 0.3,
            beta_max_diaphragm: diaphragm_contraction(posture),
            damping_ratio: 1.0,
            inertia_frequency: INERTIA_FREQUENCY,
            true_masses: false,
            specific_airway_conductance: SPECIFIC_AIRWAY_CONDUCTANCE,
            tension_toe: TENSION_TOE,
            transverse_fraction: TRANSVERSE_FRACTION,
            bulk_modulus: 3.0e5,
            lung_elastance: 1.0 / 2.0e-6,
            lung_recoil_at_frc: LUNG_RECOIL_AT_FRC,
            pleural_barrier_pressure: PLEURAL_BARRIER_PRESSURE,
            pleural_barrier_margin: PLEURAL_BARRIER_MARGIN,
            cartilage_stiffness: 1.0e4,
            first_cartilage_stiffness: 0.0,
            rib_joint_stiffness: 2.0 * rib_stiffness_factor,
            membrane_stiffness: 400.0,
            dome_membrane_stiffness: 40.0,
            dome_support: 2.0e5,
            tendon_stiffness: 2000.0,
            abdominal_wall_compliance: 2.0e-6 * compliance_factor,
            abdominal_wall_resistance: ABDOMINAL_WALL_RESISTANCE,
            gravity: GRAVITY,
            muscle_law: super::muscle::MuscleLaw::Thesis,
            gravity_loads: GravityLoads::Preloaded,
            abdominal_tone: 0.0,
            expiration_with_abdominals: false,
            abdominal_wall_tension_only: false,
            abdominal_wall_unloading: false,
        }
    }

    /// Checks that every constant is finite and in its physical range; the error names the
    /// constant.
    pub fn validate(&self) -> crate::Result<()> {
        let positive = [
            ("params.damping_ratio", self.damping_ratio),
            ("params.inertia_frequency", self.inertia_frequency),
            (
                "params.specific_airway_conductance",
                self.specific_airway_conductance,
            ),
            ("params.tension_toe", self.tension_toe),
            ("params.bulk_modulus", self.bulk_modulus),
            ("params.lung_elastance", self.lung_elastance),
            ("params.lung_recoil_at_frc", self.lung_recoil_at_frc),
            (
                "params.pleural_barrier_pressure",
                self.pleural_barrier_pressure,
            ),
            ("params.cartilage_stiffness", self.cartilage_stiffness),
            ("params.rib_joint_stiffness", self.rib_joint_stiffness),
            ("params.membrane_stiffness", self.membrane_stiffness),
            (
                "params.dome_membrane_stiffness",
                self.dome_membrane_stiffness,
            ),
            ("params.tendon_stiffness", self.tendon_stiffness),
            ("params.dome_support", self.dome_support),
            (
                "params.abdominal_wall_compliance",
                self.abdominal_wall_compliance,
            ),
        ];
        for (name, v) in positive {
            if !(v.is_finite() && v > 0.0) {
                return Err(crate::Error::invalid(name, v, "finite and > 0"));
            }
        }
        if !(self.first_cartilage_stiffness.is_finite() && self.first_cartilage_stiffness >= 0.0) {
            return Err(crate::Error::invalid(
                "params.first_cartilage_stiffness",
                self.first_cartilage_stiffness,
                "finite and >= 0 (0: as params.cartilage_stiffness)",
            ));
        }
        if !(self.abdominal_wall_resistance.is_finite() && self.abdominal_wall_resistance >= 0.0) {
            return Err(crate::Error::invalid(
                "params.abdominal_wall_resistance",
                self.abdominal_wall_resistance,
                "finite and >= 0",
            ));
        }
        if !(self.abdominal_tone.is_finite() && (0.0..=1.0).contains(&self.abdominal_tone)) {
            return Err(crate::Error::invalid(
                "params.abdominal_tone",
                self.abdominal_tone,
                "[0, 1]",
            ));
        }
        if !(self.transverse_fraction.is_finite()
            && (0.0..=1.0).contains(&self.transverse_fraction))
        {
            return Err(crate::Error::invalid(
                "params.transverse_fraction",
                self.transverse_fraction,
                "[0, 1]",
            ));
        }
        if !(self.pleural_barrier_margin > 0.0 && self.pleural_barrier_margin < 0.5) {
            return Err(crate::Error::invalid(
                "params.pleural_barrier_margin",
                self.pleural_barrier_margin,
                "(0, 0.5)",
            ));
        }
        for (name, v) in [
            ("params.beta_max", self.beta_max),
            ("params.beta_max_diaphragm", self.beta_max_diaphragm),
        ] {
            if !(v > 0.0 && v < 1.0) {
                return Err(crate::Error::invalid(name, v, "(0, 1)"));
            }
        }
        if !(self.gravity.is_finite() && (0.0..=GRAVITY_MAX).contains(&self.gravity)) {
            return Err(crate::Error::invalid(
                "params.gravity",
                self.gravity,
                format!("finite and in [0, {GRAVITY_MAX}] m/s^2"),
            ));
        }
        Ok(())
    }

    /// Unit vector of gravity in the model frame (x anterior, y cranial, z right).
    pub fn gravity_direction(posture: Posture) -> [f64; 3] {
        match posture {
            Posture::Standing | Posture::Sitting => [0.0, -1.0, 0.0],
            // Lying on the back: gravity points dorsally.
            Posture::Supine => [-1.0, 0.0, 0.0],
        }
    }
}
