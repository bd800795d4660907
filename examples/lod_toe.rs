//! How the tension-only law's smooth toe ([`breathing_torso::dynamics::Params::tension_toe`],
//! a fixed width in newtons on every element) sets the passive-and-active law's quiet breath
//! at the levels of detail: for the default upright subject under that law and its quiet
//! drive, the tidal volume at levels 0, 1 and 2 with the toe scaled by each factor given (1
//! and 0.5 by default), the gap of levels 0 and 1 to level 2, and, from the second factor on,
//! each level's change against the first factor. Two breaths after a settling one, as
//! `tests/lod_convergence.rs` measures them. A slack element pulls toe x ln 2 whatever its
//! size, so the mesh's finer levels, with more and smaller elements, carry more of that pull
//! (docs/dynamics.md, "What keeps the hill law from being the default").
//!
//! `cargo run --release --example lod_toe [FACTOR ...]`

use breathing_torso::Torso;
use breathing_torso::dynamics::muscle::MuscleLaw;
use breathing_torso::model::run::{run, summarise};
use breathing_torso::model::{Config, Drive};

/// The quiet tidal volume [L] at level `lod` with the toe scaled by `factor`.
fn tidal_volume(lod: u32, factor: f64) -> f64 {
    let law = MuscleLaw::Hill;
    let drive = Drive::quiet_for(law);
    let mut config = Config {
        drive,
        muscle_law: law,
        ..Config::default()
    };
    config.scene.level_of_detail = lod;
    let mut p = config.model_params();
    p.tension_toe *= factor;
    config.params = Some(p);
    let mut torso = Torso::new(config).expect("the default subject");
    let period = 1.0 / drive.frequency;
    let frames = run(&mut torso, 3.0 * period, 28.0).expect("quiet breathing");
    summarise(&frames, period).tidal_volume
}

fn main() {
    let mut factors: Vec<f64> = std::env::args()
        .skip(1)
        .map(|s| s.parse().expect("a factor"))
        .collect();
    if factors.is_empty() {
        factors = vec![1.0, 0.5];
    }
    let mut first: Option<Vec<f64>> = None;
    for &f in &factors {
        let vt: Vec<f64> = (0..3).map(|lod| tidal_volume(lod, f)).collect();
        print!(
            "toe x{f}: quiet VT {:.4} / {:.4} / {:.4} L at levels 0 / 1 / 2; level 0 \
             {:+.1} %, level 1 {:+.1} % of level 2",
            vt[0],
            vt[1],
            vt[2],
            100.0 * (vt[0] / vt[2] - 1.0),
            100.0 * (vt[1] / vt[2] - 1.0)
        );
        match &first {
            None => first = Some(vt),
            Some(v) => print!(
                "; against x{}: {:+.2} / {:+.2} / {:+.2} %",
                factors[0],
                100.0 * (vt[0] / v[0] - 1.0),
                100.0 * (vt[1] / v[1] - 1.0),
                100.0 * (vt[2] / v[2] - 1.0)
            ),
        }
        println!();
    }
}
