//! The physiological figures of issue 35 (`bench::physiology`, `torso bench physiology`),
//! each cited bound a test, on the default subject at the default level of detail. None of
//! these figures was calibrated: the quiet drive's amplitudes were set to a tidal volume
//! (docs/drive.md), which is therefore not tested here; compliances, shares, excursions per
//! litre, maximal volumes and pressures and a paralysed side's motion are outcomes.
//!
//! The bounds are the cited ones, never widened; those the model misses today are ignored
//! with the figure measured (`cargo test --release --test physiology_figures -- --ignored
//! --nocapture` measures them again).

use breathing_torso::anatomy::Posture;
use breathing_torso::bench::physiology::*;
use breathing_torso::dynamics::muscle::MuscleLaw;
use breathing_torso::model::Config;

/// Level of detail of every measurement (the default).
const LOD: u32 = 1;

fn within(value: f64, (lo, hi): (f64, f64)) -> bool {
    value >= lo && value <= hi
}

fn compliance(posture: Posture) {
    let s = pressure_step(posture, LOD, MuscleLaw::Thesis).unwrap();
    println!(
        "{posture:?}: rest {:.3} L, under {PRESSURE_STEP} cmH2O {:.3} L, C_rs {:.4} L/cmH2O",
        s.rest, s.held, s.compliance
    );
    assert!(
        within(s.compliance, SYSTEM_COMPLIANCE),
        "{posture:?}: C_rs {} L/cmH2O against {SYSTEM_COMPLIANCE:?}",
        s.compliance
    );
}

#[test]
#[ignore = "issue 35: respiratory-system compliance standing measured 0.062 L/cmH2O against 0.08-0.12"]
fn system_compliance_standing() {
    compliance(Posture::Standing);
}

#[test]
#[ignore = "issue 35: respiratory-system compliance supine measured 0.069 L/cmH2O against 0.08-0.12"]
fn system_compliance_supine() {
    compliance(Posture::Supine);
}

fn quiet(posture: Posture, left_gain: f64) -> QuietBreath {
    let q = quiet_breath(posture, LOD, MuscleLaw::Thesis, left_gain).unwrap();
    println!("{posture:?}, left diaphragm gain {left_gain}: {q:?}");
    q
}

#[test]
fn quiet_pleural_swing() {
    let q = quiet(Posture::Standing, 1.0);
    assert!(
        within(q.pleural_swing, PLEURAL_SWING),
        "pleural swing {} cmH2O against {PLEURAL_SWING:?}",
        q.pleural_swing
    );
}

#[test]
#[ignore = "issue 35: upright rib-cage share of quiet tidal volume measured 44.1 % against >= 50 % (46.2 % before the external intercostals' rostrocaudal drive)"]
fn upright_rib_cage_share() {
    let q = quiet(Posture::Standing, 1.0);
    assert!(
        within(q.rib_cage_share, UPRIGHT_RIB_CAGE_SHARE),
        "rib-cage share {}",
        q.rib_cage_share
    );
}

#[test]
fn supine_abdominal_share() {
    let q = quiet(Posture::Supine, 1.0);
    let abdominal = 1.0 - q.rib_cage_share;
    assert!(
        within(abdominal, SUPINE_ABDOMINAL_SHARE),
        "supine abdominal share {abdominal} against {SUPINE_ABDOMINAL_SHARE:?}"
    );
}

#[test]
fn quiet_excursion_per_litre() {
    let q = quiet(Posture::Standing, 1.0);
    assert!(
        within(q.excursion_per_litre, EXCURSION_PER_LITRE),
        "{} cm/L against {EXCURSION_PER_LITRE:?}",
        q.excursion_per_litre
    );
}

fn full() -> FullInspiration {
    let f = full_inspiration(Posture::Standing, LOD, MuscleLaw::Thesis).unwrap();
    println!("{f:?}");
    f
}

#[test]
#[ignore = "issue 35: full inspiratory activation with the airway open measured 2.40 L above FRC against 2.9-4.3 L"]
fn full_inspiration_volume() {
    let f = full();
    assert!(
        within(f.added, INSPIRATORY_CAPACITY),
        "{} L against {INSPIRATORY_CAPACITY:?}",
        f.added
    );
}

#[test]
#[ignore = "issue 35: M-mode excursion of the posterior right dome in a full inspiration measured 3.41 cm against >= 4.7 cm (2.54 before the external intercostals' rostrocaudal drive; the hill law 4.99, met)"]
fn deep_m_mode_excursion() {
    let f = full();
    assert!(
        within(f.m_mode_excursion, DEEP_EXCURSION_MEN),
        "{} cm against {DEEP_EXCURSION_MEN:?}",
        f.m_mode_excursion
    );
}

#[test]
fn the_middle_of_the_dome_descends_more_than_its_front() {
    let [_, middle, anterior] = full()
        .regional_excursion
        .expect("every line meets the dome");
    assert!(
        within(middle - anterior, REGIONAL_GRADIENT),
        "middle third {middle} cm, anterior third {anterior} cm (Gierada et al. 1995)"
    );
}

#[test]
#[ignore = "issue 35: in a full inspiration the right dome's posterior third descends 3.41 cm and its middle third 4.83 cm (the hill law's posterior less middle -0.024 cm), against the posterior's being the largest (Gierada et al. 1995); at level 1, measured with the external intercostals' rostrocaudal drive (before it: -1.50 cm, and -2.94 / -0.92 cm at levels 0 / 2)"]
fn the_back_of_the_dome_descends_most() {
    let [posterior, middle, _] = full()
        .regional_excursion
        .expect("every line meets the dome");
    assert!(
        within(posterior - middle, REGIONAL_GRADIENT),
        "posterior third {posterior} cm, middle third {middle} cm (Gierada et al. 1995)"
    );
}

/// The ribs turn no more in a full inspiratory activation than from FRC to TLC (Wilson et al.
/// 1987, CT: rib 3 11 deg pump-handle and 13 bucket-handle, rib 7 7 and 10; the effort adds
/// less than the inspiratory capacity). Measured: rib 3 5.5 / 6.4 deg, rib 7 2.8 / 4.7 deg.
#[test]
fn ribs_turn_no_more_than_to_tlc() {
    let f = full();
    for (rib, pump, bucket) in RIB_ROTATION_TO_TLC {
        let (p, b) = f.rib_rotation[rib as usize - 1];
        assert!(
            within(p, (0.0, pump)) && within(b, (0.0, bucket)),
            "rib {rib}: pump {p:.1} deg (at most {pump}), bucket {b:.1} deg (at most {bucket})"
        );
    }
}

/// The reference of the default man (30 y, 75 kg): 126 - 1.028 x 30 + 0.343 x 75 = 120.885
/// cmH2O, +- 1.96 x 22.4 (Harik-Khan, Wise & Fozard 1998).
#[test]
fn pimax_reference_of_the_default_man() {
    let (lo, hi) = pimax_range(&Config::default().subject);
    assert!((lo - 76.981).abs() < 1e-9 && (hi - 164.789).abs() < 1e-9);
}

/// Full inspiratory activation against the airway occluded after a maximal expiration,
/// through the FMU's `airway.occluded` input; the largest 1-s mean of `pressure.mouth` against
/// the default man's reference range (Harik-Khan, Wise & Fozard 1998; ATS/ERS 2002).
#[test]
fn maximal_inspiratory_pressure() {
    let o = occluded_inspiration(Posture::Standing, LOD, MuscleLaw::Thesis).unwrap();
    println!("{o:?}");
    // the occlusion holds: no gas passes (Boyle's law on the outputs within their rounding)
    assert_eq!(o.occluded_flow, 0.0);
    assert!((o.gas_ratio - 1.0).abs() < 1e-6, "{}", o.gas_ratio);
    let range = pimax_range(&Config::default().subject);
    assert!(
        within(-o.mouth_pressure, range),
        "{} cmH2O against {range:?}",
        o.mouth_pressure
    );
}

#[test]
#[ignore = "issue 35: a paralysed left hemidiaphragm measured moving 0.013 cm caudally in quiet \
            inspiration (its cranial displacement's correlation with lung volume -0.27) instead \
            of rising"]
fn paralysed_hemidiaphragm_rises() {
    let q = quiet(Posture::Standing, 0.0);
    assert!(
        q.hemidiaphragm_motion[0] > 0.0 && q.left_correlation > 0.0,
        "paralysed left side moves {} cm (cranial +), correlation {}",
        q.hemidiaphragm_motion[0],
        q.left_correlation
    );
}

#[test]
fn healthy_hemidiaphragm_descends_beside_a_paralysed_one() {
    let q = quiet(Posture::Standing, 0.0);
    assert!(
        q.hemidiaphragm_motion[1] < 0.0,
        "healthy right side moves {} cm (cranial +)",
        q.hemidiaphragm_motion[1]
    );
}

#[test]
fn paralysed_side_share() {
    let q = quiet(Posture::Standing, 0.0);
    assert!(
        within(q.left_share, PARALYSED_SIDE_SHARE),
        "paralysed side's share {} against {PARALYSED_SIDE_SHARE:?}",
        q.left_share
    );
}

fn sniffed() -> Sniff {
    let s = sniff(Posture::Standing, LOD, MuscleLaw::Thesis, 0.0).unwrap();
    println!("sniff, left diaphragm paralysed: {s:?}");
    s
}

#[test]
#[ignore = "issue 35: in a sniff a paralysed left hemidiaphragm measured moving 0.10 cm caudally \
            (the healthy right 3.72 cm) instead of rising"]
fn paralysed_hemidiaphragm_rises_in_a_sniff() {
    let s = sniffed();
    assert!(
        s.hemidiaphragm_motion[0] > 0.0,
        "paralysed left side moves {} cm (cranial +)",
        s.hemidiaphragm_motion[0]
    );
}

#[test]
fn healthy_hemidiaphragm_descends_in_a_sniff_beside_a_paralysed_one() {
    let s = sniffed();
    assert!(
        s.hemidiaphragm_motion[1] < 0.0,
        "healthy right side moves {} cm (cranial +)",
        s.hemidiaphragm_motion[1]
    );
}

/// A maximal sniff's transdiaphragmatic pressure exceeds 38 cmH2O from any volume below 95 %
/// of TLC (Wanke et al. 1990: 68 (SD 15) cmH2O there, 163 (18) at RV).
#[test]
fn sniff_transdiaphragmatic_pressure() {
    let s = sniff(Posture::Standing, LOD, MuscleLaw::Thesis, 1.0).unwrap();
    println!("{s:?}");
    assert!(
        within(s.transdiaphragmatic, SNIFF_TRANSDIAPHRAGMATIC),
        "{} cmH2O against {SNIFF_TRANSDIAPHRAGMATIC:?}",
        s.transdiaphragmatic
    );
}

/// `torso bench physiology --json` at level 0 prints every figure with a finite value, its
/// range and whether the value lies in it; a level of detail out of range is refused by name.
#[test]
fn bench_command_prints_json() {
    use std::process::Command;
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["bench", "physiology", "--lod", "0", "--json"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    let figures = v["figures"].as_array().unwrap();
    assert_eq!(figures.len(), 21, "{v}");
    for f in figures {
        let value = f["value"].as_f64().unwrap();
        // an open end of a range is written null
        let lo = f["range"][0].as_f64().unwrap_or(f64::NEG_INFINITY);
        let hi = f["range"][1].as_f64().unwrap_or(f64::INFINITY);
        assert!(value.is_finite(), "{f}");
        assert_eq!(
            f["met"].as_bool().unwrap(),
            value >= lo && value <= hi,
            "{f}"
        );
        assert!(!f["source"].as_str().unwrap().is_empty());
    }
    // every figure is measured: none failed
    assert_eq!(v["failed"].as_array().map(Vec::len), Some(0), "{v}");
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["bench", "physiology", "--lod", "3"])
        .output()
        .unwrap();
    assert!(!out.status.success());
    assert!(String::from_utf8_lossy(&out.stderr).contains("level of detail"));
}
