//! The rib-cage lining: the inner wall of the thoracic cavity, as rings of points carried
//! rigidly by the ribs, the sternum and the spine (ribs 1-7, thesis 1.3.2), closed at the top
//! over the thoracic inlet and joined at the bottom to the costal margin, where the diaphragm
//! inserts. Together with the diaphragm dome it closes the thoracic cavity (thesis 4.2:
//! V_thorax = V_trunk - V_abdomen).

use super::skeleton::{Rib, Side, Sternum, point_at, polyline_length, rib_index};
use super::{Anchor, Body};
use nalgebra::{Point3, Vector3};
use std::f64::consts::PI;

/// Number of lining rings (rib levels 1-7, the true ribs that close on the sternum).
pub const RINGS: usize = 7;

/// Inward offset of the lining from the rib centrelines [m]: half a rib's thickness plus the
/// intercostal layer and parietal pleura.
pub const WALL_THICKNESS: f64 = 0.015;

/// One ring: anchors going dorsal midline -> right side -> sternum -> left side.
pub fn ring_anchors(
    level: usize,
    ribs: &[Rib],
    sternum: &Sternum,
    points_per_ring: usize,
) -> Vec<Anchor> {
    let right = &ribs[rib_index(level, Side::Right)];
    let left = &ribs[rib_index(level, Side::Left)];
    let notch = sternum.costal_notches[level - 1];
    let dorsal = Point3::new(
        0.5 * (right.head.x + left.head.x),
        0.5 * (right.head.y + left.head.y),
        0.0,
    );
    // Closed path pieces with the body carrying each: (polyline, body).
    let mut pieces: Vec<(Vec<Point3<f64>>, Body)> = Vec::new();
    pieces.push((vec![dorsal, right.head], Body::Ground));
    pieces.push((right.polyline(), Body::Rib(right.index() as u8)));
    pieces.push((
        vec![*right.polyline().last().unwrap_or(&notch), notch],
        Body::Sternum,
    ));
    let mut left_line = left.polyline();
    left_line.reverse();
    pieces.push((vec![notch, left_line[0]], Body::Sternum));
    pieces.push((left_line, Body::Rib(left.index() as u8)));
    pieces.push((vec![left.head, dorsal], Body::Ground));
    let lengths: Vec<f64> = pieces.iter().map(|(p, _)| polyline_length(p)).collect();
    let total: f64 = lengths.iter().sum();
    let mut raw = Vec::with_capacity(points_per_ring);
    for i in 0..points_per_ring {
        let mut s = total * i as f64 / points_per_ring as f64;
        let last = pieces.len() - 1;
        for (k, ((poly, body), len)) in pieces.iter().zip(&lengths).enumerate() {
            if s <= *len || k == last {
                raw.push((point_at(poly, s), *body));
                break;
            }
            s -= len;
        }
    }
    // Offset inward, toward the ring's centroid in the horizontal plane.
    let centroid = raw.iter().fold(Vector3::zeros(), |a, (p, _)| a + p.coords) / raw.len() as f64;
    raw.into_iter()
        .map(|(p, body)| {
            let mut d = centroid - p.coords;
            d.y = 0.0;
            let n = d.norm();
            let shift = if n > 1e-9 {
                d * (WALL_THICKNESS.min(0.5 * n) / n)
            } else {
                Vector3::zeros()
            };
            Anchor {
                body,
                rest: p + shift,
            }
        })
        .collect()
}

/// Points per lining ring.
pub const POINTS_PER_RING: usize = 32;

/// Builds the lining triangles, appending their anchors: a cap over the thoracic inlet (rib 1),
/// quads between the rings of ribs 1-7, and a band from ring 7 down to the abdomen's
/// costal-margin loop (zipped by azimuth). Oriented outward as part of the thoracic cavity.
pub fn build(
    ribs: &[Rib],
    sternum: &Sternum,
    abdomen: &super::Abdomen,
    anchors: &mut Vec<Anchor>,
) -> Vec<[u32; 3]> {
    let m = POINTS_PER_RING;
    let rings: Vec<Vec<u32>> = (1..=RINGS)
        .map(|level| {
            ring_anchors(level, ribs, sternum, m)
                .into_iter()
                .map(|a| super::push_anchor(anchors, a.body, a.rest))
                .collect()
        })
        .collect();
    let mut tris = Vec::new();
    // Cap: a fan over ring 1 from its first point (dorsal midline).
    let r0 = &rings[0];
    for i in 1..m - 1 {
        tris.push([r0[0], r0[i + 1], r0[i]]);
    }
    // Tube: ring k above ring k+1; points run dorsal -> right -> ventral -> left.
    for k in 0..RINGS - 1 {
        let (a, b) = (&rings[k], &rings[k + 1]);
        for i in 0..m {
            let j = (i + 1) % m;
            tris.push([a[i], a[j], b[i]]);
            tris.push([a[j], b[j], b[i]]);
        }
    }
    // Band: zip ring 7 and the rim loop by azimuth about the cavity axis.
    let last = &rings[RINGS - 1];
    let az = |i: u32| {
        let p = anchors[i as usize].rest;
        super::abdomen::azimuth(p.x, p.z, abdomen.axis_x)
    };
    let mut upper: Vec<(f64, u32)> = last.iter().map(|&i| (az(i), i)).collect();
    let mut lower: Vec<(f64, u32)> = abdomen
        .rim
        .iter()
        .map(|&v| (az(abdomen.anchor[v as usize]), abdomen.anchor[v as usize]))
        .collect();
    upper.sort_by(|a, b| a.0.total_cmp(&b.0));
    lower.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (nu, nl) = (upper.len(), lower.len());
    let (mut i, mut j) = (0usize, 0usize);
    while i < nu || j < nl {
        let (ui, un) = (upper[i % nu], upper[(i + 1) % nu]);
        let (li, ln) = (lower[j % nl], lower[(j + 1) % nl]);
        let next_u = if i + 1 < nu { un.0 } else { un.0 + 2.0 * PI };
        let next_l = if j + 1 < nl { ln.0 } else { ln.0 + 2.0 * PI };
        if j >= nl || (i < nu && next_u <= next_l) {
            tris.push([ui.1, un.1, li.1]);
            i += 1;
        } else {
            tris.push([ui.1, ln.1, li.1]);
            j += 1;
        }
    }
    // Orientation: the side wall's normals must point away from the axis.
    let probe = tris[tris.len() / 2];
    let [pa, pb, pc] = probe.map(|v| anchors[v as usize].rest);
    let normal = (pb - pa).cross(&(pc - pa));
    let centre = (pa.coords + pb.coords + pc.coords) / 3.0;
    let outward = Vector3::new(centre.x - abdomen.axis_x, 0.0, centre.z);
    if normal.dot(&outward) < 0.0 {
        for t in tris.iter_mut() {
            t.swap(1, 2);
        }
    }
    tris
}
