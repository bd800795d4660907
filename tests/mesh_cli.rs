//! `torso mesh prepare | info | tetra` end to end through the binary.

mod mesh_support;

use std::process::Command;

use breathing_torso::mesh::{Bvh, io, pipeline::read_prepared};
use mesh_support::{folded_sphere, noisy_ellipsoid};
use nalgebra::{Point3, Vector3};

fn torso(args: &[&str]) -> (bool, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

#[test]
fn prepare_info_and_tetra() {
    let dir = std::env::temp_dir().join(format!("torso_mesh_cli_{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let mut skin = folded_sphere(4);
    skin.scale(&Point3::origin(), &Vector3::new(0.15, 0.3, 0.15));
    let (_, mut abd) = noisy_ellipsoid(Vector3::new(0.1, 0.12, 0.16), 4, 0.01, 9);
    abd.translate(&Vector3::new(0.0, -0.1, 0.0));
    let (s, a) = (dir.join("skin.stl"), dir.join("abdomen.off"));
    io::write(&skin, &s).unwrap();
    io::write(&abd, &a).unwrap();

    let (ok, out, err) = torso(&["mesh", "info", s.to_str().unwrap()]);
    assert!(ok, "{err}");
    assert!(out.contains("self-intersections"), "{out}");
    assert!(!out.contains("self-intersections  0\n"), "{out}");

    let prepared = dir.join("prepared");
    let (ok, out, err) = torso(&[
        "mesh",
        "prepare",
        "--skin",
        s.to_str().unwrap(),
        "--abdomen",
        a.to_str().unwrap(),
        "--out",
        prepared.to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("# Mesh preparation report"));
    let p = read_prepared(&prepared).unwrap();
    let skin_bvh = Bvh::new(&p.skin);
    assert!(
        p.abdomen
            .as_ref()
            .unwrap()
            .vertices
            .iter()
            .all(|v| skin_bvh.contains(v))
    );
    assert!(prepared.join("report.json").exists() && prepared.join("report.md").exists());

    let (ok, out, err) = torso(&[
        "mesh",
        "info",
        "--json",
        prepared.join("skin.obj").to_str().unwrap(),
    ]);
    assert!(ok, "{err}");
    let info: serde_json::Value = serde_json::from_str(&out).unwrap();
    assert_eq!(info["self_intersections"], 0);
    assert_eq!(info["topology"]["boundary_edges"], 0);

    let vtk = dir.join("abdomen_tets.vtk");
    let (ok, out, err) = torso(&[
        "mesh",
        "tetra",
        prepared.join("abdomen.obj").to_str().unwrap(),
        "--out",
        vtk.to_str().unwrap(),
        "--cells",
        "12",
    ]);
    assert!(ok, "{err}");
    assert!(out.contains("dihedral angles"), "{out}");
    assert!(
        std::fs::read_to_string(&vtk)
            .unwrap()
            .contains("DATASET UNSTRUCTURED_GRID")
    );

    // malformed input names the file and line
    let bad = dir.join("bad.obj");
    std::fs::write(&bad, "v 0 0 0\nv 1 0 0\nf 1 2 3\n").unwrap();
    let (ok, _, err) = torso(&["mesh", "info", bad.to_str().unwrap()]);
    assert!(!ok);
    assert!(err.contains("bad.obj:3:"), "{err}");
}
