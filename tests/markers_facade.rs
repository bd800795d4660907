//! Markers read through the facade: agreement with a direct deformation of the whole skin
//! at the same state, the exact rest pose, per-state caching, indices beyond the grid,
//! registration to a recording through `scene.slp_reference`, and the recording reader's
//! errors.

use breathing_torso::anatomy::skin::{Skin, SkinOptions};
use breathing_torso::dynamics::Layout;
use breathing_torso::dynamics::kinematics::axis_rotation;
use breathing_torso::model::Drive;
use breathing_torso::observe::markers::{HandleSource, read_slp_first_frame};
use breathing_torso::observe::skinning::HandlePose;
use breathing_torso::{Config, Error, Quantity, Torso};
use nalgebra::{Isometry3, Point3, Quaternion, Rotation3, Translation3, UnitQuaternion, Vector3};
use std::io::Write;
use std::path::PathBuf;

fn quiet_torso() -> Torso {
    Torso::new(Config {
        drive: Drive::quiet(),
        ..Config::default()
    })
    .unwrap()
}

fn read_all(torso: &mut Torso) -> Vec<Point3<f64>> {
    (0..torso.marker_count())
        .map(|i| {
            let mut c = |a: u8| {
                torso
                    .read(Quantity::Marker {
                        index: i as u16,
                        axis: a,
                    })
                    .unwrap()
            };
            Point3::new(c(0), c(1), c(2))
        })
        .collect()
}

/// Handle poses built independently of the marker model: Rodrigues rotation matrices of the
/// dynamics' kinematics about each rib's hinge, the sternum's quaternion and centre of mass,
/// the wall vertices' displacements.
fn direct_poses(torso: &Torso) -> Vec<HandlePose> {
    let model = &torso.compiled().model;
    let l = Layout::new(model);
    let y = torso.state();
    let markers = torso.compiled().markers.get_or_build(
        &torso.marker_scene(),
        &torso.compiled().anatomy,
        model,
    );
    let markers = markers.unwrap();
    markers
        .sources()
        .iter()
        .map(|s| match *s {
            HandleSource::Rib(r) => {
                let m = axis_rotation(&model.rib_axis[r].normalize(), y[l.theta + r]);
                let rot = UnitQuaternion::from_rotation_matrix(&Rotation3::from_matrix(&m));
                let h = model.rib_head[r].coords;
                HandlePose::Rigid(Isometry3::from_parts(Translation3::from(h - m * h), rot))
            }
            HandleSource::Sternum => {
                let q = &y[l.sternum_q..l.sternum_q + 4];
                let rot = UnitQuaternion::from_quaternion(Quaternion::new(q[0], q[1], q[2], q[3]));
                let x = Vector3::new(y[l.sternum_x], y[l.sternum_x + 1], y[l.sternum_x + 2]);
                HandlePose::Rigid(Isometry3::from_parts(
                    Translation3::from(x - rot * model.sternum_com.coords),
                    rot,
                ))
            }
            HandleSource::Spine | HandleSource::Clavicle => {
                HandlePose::Rigid(Isometry3::identity())
            }
            HandleSource::WallVertex(j) => {
                let k = l.vertex_x + 3 * j as usize;
                let rest = model.rest[model.vertex_anchor[j as usize] as usize];
                HandlePose::Translation(Vector3::new(y[k], y[k + 1], y[k + 2]) - rest.coords)
            }
        })
        .collect()
}

#[test]
fn facade_markers_equal_a_direct_skin_deformation() {
    let mut torso = quiet_torso();
    torso.advance_to(2.3).unwrap();
    let read = read_all(&mut torso);
    let model = torso.marker_model().unwrap();
    let frame = model.skinning().frame(&direct_poses(&torso)).unwrap();
    let mut skin = Vec::new();
    model.skinning().deform_all(&frame, &mut skin);
    let direct = model.grid().positions(&skin, &model.skin().triangles);
    let mut moved = 0.0f64;
    for (i, (a, b)) in read.iter().zip(&direct).enumerate() {
        assert!((a - b).norm() < 1e-10, "marker {i}: {a} vs {b}");
        moved = moved.max((a - model.bound().rest()[i]).norm());
    }
    assert!(moved > 1e-4, "the state moved the markers ({moved} m)");
    // The whole skin through the facade is the same deformation.
    let mut facade_skin = Vec::new();
    torso.skin_vertices(&mut facade_skin).unwrap();
    let worst = facade_skin
        .iter()
        .zip(&skin)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    assert!(worst < 1e-10, "skin differs by {worst}");
}

#[test]
fn rest_pose_reproduces_the_generated_skin_exactly() {
    let mut torso = quiet_torso();
    torso.start_at_rest();
    let model = torso.marker_model().unwrap();
    let anatomy = &torso.compiled().anatomy;
    let skin = Skin::for_anatomy(anatomy, &SkinOptions::default()).unwrap();
    assert_eq!(model.skin().vertices, skin.vertices);
    let mut v = Vec::new();
    torso.skin_vertices(&mut v).unwrap();
    assert_eq!(v, skin.vertices, "rest skin reproduced bit for bit");
    let rest = model.grid().positions(&skin.vertices, &skin.triangles);
    let read = torso.markers().unwrap().to_vec();
    for (a, b) in read.iter().zip(&rest) {
        assert!((a - b).norm() < 1e-14, "{a} vs {b}");
    }
}

#[test]
fn markers_are_recomputed_when_the_state_changes() {
    let mut torso = quiet_torso();
    let a = torso.markers().unwrap().to_vec();
    torso.advance_to(1.0).unwrap();
    let b = torso.markers().unwrap().to_vec();
    assert!(a.iter().zip(&b).any(|(p, q)| (p - q).norm() > 1e-5));
    let snap = torso.snapshot();
    torso.advance_to(2.0).unwrap();
    torso.restore(&snap).unwrap();
    assert_eq!(torso.markers().unwrap(), &b[..]);
    torso.reset();
    assert_eq!(torso.markers().unwrap(), &a[..]);
}

#[test]
fn indices_beyond_the_grid_read_zero_and_bad_axes_are_errors() {
    let mut torso = quiet_torso();
    assert_eq!(torso.marker_count(), 60);
    for index in [60u16, 100, 255] {
        assert_eq!(
            torso.read(Quantity::Marker { index, axis: 1 }).unwrap(),
            0.0
        );
    }
    assert!(
        torso
            .read(Quantity::Marker {
                index: 256,
                axis: 0
            })
            .is_err()
    );
    assert!(torso.read(Quantity::Marker { index: 0, axis: 3 }).is_err());
    assert!(torso.read(Quantity::Marker { index: 59, axis: 2 }).unwrap() != 0.0);
}

fn temp_path(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("markers_facade_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    dir.join(name)
}

/// Writes an SLP recording (mm) of `frames` (each a list of optional points in metres).
fn write_recording(path: &PathBuf, rows: usize, cols: usize, frames: &[Vec<Option<Point3<f64>>>]) {
    let mut f = std::fs::File::create(path).unwrap();
    writeln!(
        f,
        "# synthetic recording\n# grid: {rows}x{cols}\n# units: mm"
    )
    .unwrap();
    let mut header = vec!["time".to_string()];
    for i in 1..=rows * cols {
        for a in ["x", "y", "z"] {
            header.push(format!("marker[{i}].{a}"));
        }
    }
    writeln!(f, "{}", header.join(",")).unwrap();
    for (k, fr) in frames.iter().enumerate() {
        let mut row = vec![format!("{}", k as f64 / 56.0)];
        for p in fr {
            match p {
                Some(p) => row.extend([p.x, p.y, p.z].map(|c| format!("{:.4}", c * 1e3))),
                None => row.extend(["", "", ""].map(String::from)),
            }
        }
        writeln!(f, "{}", row.join(",")).unwrap();
    }
}

#[test]
fn a_recording_with_a_known_rigid_transform_is_registered_back() {
    // Ground truth: the unregistered model's rest markers seen from a camera frame.
    let mut plain = quiet_torso();
    plain.start_at_rest();
    let rest = plain.markers().unwrap().to_vec();
    let axis = nalgebra::Unit::new_normalize(Vector3::new(0.3, -1.0, 0.5));
    let truth = Isometry3::from_parts(
        Translation3::new(0.31, -0.42, 0.18),
        UnitQuaternion::from_axis_angle(&axis, 28f64.to_radians()),
    );
    // Tracking noise: uniform in +-0.8 mm per coordinate (about 0.5 mm RMS), deterministic.
    let mut seed = 0x2545_f491_4f6c_dd1du64;
    let mut noise = || {
        seed ^= seed << 13;
        seed ^= seed >> 7;
        seed ^= seed << 17;
        (seed as f64 / u64::MAX as f64 - 0.5) * 1.6e-3
    };
    let mut first: Vec<Option<Point3<f64>>> = rest
        .iter()
        .map(|p| Some(truth * p + Vector3::new(noise(), noise(), noise())))
        .collect();
    first[17] = None; // a point SLP lost
    let second = first.clone();
    let path = temp_path("known_transform.csv");
    write_recording(&path, 10, 6, &[first.clone(), second]);

    let mut config = Config {
        drive: Drive::quiet(),
        ..Config::default()
    };
    config.scene.slp_reference = Some(path.clone());
    let mut torso = Torso::new(config.clone()).unwrap();
    // the recording's frame is the rest pose's markers
    torso.start_at_rest();
    let model = torso.marker_model().unwrap();
    let reg = model.registration().expect("registered");
    let to_rec = &reg.to_recording;
    let angle = (to_rec.rotation * truth.rotation.inverse())
        .angle()
        .to_degrees();
    // Translation error where it matters: at the grid's centroid (an error of the rotation
    // alone moves the transform's translation by the lever arm from the floor origin).
    let c = Point3::from(rest.iter().fold(Vector3::zeros(), |a, p| a + p.coords) / 60.0);
    let shift = (to_rec.apply(&c) - truth * c).norm();
    println!(
        "registration: rotation error {angle:.4} deg, translation error {:.4} mm, rms {:.4} mm, fit {:?}",
        shift * 1e3,
        reg.rms * 1e3,
        reg.fit
    );
    assert!(angle < 0.5, "rotation error {angle} deg");
    assert!(shift < 1e-3, "translation error {shift} m");
    assert!(
        reg.fit.mean_after < reg.fit.mean_before,
        "skin fitting lowers the error"
    );

    // Markers at rest come out in the recording's frame, on the recorded points.
    let read = read_all(&mut torso);
    for (i, (p, q)) in read.iter().zip(&first).enumerate() {
        if let Some(q) = q {
            assert!((p - q).norm() < 1e-3, "marker {i}: {p} vs {q}");
        }
    }
    // And they keep following the model: the registered displacement is the plain one,
    // rotated into the recording's frame (to within the skin fitting's change of shape).
    torso.advance_to(2.0).unwrap();
    plain.advance_to(2.0).unwrap();
    let moved_reg = torso.markers().unwrap().to_vec();
    let moved_plain = plain.markers().unwrap().to_vec();
    for i in 0..60 {
        let d_reg = moved_reg[i] - read[i];
        let d_plain = truth.rotation * (moved_plain[i] - rest[i]);
        assert!(
            (d_reg - d_plain).norm() < 0.1 * d_plain.norm() + 2e-4,
            "marker {i}: {d_reg:?} vs {d_plain:?}"
        );
    }

    // A recording of another grid size is rejected naming both sizes.
    config.scene.grid_rows = 8;
    let mut other = Torso::new(config).unwrap();
    let err = other.markers().unwrap_err().to_string();
    assert!(err.contains("10 x 6") && err.contains("8 x 6"), "{err}");
}

fn bad(name: &str, text: &str) -> Error {
    let path = temp_path(name);
    std::fs::write(&path, text).unwrap();
    read_slp_first_frame(&path).unwrap_err()
}

fn header(n: usize) -> String {
    let mut h = vec!["time".to_string()];
    for i in 1..=n {
        for a in ["x", "y", "z"] {
            h.push(format!("marker[{i}].{a}"));
        }
    }
    h.join(",")
}

fn row(t: f64, n: usize) -> String {
    let mut r = vec![format!("{t}")];
    for i in 0..3 * n {
        r.push(format!("{}", i as f64));
    }
    r.join(",")
}

fn at(e: &Error) -> (usize, usize, String) {
    match e {
        Error::Parse {
            line,
            column,
            message,
            ..
        } => (*line, *column, message.clone()),
        other => panic!("not a parse error: {other}"),
    }
}

#[test]
fn bad_recordings_are_rejected_with_line_and_column() {
    let h = header(4);
    let ok = format!("# grid: 2x2\n{h}\n{}\n{}\n", row(0.0, 4), row(0.1, 4));
    let path = temp_path("ok.csv");
    std::fs::write(&path, &ok).unwrap();
    let f = read_slp_first_frame(&path).unwrap();
    assert_eq!((f.rows, f.cols, f.points.len()), (2, 2, 4));
    assert_eq!(f.points[1], Some(Point3::new(3.0, 4.0, 5.0)));

    let e = bad(
        "ragged.csv",
        &format!("# grid: 2x2\n{h}\n{},7\n", row(0.0, 4)),
    );
    assert_eq!(at(&e).0, 3);
    let mut nan = row(0.0, 4);
    nan = nan.replacen(",4,", ",NaN,", 1);
    let e = bad(
        "nan.csv",
        &format!("# grid: 2x2\n{h}\n{nan}\n{}\n", row(0.1, 4)),
    );
    // columns are character columns (the recording reader's), here the NaN cell's first
    assert_eq!((at(&e).0, at(&e).1), (3, nan.find("NaN").unwrap() + 1));
    let e = bad("units.csv", &format!("# units: inch\n{h}\n"));
    assert!(at(&e).2.contains("inch"));
    let e = bad(
        "time.csv",
        &format!("# grid: 2x2\n{h}\n{}\n{}\n", row(0.5, 4), row(0.5, 4)),
    );
    assert_eq!(at(&e).0, 4);
    let e = bad("one.csv", &format!("# grid: 2x2\n{h}\n{}\n", row(0.0, 4)));
    assert!(at(&e).2.contains("at least two"), "{e}");
    let e = bad(
        "nogrid.csv",
        &format!("{h}\n{}\n{}\n", row(0.0, 4), row(0.1, 4)),
    );
    assert!(at(&e).2.contains("# grid"));
    let e = bad("header.csv", "time,marker[1].x,marker[2].y,marker[1].z\n");
    assert_eq!((at(&e).0, at(&e).1), (1, "time,marker[1].x,".len() + 1));
}
