//! The airway between the alveoli and the mouth: open, it carries the airflow through the
//! airway resistance R, so the alveolar pressure is P_alv = P_ao - R dV/dt; occluded (a shutter
//! at the mouth, as in the measurement of maximal inspiratory pressure), no gas passes, and
//! the lungs' gas is compressed or rarefied at body temperature by the thoracic wall alone.
//!
//! The occluded gas obeys Boyle's law isothermally (the alveolar gas stays at body
//! temperature: the lungs' exchange surface and its blood are its thermostat, which is what
//! the body plethysmograph's isothermal reading of thoracic gas volume rests on; DuBois,
//! Botelho, Bedell, Marshall & Comroe 1956, J Clin Invest 35:322). The gas is saturated
//! with water vapour, whose partial pressure at 37 degC stays at 47 mmHg whatever the volume
//! (vapour condenses or evaporates), so the law holds for the dry gas:
//!
//! (P_B + P_alv - P_H2O) V = (P_B + P_alv,0 - P_H2O) V_0 = n,
//!
//! with P_B the barometric pressure, V the lungs' gas volume (the model's lung volume: the
//! volumes of the reference equations, FRC and RV, are gas volumes) and V_0, P_alv,0 the gas
//! volume and the alveolar pressure at the moment of occlusion. The mouth, between the lips
//! and the shutter, is then at the alveolar pressure: no gas flows, so nothing drops along
//! the airway.

use super::{Activations, Structure};

/// Barometric pressure [Pa]: one standard atmosphere, 101 325 Pa = 1033 cmH2O (the
/// International Standard Atmosphere at sea level, ISO 2533:1975; 1 cmH2O = 98.0665 Pa).
/// Source: ISO 2533:1975, sea-level pressure of the standard atmosphere, 101 325 Pa.
pub const BAROMETRIC_PRESSURE: f64 = 101_325.0;

/// Partial pressure of water vapour in the saturated alveolar gas at 37 degC [Pa]: 47 mmHg =
/// 6.27 kPa (West & Luks, Respiratory Physiology: The Essentials, 10th ed. 2016, ch. 1 and
/// Appendix; 1 mmHg = 133.322 Pa).
/// Source: West & Luks 2016, saturated water vapour pressure at 37 degC, 47 mmHg.
pub const WATER_VAPOUR_PRESSURE: f64 = 47.0 * 133.322;

/// The pressure of the dry gas at the body surface's pressure [Pa]: P_B - P_H2O.
/// Derived: [`BAROMETRIC_PRESSURE`] less [`WATER_VAPOUR_PRESSURE`].
pub const DRY_GAS_PRESSURE: f64 = BAROMETRIC_PRESSURE - WATER_VAPOUR_PRESSURE;

/// The dry gas content of lungs holding `gas_volume` [m^3] at alveolar pressure `alveolar`
/// (relative to the body surface) [Pa]: n = (P_B + P_alv - P_H2O) V [Pa m^3], the constant of
/// Boyle's law while the airway is occluded ([`Activations::occlusion`]).
pub fn gas_content(gas_volume: f64, alveolar: f64) -> f64 {
    (DRY_GAS_PRESSURE + alveolar) * gas_volume
}

/// The alveolar pressure (relative to the body surface) [Pa] of the dry gas content `content`
/// [Pa m^3] in `gas_volume` [m^3]: P_alv = n / V - (P_B - P_H2O).
pub fn occluded_pressure(content: f64, gas_volume: f64) -> f64 {
    content / gas_volume - DRY_GAS_PRESSURE
}

/// The alveolar pressure of the airway under `act` and its derivatives.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Alveolar {
    /// Alveolar pressure relative to the body surface [Pa].
    pub pressure: f64,
    /// Its derivative with respect to the thoracic mesh volume [Pa/m^3] (0 with the airway
    /// open, -n / V^2 occluded).
    pub per_volume: f64,
    /// Its derivative with respect to the thoracic volume's rate [Pa s/m^3] (-R with the
    /// airway open, 0 occluded: no airflow).
    pub per_rate: f64,
}

impl Structure {
    /// The lungs' gas volume [m^3] held by a thoracic mesh volume `thorax_mesh` [m^3]: the
    /// mesh volume less the dome's faceting and the non-lung volume (the observed lung
    /// volume, [`crate::observe::Observation::lung`]).
    pub fn gas_volume(&self, thorax_mesh: f64) -> f64 {
        thorax_mesh - self.dome_faceting_volume - self.non_lung_volume
    }

    /// The alveolar pressure under `act` at thoracic mesh volume `thorax_mesh` [m^3] changing
    /// at `rate` [m^3/s]: P_ao - R rate with the airway open, Boyle's law on the dry gas
    /// content of [`Activations::occlusion`] with it occluded.
    pub fn alveolar(&self, act: &Activations, thorax_mesh: f64, rate: f64) -> Alveolar {
        match act.occlusion {
            None => Alveolar {
                pressure: act.airway_opening - self.airway_resistance * rate,
                per_volume: 0.0,
                per_rate: -self.airway_resistance,
            },
            Some(content) => {
                let v = self.gas_volume(thorax_mesh);
                Alveolar {
                    pressure: occluded_pressure(content, v),
                    per_volume: -content / (v * v),
                    per_rate: 0.0,
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn boyle_holds_the_product_of_dry_gas_pressure_and_volume() {
        // 3 L at the surface's pressure, compressed by 1 %: the absolute dry gas pressure
        // rises by the inverse ratio
        let v0 = 3e-3;
        let n = gas_content(v0, 0.0);
        let p = occluded_pressure(n, 0.99 * v0);
        let expected = DRY_GAS_PRESSURE / 0.99 - DRY_GAS_PRESSURE;
        assert!(
            (p - expected).abs() < 1e-9 * DRY_GAS_PRESSURE,
            "{p} {expected}"
        );
        // and the same content read back where it started
        assert!(occluded_pressure(n, v0).abs() < 1e-9);
        // 1033 cmH2O of barometric pressure (the standard atmosphere)
        assert!((BAROMETRIC_PRESSURE / 98.0665 - 1033.2).abs() < 0.05);
    }
}
