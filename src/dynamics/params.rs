//! Physical constants of the model, with their sources. Stiffness and damping are physical
//! (N/m per element, Pa, N m/rad) rather than the thesis's unit gains, so that the default
//! activations produce physiological volumes.

use crate::anatomy::Posture;
use serde::{Deserialize, Serialize};

/// Largest contraction of the diaphragm's fibres from their standing rest length: they can
/// shorten by 30-40 % (seed thesis 2.3, after Hamid et al.).
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
pub const SEATED_SUPINE_COMPLIANCES: [[f64; 2]; 2] = [[0.141, 0.088], [0.025, 0.070]];

/// Abdominal wall compliance sitting relative to standing: a small factor of the model, not a
/// measured ratio (the seed thesis 2.3 only orders the postures: supine is more compliant than
/// seated); sitting is the reference posture of [`SEATED_SUPINE_COMPLIANCES`].
pub const SITTING_WALL_COMPLIANCE: f64 = 1.1;

/// Abdominal wall compliance supine relative to standing (x1.64 from sitting). The measured
/// seated-to-supine ratio of the diaphragm-abdomen compliance is x2.8
/// ([`SEATED_SUPINE_COMPLIANCES`]), but that soft a generated wall is folded in by forced
/// expiratory abdominal contraction and the integration stalls (forced supine breathing at
/// x3.08 stops advancing near t = 3 s: `cargo run --release --example posture_breathing --
/// --probe 1 1.711`), so the model keeps the smaller increase.
pub const SUPINE_WALL_COMPLIANCE: f64 = 1.8;

/// Default [`Params::pleural_barrier_pressure`]: 0.5 cmH2O [Pa]. Small enough that the
/// lungs stay within 5 % of linear over a forced breath (1 L below rest, the barrier adds
/// 0.1 cmH2O to 5 cmH2O of recoil for the default subject), large enough that the recoil
/// passes 30 cmH2O a few percent of the way from the residual volume to rest.
pub const PLEURAL_BARRIER_PRESSURE: f64 = 0.5 * 98.0665;

/// Default [`Params::pleural_barrier_margin`]: the tangent takes over 1 % of the way from
/// each asymptote to rest, where the barrier alone is about 48 cmH2O (beyond any quiet or
/// forced breath). With 2 % the strongest soak scene (seed 2011, scene 35) was squeezed 6 %
/// below its residual volume along the tangent; with 1 % it stops at it.
pub const PLEURAL_BARRIER_MARGIN: f64 = 0.01;

/// Default [`Params::inertia_frequency`] [Hz]: ten times the fastest breathing the drive
/// supports (2 Hz, `model::drive::FREQUENCY_RANGE`) and a little more, so that inertia changes
/// the response to any drive by well under 1 % (the inertial force relative to the elastic one
/// goes as (f / f_inertia)^2: (2 / 25)^2 = 0.6 % at the fastest drive, 1e-4 at quiet breathing).
pub const INERTIA_FREQUENCY: f64 = 25.0;

/// Default [`Params::specific_airway_conductance`] [1/(Pa s)]: 0.2 /(cmH2O s). Airway
/// conductance grows in proportion to lung volume, so that its ratio to the volume, the
/// specific conductance, is nearly constant between subjects (Briscoe & DuBois 1958, J Clin
/// Invest 37:1279: sGaw about 0.13-0.35 /(cmH2O s) in healthy adults). At the default man's
/// functional residual capacity (3.3 L, ECSC 1993) it gives an airway resistance of
/// 1.5 cmH2O s/L, inside the 0.5-2.5 cmH2O s/L of healthy adults (West, Respiratory
/// Physiology).
pub const SPECIFIC_AIRWAY_CONDUCTANCE: f64 = 0.2 / 98.0665;

/// Default [`Params::lung_recoil_at_frc`] [Pa]: 5 cmH2O. At the functional residual capacity,
/// with no flow, the pleural pressure is minus the lungs' elastic recoil, about -5 cmH2O in
/// upright adults (oesophageal balloon; Milic-Emili et al. 1964, J Appl Physiol 19:207;
/// Agostoni & Hyatt 1986, Handbook of Physiology, The Respiratory System III, ch. 9).
pub const LUNG_RECOIL_AT_FRC: f64 = 5.0 * 98.0665;

/// Default [`Params::tension_toe`] [N]: the width of the smooth toe of the tension-only law.
/// 0.1 N is about 1 % of the smallest muscle element's tension in quiet breathing and a few
/// thousandths of its largest; it is measured, not cited: halving it changes the default
/// subject's quiet tidal volume by under 0.1 % (`cargo run --release --example
/// fast_dynamics -- toe`).
pub const TENSION_TOE: f64 = 0.1;

/// Default [`Params::transverse_fraction`]: 0.1, the sin^2 of an 18 degree tilt. Each
/// two-point element's added inertia and damping act in its transverse directions with this
/// fraction of their axial values, so that an element that tilts by up to 18 degrees from its
/// rest direction as the cavities deform still finds as much inertia as the stiffness it
/// turns into the new direction. It is a numerical constant, chosen by measurement
/// (`cargo run --release --example fast_dynamics -- 1 1e-6 tilt=F`, docs/dynamics.md): at
/// level of detail 1, 0 leaves the step bound by the dome's central-tendon pole (29,090 RHS
/// evaluations per 1000 frames), 0.1 frees it; it changes the quiet tidal volume by under 1 %.
pub const TRANSVERSE_FRACTION: f64 = 0.1;

/// Default [`Params::abdominal_wall_resistance`] [Pa s/m^3]: 1.0 cmH2O s/L. The whole
/// respiratory system's resistance at breathing frequencies is about 2-3 cmH2O s/L, airways and
/// tissue together, and the airways' about 0.5-2.5 (West, Respiratory Physiology); the default
/// man's airway resistance is 1.5 cmH2O s/L ([`SPECIFIC_AIRWAY_CONDUCTANCE`]), which leaves
/// 0.5-1.5 cmH2O s/L to the tissues, and the model gives the middle of that to the abdominal
/// wall (the rib cage's joints and the lungs' tissue carry their own damping).
pub const ABDOMINAL_WALL_RESISTANCE: f64 = 1.0 * 98.0665e3;

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
    pub beta_max: f64,
    /// The same for the diaphragm, which can shorten by 30-40 % from its upright rest length
    /// (seed thesis 2.3, after Hamid et al.): r >= 0.6 standing. In the other postures the
    /// fibres start longer and reach the same shortest length (see
    /// [`diaphragm_length_ratio`]), so their fraction is larger.
    pub beta_max_diaphragm: f64,
    /// Damping ratio zeta of the model's inertial modes at the inertia frequency
    /// ([`Params::inertia_frequency`]): every spring-damper element, vector spring and rib
    /// joint has the damping coefficient beta k of its stiffness k, beta = 2 zeta /
    /// (2 pi f_inertia) (stiffness-proportional damping, Rayleigh; thesis 2.4 asks for
    /// critically damped elements, zeta = 1).
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
    #[serde(default = "default_inertia_frequency")]
    pub inertia_frequency: f64,
    /// Specific airway conductance [1/(Pa s)]: the airway resistance between the alveoli and
    /// the mouth is 1 / (sGaw FRC) for the subject's functional residual capacity, and the
    /// pleural pressure carries the pressure drop R dV/dt of the flow through it.
    /// Configurations written before it existed read [`SPECIFIC_AIRWAY_CONDUCTANCE`].
    #[serde(default = "default_specific_airway_conductance")]
    pub specific_airway_conductance: f64,
    /// Width [N] of the smooth toe of the tension-only law of the muscles: the tension is
    /// eps ln(1 + exp(f / eps)) of the linear spring-damper force f (softplus), so that it is
    /// smooth where a muscle goes slack. Configurations written before it existed read
    /// [`TENSION_TOE`].
    #[serde(default = "default_tension_toe")]
    pub tension_toe: f64,
    /// Fraction of each two-point element's added inertia and damping given to its
    /// transverse directions (`dynamics::inertia`; [`TRANSVERSE_FRACTION`]): the element
    /// damps the relative velocity of its ends across it with this fraction of its axial
    /// damping coefficient, and its ends' mass blocks carry the same fraction of its
    /// stiffness over omega_b^2 across it. Configurations written before it existed read
    /// [`TRANSVERSE_FRACTION`].
    #[serde(default = "default_transverse_fraction")]
    pub transverse_fraction: f64,
    /// Bulk modulus K of the abdominal contents [Pa] (thesis eq. 2.5: P = K (V0/V - 1)).
    pub bulk_modulus: f64,
    /// Lung elastance [Pa/m^3]: pleural pressure change per volume change of the lungs (the
    /// thorax's, one to one), 1 / (0.2 L/cmH2O) (lung compliance, physiology reference).
    pub lung_elastance: f64,
    /// The lungs' elastic recoil at rest, the functional residual capacity [Pa]
    /// ([`LUNG_RECOIL_AT_FRC`]): the pleural pressure read out is minus it at rest. The
    /// dynamics work with changes from rest (the chest wall's rest forces balance it), so it
    /// sets only the absolute pleural pressure. Configurations written before it existed
    /// read [`LUNG_RECOIL_AT_FRC`].
    #[serde(default = "default_lung_recoil_at_frc")]
    pub lung_recoil_at_frc: f64,
    /// Barrier pressure p_b [Pa] of the pleural pressure-volume law
    /// ([`super::pleural::PleuralLaw`]): the recoil added near the residual volume (and the
    /// total lung capacity) is about p_b x0 / x at a distance x from it (x0 from rest). > 0;
    /// configurations written before it existed read [`PLEURAL_BARRIER_PRESSURE`].
    #[serde(default = "default_pleural_barrier_pressure")]
    pub pleural_barrier_pressure: f64,
    /// Margin of the pleural pressure-volume law's barriers, as a fraction of the distance
    /// from the rest volume to each asymptote (residual volume below, total lung capacity
    /// above): within it the law follows its tangent (see [`super::pleural::PleuralLaw`]), so
    /// that it is finite for every volume an overshooting solver stage may probe. In (0, 0.5);
    /// configurations written before it existed read [`PLEURAL_BARRIER_MARGIN`].
    #[serde(default = "default_pleural_barrier_margin")]
    pub pleural_barrier_margin: f64,
    /// Stiffness of a cartilage ball joint [N/m].
    pub cartilage_stiffness: f64,
    /// Rotational stiffness of a costovertebral joint with its share of chest-wall recoil
    /// [N m/rad].
    pub rib_joint_stiffness: f64,
    /// In-plane stiffness of an abdominal membrane edge [N/m] (2D modulus about 1.15 k).
    pub membrane_stiffness: f64,
    /// In-plane stiffness of a membrane edge of the diaphragm dome [N/m]: the dome's passive
    /// stiffness is low along its fibres, so that their shortening can lower it like a piston.
    pub dome_membrane_stiffness: f64,
    /// In-plane stiffness of a membrane edge of the central tendon [N/m] (stiff: it carries the
    /// radial fibres' pull across the top of the dome).
    pub tendon_stiffness: f64,
    /// Horizontal support of the diaphragm dome by the rib cage and lungs [N/m^3] (foundation
    /// stiffness per area of dome).
    pub dome_support: f64,
    /// Compliance of the abdominal wall [m^3/Pa] (elastic support of the wall by its muscles,
    /// fascia and skin), spread over the free wall vertices as a foundation stiffness.
    pub abdominal_wall_compliance: f64,
    /// Tissue resistance of the abdominal wall [Pa s/m^3]: the viscous counterpart of its
    /// compliance, spread over the free wall vertices the same way (a uniform pressure P moves
    /// the wall's volume at P / R_w). Configurations written before it existed read
    /// [`ABDOMINAL_WALL_RESISTANCE`].
    #[serde(default = "default_abdominal_wall_resistance")]
    pub abdominal_wall_resistance: f64,
    /// Gravitational acceleration [m/s^2].
    pub gravity: f64,
}

impl Params {
    /// Largest contraction of an element of `group` (see [`Params::beta_max`]).
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
            specific_airway_conductance: SPECIFIC_AIRWAY_CONDUCTANCE,
            tension_toe: TENSION_TOE,
            transverse_fraction: TRANSVERSE_FRACTION,
            bulk_modulus: 3.0e5,
            lung_elastance: 1.0 / 2.0e-6,
            lung_recoil_at_frc: LUNG_RECOIL_AT_FRC,
            pleural_barrier_pressure: PLEURAL_BARRIER_PRESSURE,
            pleural_barrier_margin: PLEURAL_BARRIER_MARGIN,
            cartilage_stiffness: 1.0e4,
            rib_joint_stiffness: 2.0 * rib_stiffness_factor,
            membrane_stiffness: 400.0,
            dome_membrane_stiffness: 40.0,
            dome_support: 2.0e5,
            tendon_stiffness: 2000.0,
            abdominal_wall_compliance: 2.0e-6 * compliance_factor,
            abdominal_wall_resistance: ABDOMINAL_WALL_RESISTANCE,
            gravity: 9.81,
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
        if !(self.abdominal_wall_resistance.is_finite() && self.abdominal_wall_resistance >= 0.0) {
            return Err(crate::Error::invalid(
                "params.abdominal_wall_resistance",
                self.abdominal_wall_resistance,
                "finite and >= 0",
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
        if !(self.gravity.is_finite() && self.gravity >= 0.0) {
            return Err(crate::Error::invalid(
                "params.gravity",
                self.gravity,
                ">= 0",
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
