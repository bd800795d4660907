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
/// Unsourced: no source: chosen by hand in the first anatomy (commit 270ac4a); only the
/// intercostal layer's 3 mm (De Troyer 1998) is cited elsewhere. No rib depth (cutaneous to
/// pleural surface) was read: the CT studies of rib cross-sections (Holcombe et al. 2019, J Anat
/// 235:883; Front Bioeng Biotechnol 2023, doi:10.3389/fbioe.2023.1158242) give areas in their
/// full texts. The whole chest wall, skin to pleura, is 42.4 mm (95 % CI 39.7-45.2) at the
/// second intercostal space, midclavicular line, on CT of 111 patients (Givens, Ayotte &
/// Manifold 2004, Acad Emerg Med 11:211): not comparable (fat and pectoral muscle lie outside
/// the ribs); ours with the skin's 18 mm room outside the centreline (`BONE_CLEARANCE`) is at
/// least 33 mm.
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
    // Tube: ring k above ring k+1; points run dorsal -> right -> ventral -> left. Each quad's
    // diagonal is mirrored between the two halves so that the surface is left-right symmetric.
    for k in 0..RINGS - 1 {
        let (a, b) = (&rings[k], &rings[k + 1]);
        for i in 0..m {
            let j = (i + 1) % m;
            if i < m / 2 {
                tris.push([a[i], a[j], b[i]]);
                tris.push([a[j], b[j], b[i]]);
            } else {
                tris.push([a[i], b[j], b[i]]);
                tris.push([a[i], a[j], b[j]]);
            }
        }
    }
    // Band: zip ring 7 and the rim loop by azimuth about the cavity axis over the right half
    // (dorsal to ventral midline), then mirror it onto the left half.
    let last = &rings[RINGS - 1];
    // Azimuth on the right half, with points on the midline pinned to 0 (dorsal) or pi.
    let az = |i: u32| {
        let p = anchors[i as usize].rest;
        if p.z.abs() < 1e-12 {
            if p.x < abdomen.axis_x { 0.0 } else { PI }
        } else {
            super::abdomen::azimuth(p.x, p.z, abdomen.axis_x)
        }
    };
    let on_right = |(_, i): &(f64, u32)| anchors[*i as usize].rest.z > -1e-12;
    let mut upper: Vec<(f64, u32)> = last.iter().map(|&i| (az(i), i)).filter(on_right).collect();
    let mut lower: Vec<(f64, u32)> = abdomen
        .rim
        .iter()
        .map(|&v| (az(abdomen.anchor[v as usize]), abdomen.anchor[v as usize]))
        .filter(on_right)
        .collect();
    upper.sort_by(|a, b| a.0.total_cmp(&b.0));
    lower.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut band = Vec::new();
    let (nu, nl) = (upper.len(), lower.len());
    let (mut i, mut j) = (0usize, 0usize);
    while i + 1 < nu || j + 1 < nl {
        let advance_upper = j + 1 >= nl || (i + 1 < nu && upper[i + 1].0 <= lower[j + 1].0);
        if advance_upper {
            band.push([upper[i].1, upper[i + 1].1, lower[j].1]);
            i += 1;
        } else {
            band.push([upper[i].1, lower[j + 1].1, lower[j].1]);
            j += 1;
        }
    }
    // Mirror: ring point i <-> m - i; rim vertices by position.
    let mirror = |v: u32| -> u32 {
        if let Some(i) = last.iter().position(|&q| q == v) {
            return last[(m - i) % m];
        }
        let p = anchors[v as usize].rest;
        abdomen
            .rim
            .iter()
            .map(|&r| abdomen.anchor[r as usize])
            .find(|&q| {
                let o = anchors[q as usize].rest;
                (o.x - p.x).abs() < 1e-12 && (o.y - p.y).abs() < 1e-12 && (o.z + p.z).abs() < 1e-12
            })
            .unwrap_or(v)
    };
    let mirrored: Vec<[u32; 3]> = band
        .iter()
        .map(|t| [mirror(t[0]), mirror(t[2]), mirror(t[1])])
        .filter(|t| t[0] != t[1] && t[1] != t[2] && t[0] != t[2])
        .collect();
    // Close the gaps at the midlines where the rim has no vertex on them: one triangle joining
    // the end of each half to its mirror image.
    let on_midline = |v: u32| anchors[v as usize].rest.z.abs() < 1e-12;
    let mut joins = Vec::new();
    if let (Some(u0), Some(l0)) = (upper.first(), lower.first())
        && !on_midline(l0.1)
    {
        joins.push([u0.1, l0.1, mirror(l0.1)]);
    }
    if let (Some(un), Some(ln)) = (upper.last(), lower.last())
        && !on_midline(ln.1)
    {
        joins.push([un.1, mirror(ln.1), ln.1]);
    }
    tris.extend(band);
    tris.extend(mirrored);
    tris.extend(joins);
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
