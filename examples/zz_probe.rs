use breathing_torso::Torso;
use breathing_torso::anatomy::Posture;
use breathing_torso::dynamics::Params;
use breathing_torso::dynamics::muscle::MuscleLaw;
use breathing_torso::model::run::{run, summarise};
use breathing_torso::model::{Config, Drive};

type Edit = fn(&mut Params);
fn main() -> breathing_torso::Result<()> {
    let cases: [(&str, Edit); 1] = [("base", |_| {})];
    let acting = std::env::args().any(|a| a == "--acting");
    for posture in [Posture::Standing, Posture::Supine] {
        for (name, edit) in cases {
            let mut config = Config::default();
            config.subject.posture = posture;
            config.muscle_law = MuscleLaw::Hill;
            if acting {
                config.gravity_loads = breathing_torso::dynamics::GravityLoads::Acting;
            }
            let mut p = config.model_params();
            edit(&mut p);
            config.params = Some(p);
            config.drive = Drive::quiet_for(MuscleLaw::Hill);
            let period = 1.0 / config.drive.frequency;
            let mut torso = Torso::new(config)?;
            let frames = run(&mut torso, 3.0 * period, 28.0)?;
            let s = summarise(&frames, period);
            println!(
                "{posture:?} {name:22} VT {:.3} L EEV {:.3} rib share {:.1} % dome {:.2} cm/L",
                s.tidal_volume,
                s.end_expiratory_volume,
                100.0 * s.rib_cage_share,
                100.0 * s.dome_excursion / s.tidal_volume
            );
        }
    }
    Ok(())
}
