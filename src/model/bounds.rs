//! Which states count as physiological: the bounds of the thorax, abdomen and trunk volumes
//! relative to their rest values, beyond which a state has left the body's range, and the
//! facade's check of a state against them ([`Torso::physiology_violation`], with the rest
//! volumes computed once per compiled model, [`Compiled::rest_volumes`]). A step made with
//! [`super::AdvanceOptions::check_physiology`] that ends there is rolled back: the FMU
//! discards it (`fmi2Discard`, the instance stays at its last good time), the C ABI's
//! `bt_advance_to` and `torso simulate` fail with [`crate::Error::Unphysiological`], and the
//! stress benchmarks count such a run a blow-up. The dynamics keep only the pressure-volume
//! law itself ([`crate::dynamics::pleural`]), whose residual-volume and total-lung-capacity
//! ratios the thorax's bounds follow.

use super::{Compiled, Quantity, Torso};
use crate::Result;
use crate::anatomy::Subject;
use crate::dynamics::pleural::capacity_ratios;

/// Bounds of the abdomen and trunk cavity volumes as multiples of
/// their volumes in the rest state of the same model (muscles relaxed: the functional residual
/// capacity), and the thorax's bounds for a typical adult. In adults the residual volume is
/// about half the functional residual capacity and the total lung capacity about twice it
/// (ECSC reference values, Quanjer et al. 1993, Eur Respir J 6 Suppl 16: e.g. 30 y, 1.75 m
/// man: RV 1.7 L, FRC 3.3 L, TLC 7.0 L), so a cavity leaving [0.5, 2] x rest has left
/// physiology: an FMU step ending there is discarded (`fmi2Discard`) rather than continued
/// with an unphysical state, and a stress run counts it a blow-up. The thorax's own bounds
/// follow the subject ([`cavity_bounds`]).
pub const CAVITY_BOUNDS: (f64, f64) = (0.5, 2.0);

/// Room left beyond the subject's residual volume and total lung capacity before the thorax
/// counts as out of bounds: the pleural law's barriers stop the lungs at those volumes, and
/// its tangent continuation within the barrier margin lets a strong effort pass them by a
/// fraction of a percent (0.2 % in the strongest soak scenes), so 10 % is well clear of
/// anything the law allows and still far from a collapse.
pub const CAPACITY_SLACK: f64 = 0.1;

/// Bounds of the thorax, abdomen and trunk volumes (in that order) as multiples of their
/// rest values for `subject`. The abdomen and trunk keep [`CAVITY_BOUNDS`]; the thorax's
/// widen to the subject's own limits when they lie beyond: its residual volume and total
/// lung capacity relative to its functional residual capacity (the ratios at which the
/// pleural law places its barriers, [`capacity_ratios`]), less and plus
/// [`CAPACITY_SLACK`]. Over the declared subject ranges RV/FRC spans 0.38-0.89 and TLC/FRC
/// 1.37-2.43 (ECSC 1993), so a fixed [0.5, 2] would discard a full expiration of a short
/// young woman (1.60 m, 18 y: RV/FRC 0.46) or a full inspiration of a tall young man.
pub fn cavity_bounds(subject: &Subject) -> [(f64, f64); 3] {
    let (rv, tlc) = capacity_ratios(subject);
    let thorax = (
        CAVITY_BOUNDS.0.min(rv * (1.0 - CAPACITY_SLACK)),
        CAVITY_BOUNDS.1.max(tlc * (1.0 + CAPACITY_SLACK)),
    );
    [thorax, CAVITY_BOUNDS, CAVITY_BOUNDS]
}

/// The cavity volumes checked against [`cavity_bounds`], with their output names.
pub const CHECKED_VOLUMES: [(Quantity, &str); 3] = [
    (Quantity::ThoraxVolume, "volume.thorax"),
    (Quantity::AbdomenVolume, "volume.abdomen"),
    (Quantity::TrunkVolume, "volume.trunk"),
];

impl Compiled {
    /// The [`CHECKED_VOLUMES`] of the rest state (muscles relaxed, zero airway-opening
    /// pressure) [L], the reference of [`cavity_bounds`]; computed on the first call, then
    /// kept.
    pub fn rest_volumes(&self) -> [f64; 3] {
        *self.rest_volumes.get_or_init(|| {
            let model = &self.model;
            let mut data = crate::dynamics::Data::new(model);
            let y = crate::dynamics::rest_state(model);
            crate::dynamics::kinematics::positions_and_velocities(
                model,
                &mut data,
                &model.layout,
                &y,
            );
            let o =
                crate::observe::observe(model, &self.compartments, &data.pos, &data.vel, 0.0, None);
            let litres = 1e3;
            [o.thorax * litres, o.abdomen * litres, o.trunk * litres]
        })
    }
}

impl Torso {
    /// Why the current state is unphysical: a non-finite state variable, or a cavity volume
    /// outside its [`cavity_bounds`] x its rest value ([`Compiled::rest_volumes`]); `None`
    /// when it is within bounds.
    pub fn physiology_violation(&mut self) -> Result<Option<String>> {
        let bounds = cavity_bounds(&self.config().subject);
        if let Some(i) = self.state().iter().position(|v| !v.is_finite()) {
            return Ok(Some(format!("state variable {i} is not finite")));
        }
        let rest = self.compiled().rest_volumes();
        for (((q, name), r), (lo, hi)) in CHECKED_VOLUMES.into_iter().zip(rest).zip(bounds) {
            let v = self.read(q)?;
            let ratio = v / r;
            if !(ratio.is_finite() && (lo..=hi).contains(&ratio)) {
                return Ok(Some(format!(
                    "{name} = {v:.4} L is {ratio:.3} x its rest value {r:.4} L, outside the physiological bounds [{lo:.3}, {hi:.3}] x rest (the subject's residual volume to total lung capacity, with room)"
                )));
            }
        }
        Ok(None)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn subjects(ages: &[f64], statures: &[f64]) -> Vec<Subject> {
        use crate::anatomy::Sex;
        let mut out = Vec::new();
        for sex in [Sex::Male, Sex::Female] {
            for &age in ages {
                for &stature in statures {
                    out.push(Subject {
                        sex,
                        age,
                        stature,
                        ..Subject::default()
                    });
                }
            }
        }
        out
    }

    /// Over the corners of the subject ranges the thorax's bounds hold the subject's RV and TLC
    /// (relative to FRC) with [`CAPACITY_SLACK`] to spare and are never narrower than
    /// [`CAVITY_BOUNDS`]; the abdomen and trunk keep [`CAVITY_BOUNDS`]; the short young woman
    /// of the module's example needs the wider bound.
    #[test]
    fn cavity_bounds_hold_the_subjects_capacities() {
        use crate::anatomy::{SUBJECT_RANGES, Sex};
        let mut widened = 0;
        let ages = [SUBJECT_RANGES[0].1, 30.0, SUBJECT_RANGES[0].2];
        let statures = [SUBJECT_RANGES[1].1, 1.6, 1.75, SUBJECT_RANGES[1].2];
        for s in subjects(&ages, &statures) {
            let (rv, tlc) = capacity_ratios(&s);
            let [thorax, abdomen, trunk] = cavity_bounds(&s);
            assert!(thorax.0 <= (1.0 - CAPACITY_SLACK) * rv + 1e-12, "{s:?}");
            assert!(thorax.1 >= (1.0 + CAPACITY_SLACK) * tlc - 1e-12, "{s:?}");
            assert!(thorax.0 <= CAVITY_BOUNDS.0 && thorax.1 >= CAVITY_BOUNDS.1);
            assert!(thorax.0 > 0.3 && thorax.1 < 2.7, "{s:?}: {thorax:?}");
            assert_eq!((abdomen, trunk), (CAVITY_BOUNDS, CAVITY_BOUNDS));
            if thorax != CAVITY_BOUNDS {
                widened += 1;
            }
        }
        assert!(widened > 0);
        let woman = Subject {
            sex: Sex::Female,
            age: 18.0,
            stature: 1.6,
            ..Subject::default()
        };
        let (rv, _) = capacity_ratios(&woman);
        assert!(rv < CAVITY_BOUNDS.0, "RV/FRC {rv}");
        assert!(cavity_bounds(&woman)[0].0 < rv);
    }
}
