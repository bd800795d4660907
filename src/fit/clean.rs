//! What real recordings carry besides the breath, found and repaired before a fit: label
//! swaps and ghost markers (a marker's jump against its neighbours), and gaps longer than a
//! breath (left out, never interpolated).
//!
//! - **Jumps.** Between two frames where a marker is tracked, its motion less the median
//!   motion of its [`NEIGHBOURS`] nearest markers (tracked in both frames) is its jump:
//!   breathing, sway and drift move neighbours alike, so the jump of a marker that stays
//!   on its skin point is noise. A jump over the threshold (the larger of [`JUMP_M`], a
//!   marker's diameter, and [`JUMP_NOISE`] robust standard deviations of all jumps) plus
//!   the neighbours' own spread (the median of their motions' distances from their median
//!   motion: across a gap during a deep breath, neighbours move differently) is an event.
//! - **Label swaps.** Two markers jumping at the same frame, each onto where the other was
//!   (within the threshold), swapped labels: their columns are exchanged from that frame on
//!   (a later swap back is found the same way and exchanges them again).
//! - **Ghosts.** A marker jumping away and later back (a reflection, a mislabelled
//!   marker): the frames between are left out (missing); one that jumps away and never
//!   comes back is left out from the jump on (the first frame's position is the one bound
//!   to the skin). A marker with more than [`MAX_EVENTS`] such events is left out of the
//!   recording; when over a third of the markers are, the recording is refused.
//! - **Long gaps** ([`long_gaps`]): a marker untracked for longer than a breath is left out
//!   there, not interpolated: the fit's cost only ever compares tracked samples, and the
//!   breath detection (the principal displacement, [`super::principal`]) leaves out the
//!   marker coordinates with such a gap rather than draw a line across a breath.
//!
//! Every repair is a sentence naming the marker, the frames (1-based) and their times.

use crate::{Error, Result};
use nalgebra::{Point3, Vector3};

/// Least jump that is an event [m]: a motion-capture marker's diameter (10-14 mm), the
/// least distance between two markers both tracked, so the least a swap moves a label.
pub const JUMP_M: f64 = 0.010;
/// Jumps over this many robust standard deviations (1.4826 MAD per coordinate, times
/// sqrt 3 for the length) of all jumps are events however noisy the recording.
pub const JUMP_NOISE: f64 = 8.0;
/// Neighbours a marker's jump is taken against.
pub const NEIGHBOURS: usize = 4;
/// A marker with more jump events than this is left out of the recording.
pub const MAX_EVENTS: usize = 6;
/// Repair passes (each repairs every swap it finds, then the jumps are found again).
const PASSES: usize = 8;

/// A recording's frames after the repairs, and what was done.
#[derive(Clone, Debug, PartialEq)]
pub struct Cleaned {
    /// Per frame, per marker (the input's order): the repaired position, `None` where left
    /// out.
    pub frames: Vec<Vec<Option<Point3<f64>>>>,
    /// One sentence per repair.
    pub notes: Vec<String>,
    /// Label swaps repaired: (marker, marker, frame index).
    pub swaps: Vec<(usize, usize, usize)>,
    /// Ghost segments left out: (marker, first frame, frame after the last).
    pub ghosts: Vec<(usize, usize, usize)>,
    /// Markers left out of the whole recording.
    pub dropped: Vec<usize>,
    /// The jump threshold used [m].
    pub threshold_m: f64,
}

/// A jump of marker `marker` from frame `from` to frame `at`.
#[derive(Clone, Copy, Debug)]
struct Jump {
    marker: usize,
    from: usize,
    at: usize,
    size: f64,
    spread: f64,
}

/// Each marker's nearest neighbours, from the first tracked position of every marker.
fn neighbours(frames: &[Vec<Option<Point3<f64>>>]) -> Vec<Vec<usize>> {
    let points = frames.first().map_or(0, Vec::len);
    let first: Vec<Option<Point3<f64>>> = (0..points)
        .map(|p| frames.iter().find_map(|f| f[p]))
        .collect();
    (0..points)
        .map(|p| {
            let Some(a) = first[p] else {
                return Vec::new();
            };
            let mut d: Vec<(f64, usize)> = (0..points)
                .filter(|&q| q != p)
                .filter_map(|q| first[q].map(|b| ((b - a).norm(), q)))
                .collect();
            d.sort_by(|x, y| x.0.total_cmp(&y.0));
            d.into_iter().take(NEIGHBOURS).map(|x| x.1).collect()
        })
        .collect()
}

/// One marker's motion between two tracked frames against its neighbours'.
#[derive(Clone, Copy, Debug)]
struct Motion {
    marker: usize,
    from: usize,
    at: usize,
    /// The marker's motion less the neighbours' median motion.
    relative: Vector3<f64>,
    /// How differently the neighbours moved: the median of their motions' distances from
    /// their median motion (noise between consecutive frames; across a gap during a deep
    /// breath, the breath's differences over the trunk).
    spread: f64,
}

/// Every marker's motion between consecutive tracked frames against its neighbours'.
fn relative_motions(frames: &[Vec<Option<Point3<f64>>>], near: &[Vec<usize>]) -> Vec<Motion> {
    let points = frames.first().map_or(0, Vec::len);
    let mut out = Vec::new();
    for p in 0..points {
        let mut last: Option<usize> = None;
        for (i, f) in frames.iter().enumerate() {
            let Some(x) = f[p] else { continue };
            if let Some(j) = last {
                let x0 = frames[j][p].unwrap_or(x);
                // The neighbours' median motion per coordinate: one of them jumping (a
                // ghost, a swap) does not move it.
                let moved: Vec<Vector3<f64>> = near[p]
                    .iter()
                    .filter_map(|&q| match (frames[j][q], f[q]) {
                        (Some(a), Some(b)) => Some(b - a),
                        _ => None,
                    })
                    .collect();
                let common = if moved.is_empty() {
                    Vector3::zeros()
                } else {
                    Vector3::from_fn(|a, _| median_signed(moved.iter().map(|v| v[a]).collect()))
                };
                let spread = if moved.is_empty() {
                    0.0
                } else {
                    median_signed(moved.iter().map(|v| (v - common).norm()).collect())
                };
                out.push(Motion {
                    marker: p,
                    from: j,
                    at: i,
                    relative: (x - x0) - common,
                    spread,
                });
            }
            last = Some(i);
        }
    }
    out
}

/// The median of `v` (the mean of the middle two for an even count).
fn median_signed(mut v: Vec<f64>) -> f64 {
    v.sort_by(|a, b| a.total_cmp(b));
    let n = v.len();
    if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    }
}

fn median(mut v: Vec<f64>) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mid = v.len() / 2;
    *v.select_nth_unstable_by(mid, |a, b| a.total_cmp(b)).1
}

/// The jump threshold of `frames` (see the module doc).
fn threshold(motions: &[Motion]) -> f64 {
    let components: Vec<f64> = motions
        .iter()
        .flat_map(|m| {
            let r = m.relative;
            [r.x.abs(), r.y.abs(), r.z.abs()]
        })
        .collect();
    let sigma = 1.4826 * median(components);
    if sigma.is_finite() {
        JUMP_M.max(JUMP_NOISE * sigma * 3f64.sqrt())
    } else {
        JUMP_M
    }
}

/// Finds and repairs label swaps and ghosts in `frames` (per frame, per marker; `labels`
/// name the markers, `times` the frames). See the module doc.
pub fn clean(
    times: &[f64],
    labels: &[String],
    frames: &[Vec<Option<Point3<f64>>>],
) -> Result<Cleaned> {
    let points = frames.first().map_or(0, Vec::len);
    let mut out = frames.to_vec();
    let near = neighbours(frames);
    let at = |i: usize| format!("frame {} (t = {:.3} s)", i + 1, times[i] - times[0]);
    let mut notes = Vec::new();
    let mut swaps = Vec::new();
    let motions = relative_motions(&out, &near);
    let limit = threshold(&motions);
    // Label swaps, pass by pass.
    for _ in 0..PASSES {
        let motions = relative_motions(&out, &near);
        let jumps: Vec<Jump> = motions
            .iter()
            .filter(|m| m.relative.norm() > limit + m.spread)
            .map(|m| Jump {
                marker: m.marker,
                from: m.from,
                at: m.at,
                size: m.relative.norm(),
                spread: m.spread,
            })
            .collect();
        let mut found = None;
        'search: for (k, a) in jumps.iter().enumerate() {
            for b in &jumps[k + 1..] {
                if b.at != a.at || b.marker == a.marker {
                    continue;
                }
                let (i, pa, pb) = (a.at, a.marker, b.marker);
                let (Some(xa), Some(xb), Some(ya), Some(yb)) =
                    (out[i][pa], out[i][pb], out[a.from][pa], out[b.from][pb])
                else {
                    continue;
                };
                let near_enough = limit + a.spread.max(b.spread);
                if (xa - yb).norm() < near_enough && (xb - ya).norm() < near_enough {
                    found = Some((pa, pb, i, a.size.max(b.size)));
                    break 'search;
                }
            }
        }
        let Some((pa, pb, i, size)) = found else {
            break;
        };
        for f in out.iter_mut().skip(i) {
            f.swap(pa, pb);
        }
        swaps.push((pa, pb, i));
        notes.push(format!(
            "markers {} and {} swap labels at {} (each jumps {:.1} mm against its neighbours onto the other's place): \
             repaired, their labels exchanged back from there on",
            labels[pa],
            labels[pb],
            at(i),
            size * 1e3
        ));
    }
    // Ghosts: what is left of the jumps, marker by marker.
    let motions = relative_motions(&out, &near);
    let mut per_marker: Vec<Vec<Jump>> = vec![Vec::new(); points];
    for m in motions
        .iter()
        .filter(|m| m.relative.norm() > limit + m.spread)
    {
        per_marker[m.marker].push(Jump {
            marker: m.marker,
            from: m.from,
            at: m.at,
            size: m.relative.norm(),
            spread: m.spread,
        });
    }
    let mut ghosts = Vec::new();
    let mut dropped = Vec::new();
    for (p, jumps) in per_marker.iter().enumerate() {
        if jumps.is_empty() {
            continue;
        }
        if jumps.len() > MAX_EVENTS {
            for f in out.iter_mut() {
                f[p] = None;
            }
            dropped.push(p);
            notes.push(format!(
                "marker {} jumps against its neighbours {} times (over {:.1} mm; first at {}): left out of the recording",
                labels[p],
                jumps.len(),
                limit * 1e3,
                at(jumps[0].at)
            ));
            continue;
        }
        for pair in jumps.chunks(2) {
            let start = pair[0].at;
            let end = pair.get(1).map_or(frames.len(), |j| j.at);
            for f in out.iter_mut().take(end).skip(start) {
                f[p] = None;
            }
            ghosts.push((p, start, end));
            notes.push(match pair.get(1) {
                Some(back) => format!(
                    "marker {}: a jump of {:.1} mm against its neighbours at {} and one of {:.1} mm back at {} \
                     (a ghost or a mislabelled marker): the frames between left out",
                    labels[p],
                    pair[0].size * 1e3,
                    at(start),
                    back.size * 1e3,
                    at(back.at)
                ),
                None => format!(
                    "marker {}: a jump of {:.1} mm against its neighbours at {}, never back: left out from there on",
                    labels[p],
                    pair[0].size * 1e3,
                    at(start)
                ),
            });
        }
    }
    if 3 * dropped.len() > points {
        return Err(Error::invalid(
            "recording",
            format!(
                "{} of {points} markers jumping against their neighbours more than {MAX_EVENTS} times ({})",
                dropped.len(),
                dropped
                    .iter()
                    .map(|&p| labels[p].as_str())
                    .collect::<Vec<_>>()
                    .join(", ")
            ),
            "a recording where at most a third of the markers jump (label swaps and ghosts are repaired)",
        ));
    }
    Ok(Cleaned {
        frames: out,
        notes,
        swaps,
        ghosts,
        dropped,
        threshold_m: limit,
    })
}

/// Gaps longer than `breath` seconds: (marker, first missing frame, frame after the last).
/// Leading and trailing gaps count too.
pub fn long_gaps(
    times: &[f64],
    frames: &[Vec<Option<Point3<f64>>>],
    breath: f64,
) -> Vec<(usize, usize, usize)> {
    let points = frames.first().map_or(0, Vec::len);
    let n = frames.len();
    let mut out = Vec::new();
    for p in 0..points {
        let tracked: Vec<bool> = frames.iter().map(|f| f[p].is_some()).collect();
        let mut i = 0;
        while i < n {
            if tracked[i] {
                i += 1;
                continue;
            }
            let start = i;
            while i < n && !tracked[i] {
                i += 1;
            }
            // The gap spans from the last tracked frame before it to the first after it.
            let t0 = times[start.saturating_sub(1)];
            let t1 = times[i.min(n - 1)];
            if t1 - t0 > breath {
                out.push((p, start, i));
            }
        }
    }
    out
}
