//! The sternocleidomastoids, the accessory inspiratory muscles added after the thesis's eight
//! groups: present at every level of detail with their cited force (Stemper et al. 2010's
//! cross-section x Persad et al. 2024's specific tension), pulling the sternum cranially and
//! inflating the lungs when activated alone (as they lift the sternum with the head held;
//! Raper et al. 1966), silent in the quiet and forced drives, and reachable as the FMU's
//! `activation.sternocleidomastoids` input. Alone against the occluded airway they give about
//! twice the mouth pressure estimated for people (ignored tests with the figures).

use breathing_torso::anatomy::{Anatomy, Body, MuscleGroup, SCM_FORCE_PER_SIDE, Side, Subject};
use breathing_torso::dynamics::Params;
use breathing_torso::dynamics::muscle::MuscleLaw;
use breathing_torso::model::{Config, Drive};
use breathing_torso::{Quantity, Torso};

const SCM: MuscleGroup = MuscleGroup::Sternocleidomastoids;

/// At every level of detail each side has at least one element per head, from a fixed
/// mastoid origin above the sternum to the manubrium and to rib 1, and the side's elements
/// carry the cited 137 N together.
#[test]
fn every_level_has_both_heads_with_the_cited_force() {
    for lod in 0..=2 {
        let a = Anatomy::build(&Subject::default(), lod).unwrap();
        for side in [Side::Right, Side::Left] {
            let elements: Vec<_> = a
                .muscles
                .iter()
                .filter(|m| m.group == SCM && m.side == Some(side))
                .collect();
            let total: f64 = elements.iter().map(|m| m.max_force).sum();
            println!(
                "level {lod}, {side:?}: {} elements, {total} N",
                elements.len()
            );
            assert!(
                (total - SCM_FORCE_PER_SIDE).abs() < 1e-9,
                "level {lod} {side:?}: {total} N"
            );
            let (mut sternal, mut clavicular) = (0, 0);
            for m in &elements {
                let origin = a.anchors[m.path[0] as usize];
                let insertion = a.anchors[*m.path.last().unwrap() as usize];
                assert_eq!(origin.body, Body::Ground);
                // the mastoid lies above the jugular notch and on the element's side
                assert!(origin.rest.y > a.sternum.jugular.y + 0.05);
                assert!(side.sign() * origin.rest.z > 0.03);
                match insertion.body {
                    Body::Sternum => sternal += 1,
                    Body::Rib(r) => {
                        assert_eq!(a.ribs[r as usize].level, 1, "clavicular head on rib 1");
                        clavicular += 1;
                    }
                    other => panic!("insertion on {other:?}"),
                }
            }
            assert!(sternal >= 1 && clavicular >= 1, "level {lod} {side:?}");
        }
    }
}

fn standing(law: MuscleLaw) -> Config {
    let mut c = Config::default();
    c.params = Some(Params::for_posture_and_law(c.subject.posture, law));
    c.drive = Drive::default();
    c
}

/// Activated alone, with the drive off, the sternocleidomastoids lift the sternum cranially
/// and inflate the lungs, under both muscle laws.
#[test]
fn activated_alone_they_lift_the_sternum_and_inflate() {
    for law in [MuscleLaw::Thesis, MuscleLaw::Hill] {
        let mut torso = Torso::new(standing(law)).unwrap();
        let v0 = torso.read(Quantity::LungVolume).unwrap();
        torso.set_activation(SCM, 1.0).unwrap();
        torso.advance_to(3.0).unwrap();
        let dv = torso.read(Quantity::LungVolume).unwrap() - v0;
        let up = torso.read(Quantity::SternumDisplacement(1)).unwrap();
        println!(
            "{law:?}: sternocleidomastoids at 1: lung volume {dv:+.4} L, sternum {:+.2} mm cranially",
            up * 1e3
        );
        assert!(up > 0.0, "{law:?}: the sternum moved {up} m cranially");
        assert!(dv > 0.0, "{law:?}: the lungs changed by {dv} L");
    }
}

/// No breathing drive recruits them: the quiet and forced drives give 0 at every phase, and
/// a quiet run applies 0 to them.
#[test]
fn the_drives_leave_them_silent() {
    for drive in [
        Drive::quiet(),
        Drive::forced(),
        Drive::quiet_for(MuscleLaw::Hill),
    ] {
        for k in 0..100 {
            let t = k as f64 * 0.05;
            assert_eq!(drive.activation(SCM, t), 0.0);
        }
    }
    let config = Config {
        drive: Drive::quiet(),
        ..Config::default()
    };
    let mut torso = Torso::new(config).unwrap();
    let mut diaphragm = 0.0f64;
    for k in 1..=16 {
        let t = 0.25 * k as f64;
        torso.advance_to(t).unwrap();
        assert_eq!(torso.applied_activation(SCM), 0.0, "at {t} s");
        diaphragm = diaphragm.max(torso.applied_activation(MuscleGroup::Diaphragm));
    }
    // the drive was on: the diaphragm breathed meanwhile
    assert!(diaphragm > 0.1, "diaphragm peak {diaphragm}");
}

/// Through the FMU: the input `activation.sternocleidomastoids` at value reference 11 (after
/// the airway inputs, so that the older inputs keep theirs) sets the applied activation.
#[test]
fn the_fmu_input_reaches_them() {
    use breathing_torso::fmi::variables::{VR_ACTIVATION, activation_vr, table};
    let t = table();
    let v = t.by_name("activation.sternocleidomastoids").unwrap();
    assert_eq!(v.vr, 11);
    assert_eq!(activation_vr(SCM), 11);
    for (k, g) in MuscleGroup::ALL.iter().take(8).enumerate() {
        assert_eq!(activation_vr(*g), VR_ACTIVATION + k as u32);
    }
    assert_eq!(
        t.by_name("gain.sternocleidomastoids.right").unwrap().vr,
        156
    );
    assert_eq!(t.by_name("gain.sternocleidomastoids.left").unwrap().vr, 157);
}

/// The change of the mouth pressure the muscles alone give at full activation against the
/// airway occluded at FRC [cmH2O]: in seven healthy subjects about 3-4 cmH2O (Legrand,
/// Schneider, Gevenois & De Troyer 2003, J Appl Physiol 94:1467, from the muscles' shortening
/// with inflation by Maxwell's reciprocity and their mass).
const ALONE_AGAINST_OCCLUSION: (f64, f64) = (3.0, 4.0);

/// The drive off, the airway occluded at the rest volume, then the sternocleidomastoids at 1
/// for 3 s: the fall of `pressure.mouth` [cmH2O].
fn occluded_pressure_alone(law: MuscleLaw) -> f64 {
    let mut torso = Torso::new(standing(law)).unwrap();
    torso.set_airway_occluded(true).unwrap();
    torso.advance_to(1.0).unwrap();
    let p0 = torso.read(Quantity::MouthPressure).unwrap();
    torso.set_activation(SCM, 1.0).unwrap();
    // settled: at 8 s it reads within 0.01 cmH2O of this
    torso.advance_to(4.0).unwrap();
    let p1 = torso.read(Quantity::MouthPressure).unwrap();
    let drop = (p0 - p1) / 98.0665;
    println!(
        "{law:?}: the sternocleidomastoids alone, occluded at FRC: mouth pressure -{drop:.2} cmH2O"
    );
    drop
}

#[test]
#[ignore = "issue 35: the sternocleidomastoids alone against the occluded airway at FRC measured 6.86 cmH2O (thesis law) against about 3-4 cmH2O (Legrand et al. 2003)"]
fn alone_against_the_occluded_airway_thesis_law() {
    let p = occluded_pressure_alone(MuscleLaw::Thesis);
    assert!(
        (ALONE_AGAINST_OCCLUSION.0..=ALONE_AGAINST_OCCLUSION.1).contains(&p),
        "{p} cmH2O against {ALONE_AGAINST_OCCLUSION:?}"
    );
}

#[test]
#[ignore = "issue 35: the sternocleidomastoids alone against the occluded airway at FRC measured 9.01 cmH2O (hill law) against about 3-4 cmH2O (Legrand et al. 2003)"]
fn alone_against_the_occluded_airway_hill_law() {
    let p = occluded_pressure_alone(MuscleLaw::Hill);
    assert!(
        (ALONE_AGAINST_OCCLUSION.0..=ALONE_AGAINST_OCCLUSION.1).contains(&p),
        "{p} cmH2O against {ALONE_AGAINST_OCCLUSION:?}"
    );
}
