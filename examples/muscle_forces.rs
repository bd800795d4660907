//! The respiratory muscles' largest forces as the generated anatomy lays them out, and the
//! lengths they are spread over.
//!
//! `cargo run --release --example muscle_forces` prints, for the default subject (man, 30 y,
//! 1.75 m, 75 kg) at each level of detail: the length of the diaphragm's insertion line (the
//! closed rim of costal-margin insertions along which `DIAPHRAGM_FORCE` is shared), the summed
//! interspace length of each intercostal layer (along which `INTERCOSTAL_TENSION` is spread).
//! These are the lengths that turn a muscle's thickness into its cross-section in
//! `docs/respiratory_muscles.md` (section F). `-- --all` adds the default woman and the sitting
//! and supine postures.

use breathing_torso::anatomy::{
    Anatomy, DIAPHRAGM_FORCE, INTERCOSTAL_TENSION, MuscleGroup, Posture, Sex, Subject,
};

fn rim_length(anatomy: &Anatomy) -> f64 {
    let abdomen = &anatomy.abdomen;
    let at = |v: u32| anatomy.anchors[abdomen.anchor[v as usize] as usize].rest;
    let rim = &abdomen.rim;
    let m = rim.len();
    (0..m)
        .map(|i| (at(rim[(i + 1) % m]) - at(rim[i])).norm())
        .sum()
}

fn report(subject: &Subject, lod: u32) -> Result<(), Box<dyn std::error::Error>> {
    let anatomy = Anatomy::build(subject, lod)?;
    let layer = |g: MuscleGroup| -> f64 {
        anatomy
            .muscles
            .iter()
            .filter(|e| e.group == g)
            .map(|e| e.max_force)
            .sum::<f64>()
            / INTERCOSTAL_TENSION
    };
    let rim = rim_length(&anatomy);
    println!(
        "{:?} {:.2} m {:.0} kg {:?}, level {lod}: diaphragm insertion line {:.1} cm ({} rim points), DIAPHRAGM_FORCE {:.0} N = {:.0} N/m of insertion",
        subject.sex,
        subject.stature,
        subject.mass,
        subject.posture,
        rim * 100.0,
        anatomy.abdomen.rim.len(),
        DIAPHRAGM_FORCE,
        DIAPHRAGM_FORCE / rim
    );
    println!(
        "  intercostal interspaces (22, both sides): external layer {:.2} m, internal layer {:.2} m, at INTERCOSTAL_TENSION {:.0} N/m",
        layer(MuscleGroup::ExternalIntercostals),
        layer(MuscleGroup::InternalIntercostals),
        INTERCOSTAL_TENSION
    );
    Ok(())
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let all = std::env::args().any(|a| a == "--all");
    let man = Subject::default();
    for lod in 0..=2 {
        report(&man, lod)?;
    }
    if all {
        let woman = Subject {
            sex: Sex::Female,
            stature: 1.63,
            mass: 60.0,
            ..Subject::default()
        };
        report(&woman, 1)?;
        for posture in [Posture::Sitting, Posture::Supine] {
            report(
                &Subject {
                    posture,
                    ..Subject::default()
                },
                1,
            )?;
        }
    }
    Ok(())
}
