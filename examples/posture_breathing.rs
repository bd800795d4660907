//! Breathing by posture: for standing, sitting and supine, prints the rest (end-expiratory)
//! lung volume and dome apex height, and for quiet breathing, forced breathing and each
//! muscle family alone the tidal volume, the rib-cage share of the displaced volume (the
//! optoelectronic-plethysmography compartments), the dome excursion and the abdominal
//! pressure swing. Used to study how posture shifts breathing between rib cage and abdomen.
//!
//! `cargo run --release --example posture_breathing` (`-- --variants`: one posture constant
//! swapped at a time; `-- --lengths`: the diaphragm's fibre length by posture and subject).

use breathing_torso::anatomy::Posture;
use breathing_torso::dynamics::Params;
use breathing_torso::model::run::Frame;
use breathing_torso::model::run::{run, summarise};
use breathing_torso::model::{Config, Drive, Wave};
use breathing_torso::{Quantity, Torso};

fn drive(name: &str) -> Drive {
    let wave = |amplitude: f64| Wave {
        amplitude,
        phase: 0.0,
    };
    match name {
        "quiet" => Drive::quiet(),
        "forced" => Drive::forced(),
        "ribs 0.2" => Drive {
            enabled: true,
            ribs: wave(0.2),
            ..Drive::default()
        },
        "diaphragm 0.25" => Drive {
            enabled: true,
            diaphragm: wave(0.25),
            ..Drive::default()
        },
        _ => Drive::default(),
    }
}

/// In-phase changes from end-expiration to end-inspiration (frames of least and greatest lung
/// volume after the first period): rib-cage displaced, abdomen displaced, dome [L, L, cm].
fn signed(frames: &[Frame], period: f64) -> [f64; 3] {
    let sel: Vec<&Frame> = frames.iter().filter(|f| f.time >= period - 1e-9).collect();
    let lo = sel.iter().min_by(|a, b| a.lung.total_cmp(&b.lung)).unwrap();
    let hi = sel.iter().max_by(|a, b| a.lung.total_cmp(&b.lung)).unwrap();
    [
        hi.rib_cage_displaced - lo.rib_cage_displaced,
        hi.abdomen_displaced - lo.abdomen_displaced,
        100.0 * (hi.diaphragm - lo.diaphragm),
    ]
}

fn main() -> breathing_torso::Result<()> {
    if let Some(i) = std::env::args().position(|a| a == "--probe") {
        let args: Vec<String> = std::env::args().collect();
        let rib: f64 = args.get(i + 1).and_then(|v| v.parse().ok()).unwrap_or(1.0);
        let wall: f64 = args.get(i + 2).and_then(|v| v.parse().ok()).unwrap_or(1.0);
        return probe(rib, wall);
    }
    if std::env::args().any(|a| a == "--lengths") {
        return lengths();
    }
    if std::env::args().any(|a| a == "--variants") {
        return variants();
    }
    for posture in [Posture::Standing, Posture::Sitting, Posture::Supine] {
        let mut config = Config::default();
        config.subject.posture = posture;
        let mut torso = Torso::new(config.clone())?;
        let lung = torso.read(Quantity::LungVolume)?;
        let abdomen = torso.read(Quantity::AbdomenVolume)?;
        let apex = torso.compiled().anatomy.abdomen.apex_y;
        println!(
            "{posture:?}: rest lung {lung:.3} L, abdomen {abdomen:.3} L, dome apex {:.1} mm",
            apex * 1e3
        );
        for name in ["quiet", "forced", "ribs 0.2", "diaphragm 0.25"] {
            let d = drive(name);
            config.drive = d;
            let mut torso = Torso::new(config.clone())?;
            let period = 1.0 / d.frequency;
            let frames = run(&mut torso, 3.0 * period, 28.0)?;
            let s = summarise(&frames, period);
            let [rc, ab, dome] = signed(&frames, period);
            println!(
                "  {name:15} VT {:.3} L, EELV {:.3} L, rib cage {:.3} L, abdomen {:.3} L, rib share {:.1} %, dome {:.2} cm, pressure swing {:.0} Pa; in phase: rib cage {rc:+.3} L, abdomen {ab:+.3} L, dome {dome:+.2} cm",
                s.tidal_volume,
                s.end_expiratory_volume,
                s.rib_cage_swing,
                s.abdomen_swing,
                100.0 * s.rib_cage_share,
                100.0 * s.dome_excursion,
                s.pressure_swing
            );
        }
    }
    Ok(())
}

/// An edit of the posture's default constants.
type Edit = fn(&mut Params);

/// Quiet breathing with one posture-dependent constant swapped at a time, and the diaphragm's
/// total fibre rest length by posture.
fn variants() -> breathing_torso::Result<()> {
    let cases: [(&str, Posture, Edit); 7] = [
        ("standing", Posture::Standing, |_| {}),
        ("standing, supine wall compliance", Posture::Standing, |p| {
            p.abdominal_wall_compliance =
                Params::for_posture(Posture::Supine).abdominal_wall_compliance
        }),
        ("supine", Posture::Supine, |_| {}),
        ("supine, upright wall compliance", Posture::Supine, |p| {
            p.abdominal_wall_compliance =
                Params::for_posture(Posture::Standing).abdominal_wall_compliance
        }),
        (
            "supine, upright diaphragm contraction",
            Posture::Supine,
            |p| p.beta_max_diaphragm = Params::for_posture(Posture::Standing).beta_max_diaphragm,
        ),
        ("supine, upright rib joints", Posture::Supine, |p| {
            p.rib_joint_stiffness = Params::for_posture(Posture::Standing).rib_joint_stiffness
        }),
        ("supine, no gravity", Posture::Supine, |p| p.gravity = 0.0),
    ];
    for posture in [Posture::Standing, Posture::Supine] {
        let config = Config {
            subject: breathing_torso::anatomy::Subject {
                posture,
                ..Default::default()
            },
            ..Config::default()
        };
        let torso = Torso::new(config)?;
        let m = &torso.compiled().model;
        let (mut sum, mut n) = (0.0, 0);
        for e in 0..m.muscle_count {
            if m.element_group(e) == Some(breathing_torso::anatomy::MuscleGroup::Diaphragm) {
                sum += m.elements.rest_length[e];
                n += 1;
            }
        }
        println!("{posture:?}: {n} diaphragm elements, total rest length {sum:.4} m");
    }
    for (name, posture, edit) in cases {
        let mut config = Config::default();
        config.subject.posture = posture;
        let mut params = Params::for_posture(posture);
        edit(&mut params);
        config.params = Some(params);
        config.drive = if std::env::args().any(|a| a == "--forced") {
            Drive::forced()
        } else {
            Drive::quiet()
        };
        let period = 1.0 / config.drive.frequency;
        let mut torso = Torso::new(config)?;
        let clock = std::time::Instant::now();
        let frames = run(&mut torso, 3.0 * period, 28.0)?;
        let s = summarise(&frames, period);
        println!(
            "{name:40} VT {:.3} L, rib share {:.1} %, dome {:.2} cm, pressure swing {:.0} Pa ({:.1} s, {} steps)",
            s.tidal_volume,
            100.0 * s.rib_cage_share,
            100.0 * s.dome_excursion,
            s.pressure_swing,
            clock.elapsed().as_secs_f64(),
            torso.read(Quantity::SolverSteps)?
        );
    }
    Ok(())
}

/// Total rest length of the diaphragm's fibres (their tissue length, the smooth dome's arcs
/// over their routes) by posture, level of detail and subject, relative to standing.
fn lengths() -> breathing_torso::Result<()> {
    use breathing_torso::anatomy::{Anatomy, MuscleGroup, Sex, Subject};
    for (sex, stature, mass) in [
        (Sex::Male, 1.75, 75.0),
        (Sex::Female, 1.63, 60.0),
        (Sex::Male, 1.95, 110.0),
    ] {
        for lod in 0..=2 {
            let total = |posture| -> breathing_torso::Result<f64> {
                let subject = Subject {
                    sex,
                    stature,
                    mass,
                    posture,
                    ..Subject::default()
                };
                let a = Anatomy::build(&subject, lod)?;
                Ok(a.muscles
                    .iter()
                    .filter(|m| m.group == MuscleGroup::Diaphragm)
                    .filter_map(|m| m.tissue_length)
                    .sum())
            };
            let up = total(Posture::Standing)?;
            println!(
                "{sex:?} {stature} m {mass} kg lod {lod}: standing {up:.4} m, sitting x{:.4}, supine x{:.4}",
                total(Posture::Sitting)? / up,
                total(Posture::Supine)? / up
            );
        }
    }
    Ok(())
}

/// Forced supine breathing with the rib-joint stiffness and the wall compliance scaled,
/// printing progress.
fn probe(rib: f64, wall: f64) -> breathing_torso::Result<()> {
    let mut config = Config::default();
    config.subject.posture = Posture::Supine;
    let mut p = Params::for_posture(Posture::Supine);
    p.rib_joint_stiffness *= rib;
    p.abdominal_wall_compliance *= wall;
    config.params = Some(p);
    config.drive = Drive::forced();
    let mut torso = Torso::new(config)?;
    let clock = std::time::Instant::now();
    for i in 1..=30 {
        torso.advance_to(0.5 * i as f64)?;
        println!(
            "t {:.1} s: lung {:.3} L, dome {:.1} mm, steps {}, wall {:.1} s",
            torso.time(),
            torso.read(Quantity::LungVolume)?,
            1e3 * torso.read(Quantity::DiaphragmDisplacement)?,
            torso.read(Quantity::SolverSteps)?,
            clock.elapsed().as_secs_f64()
        );
    }
    Ok(())
}
