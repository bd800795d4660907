//! Thoraco-abdominal coordination over one breath: the phase angle between the rib-cage and
//! the abdominal displaced volumes by the Lissajous method, and the rib-cage share of the
//! displaced volume.
//!
//! Phase angle (Agostoni & Mognoni 1966, J. Appl. Physiol. 21:1827-1832; as computed by
//! Prisk, Hammer & Newth 2002, Pediatr. Pulmonol. 34:462-472, and reviewed by Hammer &
//! Newth 2009, Paediatr. Respir. Rev. 10:75-80): on the Konno-Mead loop of one breath (rib cage on one
//! axis, abdomen on the other), `m` is the distance between the two abdominal values where
//! the rib cage passes the midpoint of its excursion, and `s` the whole abdominal
//! excursion; sin(phi) = m / s. The loop's major axis sloping down (the two compartments
//! moving in opposite directions) puts phi beyond 90 deg: phi = 180 - asin(m / s). For two
//! sinusoids of any amplitudes and offsets the formula is exact. The sign is this
//! project's: positive when the abdomen leads the rib cage (read off the direction in which
//! the loop is traversed), as the fit's delta phase is positive when the diaphragm leads;
//! 0 is synchronous motion, +-180 deg fully paradoxical motion.
//!
//! Rib-cage share (Konno & Mead 1967, J. Appl. Physiol. 22:407-422: the volume the chest
//! wall displaces is the sum of a rib-cage and an abdominal part): the rib-cage swing over
//! the sum of the rib-cage and abdominal swings (largest minus smallest displaced volume in
//! the breath), as the model's breath summary states it.

/// The Lissajous phase angle [deg] of `abdomen` relative to `rib_cage` over one breath
/// (samples of one breath, the loop closing on itself; see the module doc). `None` when the
/// lengths differ, there are fewer than 4 samples, a compartment does not move, or the rib
/// cage does not pass the midpoint of its excursion both ways.
pub fn lissajous_phase_deg(rib_cage: &[f64], abdomen: &[f64]) -> Option<f64> {
    let n = rib_cage.len();
    if n < 4 || abdomen.len() != n {
        return None;
    }
    let (rlo, rhi) = range(rib_cage);
    let (alo, ahi) = range(abdomen);
    let s = ahi - alo;
    if !(rhi > rlo && s > 0.0 && s.is_finite()) {
        return None;
    }
    let mid = 0.5 * (rlo + rhi);
    // The abdominal values where the rib cage crosses its midpoint going up and going down
    // (linear interpolation within the sample interval; the loop is closed by the interval
    // from the last sample back to the first).
    let (mut up, mut down) = (None, None);
    for k in 0..n {
        let j = (k + 1) % n;
        let (a, b) = (rib_cage[k] - mid, rib_cage[j] - mid);
        let w = if a != b { a / (a - b) } else { 0.0 };
        let at = abdomen[k] + w * (abdomen[j] - abdomen[k]);
        if a < 0.0 && b >= 0.0 && up.is_none() {
            up = Some(at);
        } else if a > 0.0 && b <= 0.0 && down.is_none() {
            down = Some(at);
        }
    }
    let m = (up? - down?).abs();
    let mut phi = (m / s).min(1.0).asin().to_degrees();
    // Covariance sign: the loop's major axis slopes down beyond 90 deg.
    let (rm, am) = (mean(rib_cage), mean(abdomen));
    let cov: f64 = rib_cage
        .iter()
        .zip(abdomen)
        .map(|(r, a)| (r - rm) * (a - am))
        .sum();
    if cov < 0.0 {
        phi = 180.0 - phi;
    }
    // Signed area of the loop (x rib cage, y abdomen), shoelace over the closed polygon:
    // for rib cage sin(u) and abdomen sin(u + phi) it is -pi sin(phi), negative when the
    // abdomen leads.
    let area: f64 = (0..n)
        .map(|k| {
            let j = (k + 1) % n;
            (rib_cage[k] - rm) * (abdomen[j] - am) - (rib_cage[j] - rm) * (abdomen[k] - am)
        })
        .sum();
    Some(if area > 0.0 { -phi } else { phi })
}

/// The rib-cage share of one breath's displaced volume: rib-cage swing over the sum of the
/// rib-cage and abdominal swings (module doc); NaN when neither moves.
pub fn rib_cage_share(rib_cage: &[f64], abdomen: &[f64]) -> f64 {
    let (rlo, rhi) = range(rib_cage);
    let (alo, ahi) = range(abdomen);
    let (rc, ab) = (rhi - rlo, ahi - alo);
    if rc + ab > 0.0 {
        rc / (rc + ab)
    } else {
        f64::NAN
    }
}

fn range(x: &[f64]) -> (f64, f64) {
    x.iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &v| {
            (lo.min(v), hi.max(v))
        })
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len() as f64
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::f64::consts::PI;

    /// One period of rib cage a sin(u) + c and abdomen b sin(u + phi) + d, n samples.
    fn pair(phi_deg: f64, n: usize, start: f64) -> (Vec<f64>, Vec<f64>) {
        let phi = phi_deg.to_radians();
        (0..n)
            .map(|k| {
                let u = start + 2.0 * PI * k as f64 / n as f64;
                (0.3 * u.sin() + 1.2, 0.7 * (u + phi).sin() - 0.4)
            })
            .unzip()
    }

    #[test]
    fn phase_of_sinusoids_is_recovered_with_sign() {
        for phi in [
            0.0, 5.0, 20.0, 45.0, 89.0, 90.0, 100.0, 135.0, 170.0, -10.0, -60.0, -120.0, -175.0,
        ] {
            for start in [0.0, 1.1, 4.0] {
                let (rc, ab) = pair(phi, 112, start);
                let got = lissajous_phase_deg(&rc, &ab).unwrap();
                // 112 samples per breath (4 s at 28 Hz, h = 2 pi / 112): the sampled
                // excursion s and the interpolated m err by at most h^2 / 8 = 4e-4 of s,
                // which moves phi by 4e-4 / cos(phi) rad, under 0.5 deg more than 10 deg
                // from 90 deg; near 90 deg asin is flat and the error is up to
                // sqrt(2 * 4e-4) rad = 1.6 deg.
                let tol = if (phi.abs() - 90.0).abs() > 10.0 {
                    0.5
                } else {
                    1.7
                };
                assert!(
                    (got - phi).abs() < tol,
                    "phi {phi} start {start}: got {got}"
                );
            }
        }
    }

    #[test]
    fn degenerate_breaths_give_none() {
        assert_eq!(lissajous_phase_deg(&[1.0; 10], &[0.0, 1.0].repeat(5)), None);
        assert_eq!(lissajous_phase_deg(&[0.0, 1.0], &[0.0, 1.0]), None);
        assert_eq!(lissajous_phase_deg(&[0.0, 1.0, 2.0], &[0.0, 1.0]), None);
    }

    #[test]
    fn rib_cage_share_is_swing_ratio() {
        let (rc, ab) = pair(30.0, 100, 0.0);
        // Swings 0.6 and 1.4 (up to sampling of the extremes).
        let share = rib_cage_share(&rc, &ab);
        assert!((share - 0.3).abs() < 2e-3, "{share}");
        assert!(rib_cage_share(&[1.0; 4], &[2.0; 4]).is_nan());
    }
}
