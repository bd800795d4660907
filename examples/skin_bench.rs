//! Skinning benchmarks (run with `cargo run --release --example skin_bench`): bone-heat
//! weights at start-up, 60 markers per frame, whole-skin deformation per frame. Medians.

use breathing_torso::anatomy::Subject;
use breathing_torso::anatomy::skin::{MarkerGrid, Skin};
use breathing_torso::observe::skinning::{
    HandleKind, HandlePose, Skinning, SkinningOptions, reference_handles,
};
use nalgebra::{Isometry3, Point3, Translation3, UnitQuaternion, Vector3};
use std::time::Instant;

fn median(mut v: Vec<f64>) -> f64 {
    v.sort_by(f64::total_cmp);
    v[v.len() / 2]
}

fn main() -> breathing_torso::Result<()> {
    let subject = Subject::default();
    let t = Instant::now();
    let skin = Skin::generate(&subject)?;
    println!(
        "skin generation: {:.1} ms ({} vertices)",
        t.elapsed().as_secs_f64() * 1e3,
        skin.vertices.len()
    );
    let handles = reference_handles(&subject)?;
    let opts = SkinningOptions::default();
    let mut times = Vec::new();
    let mut skinning = None;
    for _ in 0..5 {
        let t = Instant::now();
        skinning = Some(Skinning::new(
            &skin.vertices,
            &skin.triangles,
            &handles,
            &opts,
        )?);
        times.push(t.elapsed().as_secs_f64());
    }
    let skinning = skinning.expect("five runs");
    let rigid = handles
        .iter()
        .filter(|h| h.kind == HandleKind::Rigid)
        .count();
    println!(
        "weights at start-up: median {:.1} ms over 5 runs ({} rigid handles, {} translation handles in {} influences)",
        median(times) * 1e3,
        rigid,
        handles.len() - rigid,
        skinning.influences().len()
    );
    let grid = MarkerGrid::place(&skin, 10, 6)?;
    let bound = skinning.bind(&skin.triangles, &grid.bindings())?;
    let pose = |k: usize| -> Vec<HandlePose> {
        let a = 0.02 * (k as f64 * 0.01).sin();
        handles
            .iter()
            .map(|h| match h.kind {
                HandleKind::Rigid => HandlePose::Rigid(Isometry3::from_parts(
                    Translation3::new(0.0, a * 0.1, a * 0.05),
                    UnitQuaternion::from_axis_angle(&Vector3::z_axis(), a),
                )),
                HandleKind::Translation => HandlePose::Translation(Vector3::new(a * 0.2, 0.0, 0.0)),
            })
            .collect()
    };
    let poses: Vec<Vec<HandlePose>> = (0..64).map(pose).collect();
    let mut frame = skinning.frame(&poses[0])?;
    let mut markers = vec![Point3::origin(); bound.len()];
    let mut per_frame = Vec::new();
    let mut marker_only = Vec::new();
    let mut checksum = 0.0;
    for k in 0..20_000 {
        let t = Instant::now();
        skinning.frame_into(&poses[k % 64], &mut frame)?;
        let t1 = Instant::now();
        bound.evaluate(&frame, &mut markers);
        let t2 = Instant::now();
        per_frame.push((t2 - t).as_secs_f64());
        marker_only.push((t2 - t1).as_secs_f64());
        checksum += markers[17].x;
    }
    println!(
        "60 markers per frame: median {:.2} us including the handle frame, {:.2} us marker blend alone",
        median(per_frame) * 1e6,
        median(marker_only) * 1e6
    );
    let mut all = Vec::new();
    let mut whole = Vec::new();
    for k in 0..500 {
        let t = Instant::now();
        skinning.frame_into(&poses[k % 64], &mut frame)?;
        skinning.deform_all(&frame, &mut all);
        whole.push(t.elapsed().as_secs_f64());
        checksum += all[100].y;
    }
    println!(
        "whole skin ({} vertices) per frame: median {:.1} us",
        all.len(),
        median(whole) * 1e6
    );
    println!("(checksum {checksum:.3})");
    Ok(())
}
