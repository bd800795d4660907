//! Stage 1: body poses from the state, then the position and velocity of every anchor.
//!
//! A rib turns by theta about its unit hinge axis u through its head h (Rodrigues):
//! p = h + R(u, theta)(p0 - h), v = theta' u x (p - h). The sternum is a free rigid body:
//! p = x + R(q)(p0 - x0), v = x' + w x (p - x). Free vertices are read directly. The rest
//! arms p0 - h and p0 - x0 are precomputed in the [`Structure`].
//!
//! The same poses as rigid motions ([`rib_pose`], [`sternum_pose`]) drive the skinning of
//! the markers (`observe::markers`), so that the state is read into body poses in one place.
//! The right-hand side turns a rib by its Rodrigues matrix, the skinning by the unit
//! quaternion of the same axis and angle (the two agree to rounding).

use super::Data;
use super::state::Layout;
use super::structure::{RIBS, Structure};
use nalgebra::{
    Isometry3, Matrix3, Point3, Quaternion, Translation3, Unit, UnitQuaternion, Vector3,
};

/// Rotation matrix about unit axis `u` by `angle` (Rodrigues' formula).
pub fn axis_rotation(u: &Vector3<f64>, angle: f64) -> Matrix3<f64> {
    let (s, c) = angle.sin_cos();
    let k = u.cross_matrix();
    Matrix3::identity() + k * s + k * k * (1.0 - c)
}

/// The sternum's orientation (its quaternion normalised) and centre of mass at state `y`.
pub fn sternum_frame(l: &Layout, y: &[f64]) -> (UnitQuaternion<f64>, Point3<f64>) {
    let q = Quaternion::new(
        y[l.sternum_q],
        y[l.sternum_q + 1],
        y[l.sternum_q + 2],
        y[l.sternum_q + 3],
    );
    (
        UnitQuaternion::from_quaternion(q),
        Point3::new(y[l.sternum_x], y[l.sternum_x + 1], y[l.sternum_x + 2]),
    )
}

/// The sternum's motion from rest at state `y` as a rigid transform, `p -> x + R(q)(p - x0)`,
/// with `com_rest` its rest centre of mass x0.
pub fn sternum_pose(l: &Layout, y: &[f64], com_rest: &Point3<f64>) -> Isometry3<f64> {
    let (rot, x) = sternum_frame(l, y);
    Isometry3::from_parts(Translation3::from(x.coords - rot * com_rest.coords), rot)
}

/// A rib's motion from rest as a rigid transform: the turn by `theta` about the unit hinge
/// `axis` through its `head`, `p -> h + R(u, theta)(p - h)`.
pub fn rib_pose(head: &Point3<f64>, axis: &Unit<Vector3<f64>>, theta: f64) -> Isometry3<f64> {
    let rot = UnitQuaternion::from_axis_angle(axis, theta);
    let h = head.coords;
    Isometry3::from_parts(Translation3::from(h - rot * h), rot)
}

/// Fills `data.pos` and `data.vel` for all moving anchors.
pub fn positions_and_velocities(model: &Structure, data: &mut Data, l: &Layout, y: &[f64]) {
    for r in 0..RIBS {
        data.rib_rotation[r] = axis_rotation(&model.rib_axis[r], y[l.theta + r]);
    }
    (data.sternum_rotation, data.sternum_x) = sternum_frame(l, y);
    data.sternum_w = Vector3::new(y[l.sternum_w], y[l.sternum_w + 1], y[l.sternum_w + 2]);
    let sternum_v = Vector3::new(y[l.sternum_v], y[l.sternum_v + 1], y[l.sternum_v + 2]);

    // one length for both arrays, so that one index check covers them
    let m = data.pos.len();
    let (pos, vel) = (&mut data.pos[..], &mut data.vel[..m]);
    let rates = &y[l.theta_dot..l.theta_dot + RIBS];
    for ((((anchors, arms), rot), (h, u)), &rate) in model
        .rib_anchors
        .iter()
        .zip(&model.rib_arm)
        .zip(&data.rib_rotation)
        .zip(model.rib_head.iter().zip(&model.rib_axis))
        .zip(rates)
    {
        // by value: the stores to pos and vel cannot then be taken to alias them
        let (rot, h, u) = (*rot, *h, *u);
        for (&a, arm0) in anchors.iter().zip(arms) {
            let a = a as usize;
            let arm = rot * arm0;
            pos[a] = h + arm;
            vel[a] = u.cross(&arm) * rate;
        }
    }
    let rot = data.sternum_rotation.to_rotation_matrix();
    for (&a, arm0) in model.sternum_anchors.iter().zip(&model.sternum_arm) {
        let a = a as usize;
        let arm = rot * arm0;
        pos[a] = data.sternum_x + arm;
        vel[a] = sternum_v + data.sternum_w.cross(&arm);
    }
    let n3 = 3 * l.vertices;
    let xs = y[l.vertex_x..l.vertex_x + n3].chunks_exact(3);
    let vs = y[l.vertex_v..l.vertex_v + n3].chunks_exact(3);
    for ((&a, x), v) in model.vertex_anchor.iter().zip(xs).zip(vs) {
        let a = a as usize;
        pos[a] = Point3::new(x[0], x[1], x[2]);
        vel[a] = Vector3::new(v[0], v[1], v[2]);
    }
    debug_assert!(model.carrier.len() == data.pos.len());
}
