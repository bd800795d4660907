//! Overlaps between surfaces (Peeters & Pronost 2013, section 3.6): a surface that must stay
//! inside another (abdominal cavity inside the skin) or outside it (cavity not through the
//! ribs). Penetrating vertices, found by signed distance (BVH closest point and ray-parity
//! point-in-mesh), are pushed along the fixed surface's normal to a margin from it, their
//! neighbourhood is smoothed with a short Taubin filter, and the two steps repeat until no
//! vertex penetrates and no triangles of the two surfaces cross.

use nalgebra::Vector3;

use super::{Bvh, Taubin, TriMesh};
use crate::{Error, Result};

/// Where the moving surface must lie relative to the fixed one.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Relation {
    /// Inside the fixed closed surface (an organ inside the skin).
    Inside,
    /// Outside the fixed closed surface (an organ that must not enter a bone).
    Outside,
}

/// Options of [`resolve_overlap`].
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct OverlapOptions {
    /// Required relation of the moving surface to the fixed one.
    pub relation: Relation,
    /// Clearance kept from the fixed surface, in mesh units (> 0).
    pub margin: f64,
    /// Rings of neighbours around moved vertices that are smoothed with them.
    pub smoothing_rings: usize,
    /// Push-and-smooth rounds before giving up.
    pub max_iterations: usize,
}

impl OverlapOptions {
    /// `relation` with a margin of half the moving surface's mean edge length, 2 smoothing
    /// rings and 50 rounds.
    pub fn for_mesh(moving: &TriMesh, relation: Relation) -> OverlapOptions {
        OverlapOptions {
            relation,
            margin: 0.5 * moving.mean_edge_length(),
            smoothing_rings: 2,
            max_iterations: 50,
        }
    }
}

/// What [`resolve_overlap`] did.
#[derive(Debug, Clone, Default, PartialEq, serde::Serialize)]
pub struct OverlapReport {
    /// Vertices violating the relation (within the margin) at the start.
    pub penetrating_at_start: usize,
    /// Crossing triangle pairs at the start.
    pub crossing_pairs_at_start: usize,
    /// Distinct vertices moved.
    pub vertices_moved: usize,
    /// Largest displacement of a vertex.
    pub max_displacement: f64,
    /// Rounds used.
    pub iterations: usize,
}

/// Vertices of `moving` that violate `relation` to `fixed` by less than `margin` clearance.
pub fn penetrating_vertices(
    moving: &TriMesh,
    fixed: &Bvh,
    relation: Relation,
    margin: f64,
) -> Vec<u32> {
    (0..moving.vertices.len() as u32)
        .filter(|&i| violation(fixed, &moving.vertices[i as usize], relation, margin).is_some())
        .collect()
}

/// The target position of a violating point: the closest point of `fixed` moved by the
/// margin along the fixed surface's normal (inward for [`Relation::Inside`]).
fn violation(
    fixed: &Bvh,
    p: &nalgebra::Point3<f64>,
    relation: Relation,
    margin: f64,
) -> Option<nalgebra::Point3<f64>> {
    let c = fixed.closest(p)?;
    let inside = fixed.contains(p);
    let ok = match relation {
        Relation::Inside => inside && c.distance >= margin,
        Relation::Outside => !inside && c.distance >= margin,
    };
    if ok {
        return None;
    }
    let n = fixed.face_normal(c.triangle as usize);
    let sign = if relation == Relation::Inside {
        -1.0
    } else {
        1.0
    };
    // a small extra step keeps the point off the margin's boundary after smoothing
    Some(c.point + n * (sign * margin * 1.05))
}

/// Whether `p` keeps `relation` to `fixed` with clearance `margin`.
fn satisfied(fixed: &Bvh, p: &nalgebra::Point3<f64>, relation: Relation, margin: f64) -> bool {
    violation(fixed, p, relation, margin).is_none()
}

/// The first point on the segment from `p` towards `centre` (the moving surface's centroid,
/// the inward direction of a star-shaped surface) that keeps `relation` to `fixed` with 1.05
/// times the margin: 32 even steps, then bisection. None when no such point exists.
fn inward_target(
    fixed: &Bvh,
    p: &nalgebra::Point3<f64>,
    centre: &nalgebra::Point3<f64>,
    relation: Relation,
    margin: f64,
) -> Option<nalgebra::Point3<f64>> {
    let at = |t: f64| p + (centre - p) * t;
    let m = margin * 1.05;
    let steps = 32;
    let mut lo = 0.0;
    let mut hi = None;
    for k in 1..=steps {
        let t = k as f64 / steps as f64;
        if satisfied(fixed, &at(t), relation, m) {
            hi = Some(t);
            break;
        }
        lo = t;
    }
    let mut hi = hi?;
    for _ in 0..20 {
        let mid = 0.5 * (lo + hi);
        if satisfied(fixed, &at(mid), relation, m) {
            hi = mid;
        } else {
            lo = mid;
        }
    }
    Some(at(hi))
}

/// Moves vertices of `moving` until it satisfies `relation` to the closed surface `fixed`
/// with the given margin: each round pushes every violating vertex inward, along the ray to
/// the moving surface's centroid, to the first point that keeps the margin (or, when that
/// ray finds none, to the margin along `fixed`'s normal at its closest point); vertices of
/// triangles still crossing `fixed` move a margin further away from it;
/// then smooths `smoothing_rings` rings around the pushed vertices (which hold still) with
/// lambda|mu = 0.5|-0.53, N = 3. Fails when violations remain after `max_iterations`.
pub fn resolve_overlap(
    moving: &mut TriMesh,
    fixed: &TriMesh,
    opts: &OverlapOptions,
) -> Result<OverlapReport> {
    moving.validate()?;
    fixed.validate()?;
    if !(opts.margin.is_finite() && opts.margin >= 0.0) {
        return Err(Error::invalid("margin", opts.margin, "[0, inf)"));
    }
    let bvh = Bvh::new(fixed);
    let start = moving.vertices.clone();
    let centre = moving.centroid();
    let adj = moving.adjacency();
    let smooth = Taubin {
        iterations: 3,
        ..Taubin::from_pass_band(0.5, 0.1, 3)?
    };
    let mut rep = OverlapReport::default();
    let mut ever = vec![false; moving.vertices.len()];
    for it in 0..=opts.max_iterations {
        let mut bad: Vec<u32> = penetrating_vertices(moving, &bvh, opts.relation, opts.margin);
        let crossing = bvh.intersections_with(&Bvh::new(moving));
        for &(_, t) in &crossing {
            bad.extend_from_slice(&moving.triangles[t as usize]);
        }
        bad.sort_unstable();
        bad.dedup();
        if it == 0 {
            rep.penetrating_at_start =
                penetrating_vertices(moving, &bvh, opts.relation, opts.margin).len();
            rep.crossing_pairs_at_start = crossing.len();
        }
        if bad.is_empty() {
            rep.iterations = it;
            if opts.relation == Relation::Outside {
                // pushing can wrap the moving surface around the whole fixed one
                let mb = Bvh::new(moving);
                if fixed.vertices.iter().any(|p| mb.contains(p)) {
                    return Err(Error::State(
                        "the fixed surface lies inside the moving one: pushing cannot separate them".into(),
                    ));
                }
            }
            break;
        }
        if it == opts.max_iterations {
            return Err(Error::State(format!(
                "{} vertices still violate the overlap constraint after {} rounds",
                bad.len(),
                opts.max_iterations
            )));
        }
        let mut free = vec![false; moving.vertices.len()];
        for &i in &bad {
            let p = moving.vertices[i as usize];
            let target = match violation(&bvh, &p, opts.relation, opts.margin) {
                Some(fallback) => {
                    inward_target(&bvh, &p, &centre, opts.relation, opts.margin).unwrap_or(fallback)
                }
                None => {
                    // a vertex of a crossing triangle that itself keeps its clearance: move
                    // it a margin further away from the fixed surface
                    match bvh.closest(&p) {
                        Some(c) if c.distance > 0.0 => {
                            p + (p - c.point) * (opts.margin / c.distance)
                        }
                        _ => p,
                    }
                }
            };
            moving.vertices[i as usize] = target;
            free[i as usize] = true;
            ever[i as usize] = true;
        }
        let mut ring: Vec<u32> = bad.clone();
        for _ in 0..opts.smoothing_rings {
            let mut next = Vec::new();
            for &i in &ring {
                for &j in &adj.vertex_neighbours[i as usize] {
                    if !free[j as usize] {
                        free[j as usize] = true;
                        next.push(j);
                    }
                }
            }
            ring = next;
        }
        // the pushed vertices hold while their neighbourhood is smoothed around them
        for &i in &bad {
            free[i as usize] = false;
        }
        smooth.smooth_subset(moving, &free)?;
        for (i, f) in free.iter().enumerate() {
            if *f && moving.vertices[i] != start[i] {
                ever[i] = true;
            }
        }
    }
    rep.vertices_moved = ever.iter().filter(|e| **e).count();
    rep.max_displacement = moving
        .vertices
        .iter()
        .zip(&start)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max);
    Ok(rep)
}

impl Bvh {
    /// Unit normal of triangle `t` of the tree's surface.
    pub fn face_normal(&self, t: usize) -> Vector3<f64> {
        let [a, b, c] = self.corners(t);
        (b - a)
            .cross(&(c - a))
            .try_normalize(0.0)
            .unwrap_or_else(Vector3::zeros)
    }
}
