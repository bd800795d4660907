//! Level-of-detail agreement of the compartment split and of the marker grid: for the default
//! upright subject at levels of detail 0, 1 and 2, the peak-to-trough swings over the second
//! breath of the lung volume, the rib-cage and abdominal displaced volumes (ribs alone driven,
//! then the default quiet drive, with its rib-cage share) and the ventral (x) swing of each
//! row of the default 10 x 6 marker grid (mean over the row's columns), each row's rest
//! height given against the lowest point of the costal margin; and how many abdominal-wall
//! patches the skinning groups the wall's handles into.
//!
//! `cargo run --release --example lod_compartments`

use breathing_torso::model::Drive;
use breathing_torso::observe::costal_margin_height;
use breathing_torso::observe::markers::MarkerModel;
use breathing_torso::observe::skinning::{HandleKind, InfluenceSource};
use breathing_torso::{Config, Quantity, Torso};

/// Peak-to-trough swings over the second breath: lung, rib cage, abdomen [L], and each
/// marker's x [m]; with each marker's rest height [m].
fn swings(lod: u32, drive: Drive) -> (f64, f64, f64, Vec<f64>, Vec<f64>, usize, f64) {
    let mut config = Config::default();
    config.scene.level_of_detail = lod;
    config.drive = drive;
    let cols = config.scene.grid_cols;
    let n = config.scene.grid_rows * cols;
    let mut torso = Torso::new(config).unwrap();
    let compiled = torso.compiled().clone();
    let margin = costal_margin_height(&compiled.model);
    let markers = MarkerModel::with_first_frame(
        &compiled.anatomy,
        &compiled.model,
        torso.config().scene.grid_rows,
        cols,
        None,
    )
    .unwrap();
    let patches = markers
        .skinning()
        .influences()
        .iter()
        .filter(|f| matches!(f.source, InfluenceSource::TranslationGroup(_)))
        .count();
    let wall = markers
        .handles()
        .iter()
        .filter(|h| h.kind == HandleKind::Translation)
        .count();
    println!("LOD {lod}: {wall} wall handles in {patches} patches");
    let marker = |t: &mut Torso, i: usize, axis: u8| {
        t.read(Quantity::Marker {
            index: i as u16,
            axis,
        })
        .unwrap()
    };
    let heights: Vec<f64> = (0..n).map(|i| marker(&mut torso, i, 1)).collect();
    let period = 1.0 / torso.config().drive.frequency;
    let rate = 56.0;
    let mut lo = vec![f64::INFINITY; 3 + n];
    let mut hi = vec![f64::NEG_INFINITY; 3 + n];
    for k in 1..=(2.0 * period * rate).round() as usize {
        let t = k as f64 / rate;
        torso.advance_to(t).unwrap();
        if t < period - 1e-9 {
            continue;
        }
        let mut v = vec![
            torso.read(Quantity::LungVolume).unwrap(),
            torso.read(Quantity::RibCageDisplaced).unwrap(),
            torso.read(Quantity::AbdomenDisplaced).unwrap(),
        ];
        v.extend((0..n).map(|i| marker(&mut torso, i, 0)));
        for (j, x) in v.iter().enumerate() {
            lo[j] = lo[j].min(*x);
            hi[j] = hi[j].max(*x);
        }
    }
    let s: Vec<f64> = lo.iter().zip(&hi).map(|(a, b)| b - a).collect();
    (s[0], s[1], s[2], s[3..].to_vec(), heights, cols, margin)
}

fn main() {
    for lod in 0..=2 {
        let mut ribs = Drive::quiet();
        ribs.diaphragm.amplitude = 0.0;
        let (lung, rc, _, _, _, _, _) = swings(lod, ribs);
        println!("LOD {lod} ribs only: lung {lung:.4} L, rib-cage displaced {rc:.4} L");
        let (lung, rc, ab, m, h, cols, margin) = swings(lod, Drive::quiet());
        println!(
            "LOD {lod} quiet: lung {lung:.4} L, rib cage {rc:.4} L, abdomen {ab:.4} L, rib-cage share {:.1} %",
            100.0 * rc / (rc + ab)
        );
        for (r, row) in m.chunks(cols).enumerate() {
            let y = h[r * cols..(r + 1) * cols].iter().sum::<f64>() / cols as f64;
            let mean = row.iter().sum::<f64>() / cols as f64;
            println!(
                "  row {r}: {:+6.1} cm from the costal margin, AP swing {:.2} mm",
                100.0 * (y - margin),
                1e3 * mean
            );
        }
    }
}
