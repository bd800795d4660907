//! `torso bench physiology`: the physiological figures the chest wall is judged by
//! (`bench::physiology`), each printed with its measured value, its cited range, its source,
//! whether it is met and how it was measured; `--json` prints them as JSON instead.

use crate::Result;
use crate::bench::physiology::physiology;
use clap::Args;

/// Options of `torso bench physiology`.
#[derive(Args, Debug)]
pub struct PhysiologyArgs {
    /// Level of detail.
    #[arg(long, default_value_t = 1)]
    pub lod: u32,
    /// Print the figures as JSON.
    #[arg(long)]
    pub json: bool,
    /// Muscle law: thesis or hill (the FMU's `muscle_law`).
    #[arg(long, default_value = "thesis")]
    pub muscle_law: String,
    /// How gravity loads the model: preloaded or acting (the FMU's `gravity_loads`).
    #[arg(long, default_value = "preloaded")]
    pub gravity_loads: String,
    /// The posture's tonic muscle activity: on or off (the FMU's `postural_tone`; off, the
    /// relaxed subject whose respiratory-system compliance is the passive one).
    #[arg(long, default_value = "on")]
    pub postural_tone: String,
}

/// A range's end for printing (an infinite end as "-").
fn end(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        "-".into()
    }
}

/// Runs `torso bench physiology`.
pub fn run(args: &PhysiologyArgs) -> Result<()> {
    let law = crate::dynamics::muscle::MuscleLaw::parse(&args.muscle_law)
        .map_err(|_| crate::Error::invalid("--muscle-law", &args.muscle_law, "thesis or hill"))?;
    let gravity_loads =
        crate::dynamics::GravityLoads::parse(&args.gravity_loads).map_err(|_| {
            crate::Error::invalid(
                "--gravity-loads",
                &args.gravity_loads,
                "preloaded or acting",
            )
        })?;
    let p = physiology(
        args.lod,
        crate::bench::physiology::Laws {
            muscle: law,
            gravity_loads,
            postural_tone: crate::model::parse_postural_tone(&args.postural_tone).map_err(
                |_| crate::Error::invalid("--postural-tone", &args.postural_tone, "on or off"),
            )?,
        },
    )?;
    if args.json {
        let text = serde_json::to_string_pretty(&p)
            .map_err(|e| crate::Error::State(format!("JSON: {e}")))?;
        println!("{text}");
        return Ok(());
    }
    println!(
        "physiological figures of the default subject (male, 30 y, 1.75 m, 75 kg), level of detail {}, {:?} muscle law, gravity {:?}, postural tone {}",
        p.level_of_detail,
        p.muscle_law,
        p.gravity_loads,
        if p.postural_tone { "on" } else { "off" }
    );
    for f in &p.figures {
        println!(
            "{} {}: {:.3} {} (cited {}..{}, {}; through the {})",
            if f.met { "met   " } else { "MISSED" },
            f.name,
            f.value,
            f.unit,
            end(f.range.0),
            end(f.range.1),
            f.source,
            f.through
        );
    }
    for (what, why) in &p.failed {
        println!("FAILED {what}: {why}");
    }
    Ok(())
}
