//! Rib kinematics of the default subject: per right rib the inclination of the bone and of
//! the whole rib (head to cartilage joint), the direction a unit rotation about the rib-neck
//! axis moves its bony end and cartilage end, and, over one quiet breath (end-expiration to
//! end-inspiration of the second breath, upright, level of detail 1), each rib's rotation,
//! the sternum's motion and the upper marker rows split by what moves them (ribs, sternum,
//! abdominal wall).
//!
//! `cargo run --release --example rib_kinematics [forced] [cartilage=<stiffness factor>]`

mod common;

use breathing_torso::Quantity;
use breathing_torso::observe::markers::HandleSource;
use breathing_torso::observe::skinning::HandlePose;
use nalgebra::{Point3, Quaternion, UnitQuaternion, Vector3};

fn vcl(d: Vector3<f64>) -> String {
    format!("v {:6.2} c {:6.2} l {:6.2}", d.x, d.y, d.z)
}

fn main() {
    let drive = common::drive_from_args();
    // `cartilage=<factor>` scales the cartilage ball joints' stiffness (a crude stand-in for
    // compliant costal cartilage).
    let cartilage = common::factor_from_args("cartilage");
    let mut torso = common::torso_with(drive, |p| p.cartilage_stiffness *= cartilage);
    let compiled = torso.compiled().clone();
    let anatomy = &compiled.anatomy;
    println!("right ribs: inclination below horizontal (sagittal), unit-rotation motion [mm/deg]");
    println!(" lvl  bone_incl  joint_incl   bone end motion                 cartilage end motion");
    for rib in anatomy.ribs.iter().filter(|r| r.side.sign() > 0.0) {
        let end = rib.bone_end();
        let joint = rib.cartilage.last().copied().unwrap_or(end);
        let incl = |p: Point3<f64>| {
            let r = p - rib.head;
            (-r.y).atan2(r.x).to_degrees()
        };
        let motion = |p: Point3<f64>| rib.axis.cross(&(p - rib.head)) * 1e3 * 1f64.to_radians();
        let (me, mj) = (motion(end), motion(joint));
        println!(
            " {:2}   {:7.1}    {:7.1}     {}  v/c {:4.2}   {}  v/c {:4.2}",
            rib.level,
            incl(end),
            incl(joint),
            vcl(me),
            me.x / me.y,
            vcl(mj),
            mj.x / mj.y
        );
    }
    let s = &anatomy.sternum;
    println!(
        "sternum: jugular {:?} angle {:?} xiphisternal {:?}",
        s.jugular.coords.map(|v| (v * 1e3).round()),
        s.angle.coords.map(|v| (v * 1e3).round()),
        s.xiphisternal.coords.map(|v| (v * 1e3).round())
    );

    let mm = torso.marker_model().unwrap();
    {
        let lm = &mm.skin().landmarks;
        let lowest10 = anatomy.ribs[9]
            .bone
            .iter()
            .map(|p| p.y)
            .fold(f64::INFINITY, f64::min);
        let spine = |n: &str| anatomy.spine.joint(n).map(|p| (p.y * 1e3).round());
        println!(
            "skin: suprasternale {:.0} chest {:.0} tenth rib {:.0} omphalion {:.0} | bones: jugular {:.0} rib10 lowest {:.0} T1 {:?} T12 {:?} L3 {:?} sacrum {:?}",
            lm.suprasternale_height * 1e3,
            lm.chest_height * 1e3,
            lm.tenth_rib_height * 1e3,
            lm.omphalion_height * 1e3,
            s.jugular.y * 1e3,
            lowest10 * 1e3,
            spine("thoracic1"),
            spine("thoracic12"),
            spine("lumbar3"),
            spine("sacrum"),
        );
        for (n, p) in &anatomy.spine.joints {
            print!(" {n} {:.0}/{:.0}", p.x * 1e3, p.y * 1e3);
        }
        println!();
    }
    let (lo, hi) = common::second_breath(&mut torso, &[Quantity::RibCageDisplaced]);
    println!("tidal volume {:.3} L", hi.lung - lo.lung);
    let (ylo, yhi) = (&lo.state, &hi.state);
    let layout = breathing_torso::dynamics::Layout::new(&compiled.model);
    print!("rib rotation [deg], right 1-12:");
    for r in 0..12 {
        print!(
            " {:.2}",
            (yhi[layout.theta + r] - ylo[layout.theta + r]).to_degrees()
        );
    }
    println!();
    let mean_turn = (1..10)
        .map(|r| (yhi[layout.theta + r] - ylo[layout.theta + r]).to_degrees())
        .sum::<f64>()
        / 9.0;
    let rib_cage = hi.reads[0] - lo.reads[0];
    println!(
        "rib cage displaces {:.3} L end-expiration to end-inspiration; ribs 2-10 turn {:.2} deg on average: {:.0} mL per degree",
        rib_cage,
        mean_turn,
        1e3 * rib_cage / mean_turn
    );
    // Sternum landmarks.
    let sternum_pose = |y: &[f64]| {
        let q = &y[layout.sternum_q..layout.sternum_q + 4];
        let rot = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
        let x = Point3::new(
            y[layout.sternum_x],
            y[layout.sternum_x + 1],
            y[layout.sternum_x + 2],
        );
        (rot, x)
    };
    let com0 = compiled.model.sternum_com;
    let (rl, xl) = sternum_pose(ylo);
    let (rh, xh) = sternum_pose(yhi);
    for (name, p) in [
        ("jugular", s.jugular),
        ("angle", s.angle),
        ("xiphisternal", s.xiphisternal),
    ] {
        let at = |r: UnitQuaternion<f64>, x: Point3<f64>| x + r * (p - com0);
        println!(
            "sternum {name:12} moves [mm] {}",
            vcl((at(rh, xh) - at(rl, xl)) * 1e3)
        );
    }
    let dr = rh * rl.inverse();
    println!(
        "sternum turns {:.2} deg about {:?}",
        dr.angle().to_degrees(),
        dr.axis().map(|a| a.into_inner())
    );
    // Rib joint ends: where each right rib's cartilage end goes vs where the sternum's notch goes.
    for rib in anatomy
        .ribs
        .iter()
        .filter(|r| r.side.sign() > 0.0 && r.level <= 7)
    {
        let joint = *rib.cartilage.last().unwrap();
        let r = rib.index();
        let rot = |y: &[f64]| {
            UnitQuaternion::from_axis_angle(&rib.axis, y[layout.theta + r])
                .transform_vector(&(joint - rib.head))
        };
        let d_rib = (rot(yhi) - rot(ylo)) * 1e3;
        let at = |q: UnitQuaternion<f64>, x: Point3<f64>| x + q * (joint - com0);
        let d_st = (at(rh, xh) - at(rl, xl)) * 1e3;
        println!(
            "rib {:2} joint: rib end {}   sternum point {}",
            rib.level,
            vcl(d_rib),
            vcl(d_st)
        );
    }

    // Markers by what moves them.
    let split = |keep: &dyn Fn(&HandleSource) -> bool| {
        let mut poses_lo = Vec::new();
        let mut poses_hi = Vec::new();
        mm.handle_poses(ylo, &mut poses_lo).unwrap();
        mm.handle_poses(yhi, &mut poses_hi).unwrap();
        for (k, s) in mm.sources().iter().enumerate() {
            if !keep(s) {
                let rest = HandlePose::rest(mm.handles()[k].kind);
                poses_lo[k] = rest;
                poses_hi[k] = rest;
            }
        }
        let eval = |poses: &[HandlePose]| {
            let frame = mm.skinning().frame(poses).unwrap();
            let mut out = vec![Point3::origin(); mm.len()];
            mm.bound().evaluate(&frame, &mut out);
            out
        };
        let (a, b) = (eval(&poses_lo), eval(&poses_hi));
        b.iter()
            .zip(&a)
            .map(|(p, q)| (p - q) * 1e3)
            .collect::<Vec<_>>()
    };
    let all = split(&|_| true);
    let ribs = split(&|s| matches!(s, HandleSource::Rib(_)));
    let sternum = split(&|s| matches!(s, HandleSource::Sternum));
    let wall = split(&|s| matches!(s, HandleSource::WallVertex(_)));
    let cols = mm.grid().cols;
    let rest = mm.bound().rest();
    for row in 0..4 {
        println!("row {} (y {:.0} mm):", row + 1, rest[row * cols].y * 1e3);
        for c in 0..cols {
            let i = row * cols + c;
            println!(
                "  m{:2} z {:5.0}  all {} | ribs {} | sternum {} | wall {}",
                i + 1,
                rest[i].z * 1e3,
                vcl(all[i]),
                vcl(ribs[i]),
                vcl(sternum[i]),
                vcl(wall[i])
            );
        }
    }

    for &m in &[0usize, 6, 8, 12, 14, 18] {
        print!(
            "m{:2} rest {:?} by handle:",
            m + 1,
            rest[m].coords.map(|v| (v * 1e3).round())
        );
        for (k, src) in mm.sources().iter().enumerate() {
            if matches!(src, HandleSource::WallVertex(_)) {
                continue;
            }
            let d = split(&|s| s == src)[m];
            if d.norm() > 0.3 {
                print!(" [{} {}]", mm.handles()[k].name, vcl(d));
            }
        }
        println!();
    }
    let upper: Vec<f64> = (cols..3 * cols).map(|i| all[i].norm()).collect();
    let (umin, umax) = upper
        .iter()
        .fold((f64::INFINITY, 0.0f64), |(a, b), &n| (a.min(n), b.max(n)));
    println!(
        "rows 2-3: {umin:.2}-{umax:.2} mm, i.e. {:.0}-{:.0} mm per litre of rib-cage displacement and {:.2}-{:.2} mm per degree of mean rib rotation",
        umin / rib_cage,
        umax / rib_cage,
        umin / mean_turn,
        umax / mean_turn
    );
    let lm = &mm.skin().landmarks;
    println!("omphalion height {:.0} mm", lm.omphalion_height * 1e3);
    for i in 0..rest.len() {
        let p = rest[i];
        if (p.y - lm.omphalion_height).hypot(p.z) < 0.05 {
            println!(
                "  umbilical m{:2}: all {} | ribs {} | sternum {} | wall {}",
                i + 1,
                vcl(all[i]),
                vcl(ribs[i]),
                vcl(sternum[i]),
                vcl(wall[i])
            );
        }
    }
}
