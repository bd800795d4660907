//! Trunk dimensions of a [`Subject`] predicted from the ANSUR II anthropometric survey.
//!
//! Source: ANSUR II (Gordon et al. 2014, "2012 Anthropometric Survey of U.S. Army Personnel"),
//! public release; linear regressions fitted on 4082 men and 1986 women:
//! `dim_mm = b0 + b_stature * stature_mm + b_weight * mass_kg + b_age * age_yr`.

use crate::anatomy::{Sex, Subject};
use crate::{Error, Result};

/// One regression row of the ANSUR II table (millimetres, kilograms, years).
#[derive(Clone, Copy, Debug)]
struct Regression {
    dimension: &'static str,
    b0: f64,
    b_stature: f64,
    b_weight: f64,
    b_age: f64,
    #[allow(dead_code)]
    resid_sd: f64,
}

/// ANSUR II regressions for men (n = 4082).
/// Source: ANSUR II (Gordon et al. 2014); the coefficients of
/// data/anatomy/torso_anthropometry_ansur2.csv.
const MALE: [Regression; 20] = [
    Regression {
        dimension: "chestcircumference",
        b0: 981.93,
        b_stature: -0.2687,
        b_weight: 6.025,
        b_age: 1.111,
        resid_sd: 30.9,
    },
    Regression {
        dimension: "chestdepth",
        b0: 240.36,
        b_stature: -0.0821,
        b_weight: 1.717,
        b_age: 0.362,
        resid_sd: 12.0,
    },
    Regression {
        dimension: "chestbreadth",
        b0: 197.35,
        b_stature: 0.0072,
        b_weight: 0.866,
        b_age: 0.180,
        resid_sd: 12.8,
    },
    Regression {
        dimension: "chestheight",
        b0: -82.78,
        b_stature: 0.7829,
        b_weight: 0.045,
        b_age: -0.164,
        resid_sd: 18.1,
    },
    Regression {
        dimension: "waistcircumference",
        b0: 927.56,
        b_stature: -0.3961,
        b_weight: 7.587,
        b_age: 1.985,
        resid_sd: 40.7,
    },
    Regression {
        dimension: "waistdepth",
        b0: 262.02,
        b_stature: -0.1368,
        b_weight: 2.236,
        b_age: 0.823,
        resid_sd: 15.0,
    },
    Regression {
        dimension: "waistbreadth",
        b0: 294.18,
        b_stature: -0.0984,
        b_weight: 2.314,
        b_age: 0.241,
        resid_sd: 15.8,
    },
    Regression {
        dimension: "waistheightomphalion",
        b0: -189.97,
        b_stature: 0.7389,
        b_weight: -0.495,
        b_age: -0.294,
        resid_sd: 20.5,
    },
    Regression {
        dimension: "buttockcircumference",
        b0: 831.67,
        b_stature: -0.1496,
        b_weight: 5.436,
        b_age: -0.474,
        resid_sd: 26.0,
    },
    Regression {
        dimension: "hipbreadth",
        b0: 236.23,
        b_stature: -0.0080,
        b_weight: 1.470,
        b_age: -0.075,
        resid_sd: 12.8,
    },
    Regression {
        dimension: "bicristalbreadth",
        b0: 111.16,
        b_stature: 0.0613,
        b_weight: 0.700,
        b_age: -0.108,
        resid_sd: 12.4,
    },
    Regression {
        dimension: "biacromialbreadth",
        b0: 210.34,
        b_stature: 0.0893,
        b_weight: 0.608,
        b_age: -0.117,
        resid_sd: 14.4,
    },
    Regression {
        dimension: "cervicaleheight",
        b0: -64.85,
        b_stature: 0.8869,
        b_weight: 0.224,
        b_age: 0.179,
        resid_sd: 10.6,
    },
    Regression {
        dimension: "suprasternaleheight",
        b0: -80.00,
        b_stature: 0.8457,
        b_weight: 0.324,
        b_age: 0.188,
        resid_sd: 10.7,
    },
    Regression {
        dimension: "acromialheight",
        b0: -107.59,
        b_stature: 0.8590,
        b_weight: 0.350,
        b_age: 0.322,
        resid_sd: 15.1,
    },
    Regression {
        dimension: "iliocristaleheight",
        b0: -177.68,
        b_stature: 0.7106,
        b_weight: -0.206,
        b_age: 0.297,
        resid_sd: 21.4,
    },
    Regression {
        dimension: "abdominalextensiondepthsitting",
        b0: 294.21,
        b_stature: -0.1540,
        b_weight: 2.404,
        b_age: 0.838,
        resid_sd: 16.7,
    },
    Regression {
        dimension: "sittingheight",
        b0: 228.97,
        b_stature: 0.3883,
        b_weight: 0.175,
        b_age: -0.250,
        resid_sd: 22.2,
    },
    Regression {
        dimension: "neckcircumferencebase",
        b0: 367.90,
        b_stature: -0.0353,
        b_weight: 1.434,
        b_age: 0.202,
        resid_sd: 16.2,
    },
    Regression {
        dimension: "tenthribheight",
        b0: -136.33,
        b_stature: 0.7070,
        b_weight: 0.171,
        b_age: 0.022,
        resid_sd: 20.2,
    },
];
/// ANSUR II regressions for women (n = 1986).
/// Source: ANSUR II (Gordon et al. 2014); the coefficients of
/// data/anatomy/torso_anthropometry_ansur2.csv.
const FEMALE: [Regression; 20] = [
    Regression {
        dimension: "chestcircumference",
        b0: 934.55,
        b_stature: -0.3054,
        b_weight: 6.985,
        b_age: 1.255,
        resid_sd: 41.4,
    },
    Regression {
        dimension: "chestdepth",
        b0: 263.36,
        b_stature: -0.1102,
        b_weight: 2.274,
        b_age: 0.325,
        resid_sd: 15.0,
    },
    Regression {
        dimension: "chestbreadth",
        b0: 204.95,
        b_stature: -0.0123,
        b_weight: 1.231,
        b_age: 0.032,
        resid_sd: 13.1,
    },
    Regression {
        dimension: "chestheight",
        b0: -133.89,
        b_stature: 0.8249,
        b_weight: -0.359,
        b_age: -0.465,
        resid_sd: 21.6,
    },
    Regression {
        dimension: "waistcircumference",
        b0: 963.36,
        b_stature: -0.4501,
        b_weight: 8.817,
        b_age: 1.142,
        resid_sd: 47.6,
    },
    Regression {
        dimension: "waistdepth",
        b0: 300.05,
        b_stature: -0.1738,
        b_weight: 2.729,
        b_age: 0.383,
        resid_sd: 16.3,
    },
    Regression {
        dimension: "waistbreadth",
        b0: 282.96,
        b_stature: -0.1083,
        b_weight: 2.727,
        b_age: 0.291,
        resid_sd: 18.0,
    },
    Regression {
        dimension: "waistheightomphalion",
        b0: -211.34,
        b_stature: 0.7599,
        b_weight: -0.562,
        b_age: -0.276,
        resid_sd: 19.9,
    },
    Regression {
        dimension: "buttockcircumference",
        b0: 843.88,
        b_stature: -0.1771,
        b_weight: 6.846,
        b_age: 0.068,
        resid_sd: 29.5,
    },
    Regression {
        dimension: "hipbreadth",
        b0: 258.98,
        b_stature: -0.0301,
        b_weight: 2.090,
        b_age: 0.077,
        resid_sd: 14.9,
    },
    Regression {
        dimension: "bicristalbreadth",
        b0: 155.48,
        b_stature: 0.0138,
        b_weight: 1.309,
        b_age: 0.233,
        resid_sd: 16.1,
    },
    Regression {
        dimension: "biacromialbreadth",
        b0: 139.28,
        b_stature: 0.1252,
        b_weight: 0.398,
        b_age: -0.164,
        resid_sd: 14.7,
    },
    Regression {
        dimension: "cervicaleheight",
        b0: -85.63,
        b_stature: 0.9064,
        b_weight: 0.067,
        b_age: 0.023,
        resid_sd: 10.5,
    },
    Regression {
        dimension: "suprasternaleheight",
        b0: -68.04,
        b_stature: 0.8439,
        b_weight: 0.329,
        b_age: 0.041,
        resid_sd: 10.5,
    },
    Regression {
        dimension: "acromialheight",
        b0: -79.10,
        b_stature: 0.8558,
        b_weight: 0.255,
        b_age: 0.111,
        resid_sd: 13.4,
    },
    Regression {
        dimension: "iliocristaleheight",
        b0: -155.37,
        b_stature: 0.7031,
        b_weight: 0.058,
        b_age: 0.079,
        resid_sd: 20.0,
    },
    Regression {
        dimension: "abdominalextensiondepthsitting",
        b0: 301.85,
        b_stature: -0.1634,
        b_weight: 2.720,
        b_age: 0.333,
        resid_sd: 16.7,
    },
    Regression {
        dimension: "sittingheight",
        b0: 224.99,
        b_stature: 0.3899,
        b_weight: 0.043,
        b_age: -0.217,
        resid_sd: 21.2,
    },
    Regression {
        dimension: "neckcircumferencebase",
        b0: 266.79,
        b_stature: 0.0102,
        b_weight: 1.264,
        b_age: 0.071,
        resid_sd: 13.4,
    },
    Regression {
        dimension: "tenthribheight",
        b0: -124.75,
        b_stature: 0.7202,
        b_weight: 0.122,
        b_age: -0.005,
        resid_sd: 17.2,
    },
];

/// Trunk dimensions of one subject, in metres, predicted by the ANSUR II regressions.
/// Heights are above the floor; breadths and depths are full (not half) extents.
#[derive(Clone, Debug, PartialEq)]
pub struct TorsoDimensions {
    /// Chest circumference at the nipple (bust) level.
    pub chest_circumference: f64,
    /// Chest depth (back to front) at the nipple level.
    pub chest_depth: f64,
    /// Chest breadth at the nipple level, measured between the arms.
    pub chest_breadth: f64,
    /// Height of the nipple (bust) level.
    pub chest_height: f64,
    /// Waist circumference at the omphalion (umbilicus).
    pub waist_circumference: f64,
    /// Waist depth at the omphalion.
    pub waist_depth: f64,
    /// Waist breadth at the omphalion.
    pub waist_breadth: f64,
    /// Height of the omphalion (umbilicus).
    pub omphalion_height: f64,
    /// Buttock circumference (maximal posterior protrusion of the buttocks).
    pub buttock_circumference: f64,
    /// Hip breadth, standing.
    pub hip_breadth: f64,
    /// Biacromial breadth (between the acromia).
    pub biacromial_breadth: f64,
    /// Height of the cervicale (C7 spinous process).
    pub cervicale_height: f64,
    /// Height of the suprasternale (jugular notch).
    pub suprasternale_height: f64,
    /// Height of the acromion.
    pub acromial_height: f64,
    /// Height of the iliac crest.
    pub iliocristale_height: f64,
    /// Neck circumference at its base.
    pub neck_base_circumference: f64,
    /// Height of the lowest point of the tenth rib.
    pub tenth_rib_height: f64,
}

impl TorsoDimensions {
    /// Predicts the dimensions of `subject` (validated first) from the ANSUR II regressions of
    /// its sex.
    pub fn from_subject(subject: &Subject) -> Result<Self> {
        subject.validate()?;
        let table: &[Regression] = match subject.sex {
            Sex::Male => &MALE,
            Sex::Female => &FEMALE,
        };
        let predict = |name: &str| -> Result<f64> {
            let r = table
                .iter()
                .find(|r| r.dimension == name)
                .ok_or_else(|| Error::State(format!("ANSUR II table has no dimension `{name}`")))?;
            let mm = r.b0
                + r.b_stature * subject.stature * 1000.0
                + r.b_weight * subject.mass
                + r.b_age * subject.age;
            if !(mm.is_finite() && mm > 0.0) {
                return Err(Error::invalid(
                    "subject",
                    format!("{subject:?}"),
                    format!("a subject whose predicted {name} is positive (got {mm:.1} mm)"),
                ));
            }
            Ok(mm / 1000.0)
        };
        Ok(TorsoDimensions {
            chest_circumference: predict("chestcircumference")?,
            chest_depth: predict("chestdepth")?,
            chest_breadth: predict("chestbreadth")?,
            chest_height: predict("chestheight")?,
            waist_circumference: predict("waistcircumference")?,
            waist_depth: predict("waistdepth")?,
            waist_breadth: predict("waistbreadth")?,
            omphalion_height: predict("waistheightomphalion")?,
            buttock_circumference: predict("buttockcircumference")?,
            hip_breadth: predict("hipbreadth")?,
            biacromial_breadth: predict("biacromialbreadth")?,
            cervicale_height: predict("cervicaleheight")?,
            suprasternale_height: predict("suprasternaleheight")?,
            acromial_height: predict("acromialheight")?,
            iliocristale_height: predict("iliocristaleheight")?,
            neck_base_circumference: predict("neckcircumferencebase")?,
            tenth_rib_height: predict("tenthribheight")?,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn default_man_matches_worked_example() {
        // physiology reference, "Torso surface": man 1.75 m / 75 kg / 30 y.
        let d = TorsoDimensions::from_subject(&Subject::default()).unwrap();
        let close = |a: f64, mm: f64| (a * 1000.0 - mm).abs() < 1.0;
        assert!(
            close(d.chest_circumference, 997.0),
            "{}",
            d.chest_circumference
        );
        assert!(close(d.chest_depth, 236.0));
        assert!(close(d.chest_breadth, 280.0));
        assert!(close(d.waist_circumference, 863.0));
        assert!(close(d.waist_depth, 215.0));
        assert!(close(d.waist_breadth, 303.0));
        assert!(close(d.suprasternale_height, 1430.0));
        assert!(close(d.chest_height, 1286.0));
        assert!(close(d.tenth_rib_height, 1114.0));
        assert!(close(d.omphalion_height, 1057.0));
    }
}
