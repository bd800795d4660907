//! What the diaphragm does with its force, default subject, level of detail 1, through the
//! facade (docs/dynamics.md, "Physiological figures"):
//!
//! 1. the diaphragm alone at the hill law's quiet activation (`HILL_QUIET_DIAPHRAGM`, ramped
//!    over 1 s and held), standing and supine: the volume it adds;
//! 2. the diaphragm alone at full activation against the occluded airway at FRC, both laws,
//!    and under the hill law with the rib joints and cartilage 100 times stiffer: the
//!    transdiaphragmatic pressure, the dome's descent and the rib cage's and abdomen's
//!    displaced volumes;
//! 3. the hill law's full inspiration (the physiology bench's inspiratory groups at 1) and the
//!    diaphragm alone at 1, airway open: how far the right costal margin (the diaphragm's
//!    insertions) rises, at the back and elsewhere, and how far the dome's apex descends;
//! 4. the hill law's quiet breathing standing with the internal intercostals silent (the
//!    drive applied by hand, every group but them): the rib-cage share it rests on;
//! 5. where the dome's posterior insertions (the crura's) stand against the lumbar joints.
//!
//! `cargo run --release --example diaphragm_pressure`

use breathing_torso::anatomy::{MuscleGroup, Posture, VertexRole};
use breathing_torso::bench::physiology::INSPIRATORY;
use breathing_torso::dynamics::muscle::MuscleLaw;
use breathing_torso::dynamics::{Data, Layout, Params, kinematics};
use breathing_torso::model::drive::HILL_QUIET_DIAPHRAGM;
use breathing_torso::model::{Config, Drive, Quantity, Torso};
use nalgebra::Point3;

const CMH2O: f64 = 98.0665;

/// A change made to the model's constants before it is built.
type Change = dyn Fn(&mut Params);

fn torso(law: MuscleLaw, posture: Posture, change: impl Fn(&mut Params)) -> Torso {
    let mut config = Config {
        muscle_law: law,
        ..Config::default()
    };
    config.subject.posture = posture;
    config.drive.enabled = false;
    let mut params = config.model_params();
    change(&mut params);
    config.params = Some(params);
    Torso::new(config).expect("the default subject builds")
}

/// Ramps `groups` to `level` over 1 s and holds them to `end` seconds.
fn activate(t: &mut Torso, groups: &[MuscleGroup], level: f64, end: f64) {
    let h = 0.05;
    for k in 1..=(end / h).round() as u32 {
        let time = f64::from(k) * h;
        for &g in groups {
            t.set_activation(g, level * time.min(1.0)).unwrap();
        }
        t.advance_to(time).unwrap();
    }
}

fn read(t: &mut Torso) -> [f64; 6] {
    [
        Quantity::LungVolume,
        Quantity::PleuralPressure,
        Quantity::AbdominalPressure,
        Quantity::DiaphragmDisplacement,
        Quantity::RibCageDisplaced,
        Quantity::AbdomenDisplaced,
    ]
    .map(|q| t.read(q).unwrap())
}

fn positions(t: &Torso) -> Vec<Point3<f64>> {
    let model = &t.compiled().model;
    let mut data = Data::new(model);
    kinematics::positions_and_velocities(model, &mut data, &Layout::new(model), t.state());
    data.pos
}

fn main() {
    println!("1. the diaphragm alone at {HILL_QUIET_DIAPHRAGM}, hill law, airway open");
    for posture in [Posture::Standing, Posture::Supine] {
        let mut t = torso(MuscleLaw::Hill, posture, |_| {});
        let v0 = t.read(Quantity::LungVolume).unwrap();
        activate(&mut t, &[MuscleGroup::Diaphragm], HILL_QUIET_DIAPHRAGM, 6.0);
        let dv = t.read(Quantity::LungVolume).unwrap() - v0;
        println!("   {posture:?}: adds {dv:.3} L");
    }

    println!("2. the diaphragm alone at 1 against the occluded airway at FRC, standing");
    let stiff_ribs = |p: &mut Params| {
        p.rib_joint_stiffness *= 100.0;
        p.cartilage_stiffness *= 100.0;
    };
    let cases: [(&str, MuscleLaw, &Change); 3] = [
        ("thesis law", MuscleLaw::Thesis, &|_| {}),
        ("hill law", MuscleLaw::Hill, &|_| {}),
        (
            "hill law, rib joints and cartilage x100",
            MuscleLaw::Hill,
            &stiff_ribs,
        ),
    ];
    for (label, law, change) in cases {
        let mut t = torso(law, Posture::Standing, change);
        t.set_airway_occluded(true).unwrap();
        let r0 = read(&mut t);
        activate(&mut t, &[MuscleGroup::Diaphragm], 1.0, 3.0);
        let r1 = read(&mut t);
        println!(
            "   {label}: Pdi {:.1} cmH2O (rest {:.1}), dome descends {:.2} cm, rib cage {:+.3} L, abdomen {:+.3} L",
            (r1[2] - r1[1]) / CMH2O,
            (r0[2] - r0[1]) / CMH2O,
            100.0 * (r0[3] - r1[3]),
            r1[4] - r0[4],
            r1[5] - r0[5]
        );
    }

    println!("3. hill law, standing, airway open, activations at 1 held 9 s");
    let efforts: [(&str, &[MuscleGroup]); 2] = [
        ("diaphragm alone", &[MuscleGroup::Diaphragm]),
        ("full inspiration", &INSPIRATORY),
    ];
    for (label, groups) in efforts {
        let mut t = torso(MuscleLaw::Hill, Posture::Standing, |_| {});
        let p0 = positions(&t);
        activate(&mut t, groups, 1.0, 9.0);
        let p1 = positions(&t);
        let ab = &t.compiled().anatomy.abdomen;
        let anchor = |v: usize| ab.anchor[v] as usize;
        let rim: Vec<usize> = (0..ab.len())
            .filter(|&v| ab.roles[v] == VertexRole::Insertion)
            .map(anchor)
            .filter(|&a| p0[a].z > 0.02)
            .collect();
        let back_x = rim.iter().map(|&a| p0[a].x).fold(f64::INFINITY, f64::min) + 0.03;
        let rise = |back: bool| {
            let r: Vec<f64> = rim
                .iter()
                .filter(|&&a| (p0[a].x < back_x) == back)
                .map(|&a| 100.0 * (p1[a].y - p0[a].y))
                .collect();
            let lo = r.iter().copied().fold(f64::INFINITY, f64::min);
            let hi = r.iter().copied().fold(f64::NEG_INFINITY, f64::max);
            (lo, hi)
        };
        let apex = (0..ab.len())
            .filter(|&v| ab.roles[v] == VertexRole::Dome)
            .map(anchor)
            .max_by(|&a, &b| p0[a].y.total_cmp(&p0[b].y))
            .expect("a dome");
        let (back_lo, back_hi) = rise(true);
        let (side_lo, side_hi) = rise(false);
        println!(
            "   {label}: right costal margin rises {back_lo:.2} to {back_hi:.2} cm at the back (its last 3 cm), {side_lo:.2} to {side_hi:.2} cm elsewhere; apex descends {:.2} cm",
            100.0 * (p0[apex].y - p1[apex].y)
        );
    }

    println!("4. hill law, quiet breathing standing, the drive applied by hand");
    let drive = Drive::quiet_for(MuscleLaw::Hill);
    for silent in [false, true] {
        let mut t = torso(MuscleLaw::Hill, Posture::Standing, |_| {});
        let h = 0.05;
        let (mut rc, mut ab, mut v) = (Vec::new(), Vec::new(), Vec::new());
        for k in 1..=(16.0 / h) as u32 {
            let time = f64::from(k) * h;
            for g in MuscleGroup::ALL {
                let a = if silent && g == MuscleGroup::InternalIntercostals {
                    0.0
                } else {
                    drive.activation(g, time)
                };
                t.set_activation(g, a).unwrap();
            }
            t.advance_to(time).unwrap();
            if time >= 6.0 {
                rc.push(t.read(Quantity::RibCageDisplaced).unwrap());
                ab.push(t.read(Quantity::AbdomenDisplaced).unwrap());
                v.push(t.read(Quantity::LungVolume).unwrap());
            }
        }
        let swing = |x: &[f64]| {
            x.iter().copied().fold(f64::NEG_INFINITY, f64::max)
                - x.iter().copied().fold(f64::INFINITY, f64::min)
        };
        let (rc, ab) = (swing(&rc), swing(&ab));
        println!(
            "   internal intercostals {}: tidal volume {:.3} L, rib-cage share {:.1} %",
            if silent { "silent" } else { "driven" },
            swing(&v),
            100.0 * rc / (rc + ab)
        );
    }

    println!("5. the dome's insertions within 3 cm of the midline at the back, standing");
    let t = torso(MuscleLaw::Thesis, Posture::Standing, |_| {});
    let a = &t.compiled().anatomy;
    let ab = &a.abdomen;
    let rim: Vec<Point3<f64>> = (0..ab.len())
        .filter(|&v| ab.roles[v] == VertexRole::Insertion)
        .map(|v| a.anchors[ab.anchor[v] as usize].rest)
        .collect();
    let back = rim.iter().map(|p| p.x).fold(f64::INFINITY, f64::min);
    let crura: Vec<f64> = rim
        .iter()
        .filter(|p| p.z.abs() < 0.03 && p.x < back + 0.05)
        .map(|p| p.y)
        .collect();
    println!(
        "   heights {:.3}-{:.3} m",
        crura.iter().copied().fold(f64::INFINITY, f64::min),
        crura.iter().copied().fold(f64::NEG_INFINITY, f64::max)
    );
    let joints: Vec<String> = a
        .spine
        .joints
        .iter()
        .filter(|(n, _)| ["thoracic12", "lumbar1", "lumbar2", "lumbar3"].contains(&n.as_ref()))
        .map(|(n, p)| format!("{n} {:.3}", p.y))
        .collect();
    println!("   spine joints: {}", joints.join(", "));
}
