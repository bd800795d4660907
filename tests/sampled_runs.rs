//! Runs read off the solver's continuous extension (`Torso::advance_sampled`) and runs read
//! off the periodic breath (`TorsoMarkers::run_periodic`) against plain runs that stop the
//! solver at every frame.

use breathing_torso::dynamics::Params;
use breathing_torso::fit::{MarkerSource, TorsoMarkers, Trajectory};
use breathing_torso::model::{Config, Drive, Quantity, Torso, Wave};
use nalgebra::Point3;

fn config() -> Config {
    let mut c = Config::default();
    c.scene.level_of_detail = 0;
    c
}

fn drive(f: f64, ribs: f64, diaphragm: f64) -> Drive {
    Drive {
        enabled: true,
        frequency: f,
        inspiratory_fraction: 0.5,
        ribs: Wave {
            amplitude: ribs,
            phase: -1.6,
        },
        diaphragm: Wave {
            amplitude: diaphragm,
            phase: -1.5,
        },
        abdominals: Wave::default(),
    }
}

fn frames(start: f64, n: usize) -> Vec<f64> {
    (0..n).map(|k| start + k as f64 / 56.0).collect()
}

fn max_distance(a: &[Vec<Point3<f64>>], b: &[Vec<Point3<f64>>]) -> f64 {
    a.iter()
        .zip(b)
        .flat_map(|(x, y)| x.iter().zip(y).map(|(p, q)| (p - q).norm()))
        .fold(0.0, f64::max)
}

/// The interpolated frames agree with frames the solver stopped at, to about its
/// tolerance, the run ends where `advance_to` ends, and it takes fewer steps.
#[test]
fn sampled_frames_match_frames_the_solver_stops_at() {
    let times = frames(0.0, 225);
    // a plain run whose steps end on every frame
    let mut exact = config();
    exact.solver.step_past_outputs = false;
    let mut plain = Torso::new(exact).unwrap();
    plain.set_drive(Drive::quiet()).unwrap();
    let mut lung_plain = Vec::new();
    let mut markers_plain = Vec::new();
    for &t in &times {
        plain.advance_to(t).unwrap();
        lung_plain.push(plain.read(Quantity::LungVolume).unwrap());
        markers_plain.push(plain.markers().unwrap().to_vec());
    }
    let mut sampled = Torso::new(config()).unwrap();
    sampled.set_drive(Drive::quiet()).unwrap();
    let mut lung = vec![f64::NAN; times.len()];
    let mut markers = vec![Vec::new(); times.len()];
    let stats = sampled
        .advance_sampled(4.0, &times, &mut |k, s| {
            assert_eq!(s.time(), times[k]);
            lung[k] = s.read(Quantity::LungVolume)?;
            markers[k] = s.markers()?.to_vec();
            Ok(())
        })
        .unwrap();
    assert_eq!(sampled.time(), 4.0);
    let dl = lung
        .iter()
        .zip(&lung_plain)
        .map(|(a, b)| (a - b).abs())
        .fold(0.0, f64::max);
    let dm = max_distance(&markers, &markers_plain);
    println!(
        "max lung difference {dl:.2e} L, markers {dm:.2e} m; steps {} (plain {})",
        stats.steps,
        plain.solver_stats().steps
    );
    assert!(dl < 1e-5, "lung volumes differ by {dl} L");
    assert!(dm < 1e-6, "markers differ by {dm} m");
    assert!(stats.steps < plain.solver_stats().steps);
    plain.advance_to(4.0).unwrap();
    let end = (sampled.read(Quantity::LungVolume).unwrap()
        - plain.read(Quantity::LungVolume).unwrap())
    .abs();
    assert!(end < 1e-5, "end states differ by {end} L");
}

/// Bad output times are rejected naming the entry, and the instance does not move; an
/// error from the visitor leaves the instance at a state it reached, whose reads are its own.
#[test]
fn bad_output_times_and_visitor_errors_lose_nothing() {
    let mut t = Torso::new(config()).unwrap();
    t.set_drive(Drive::quiet()).unwrap();
    t.advance_to(0.5).unwrap();
    let y0 = t.state().to_vec();
    for (times, t_end, needle) in [
        (vec![0.6, 0.55], 1.0, "output time [1]"),
        (vec![0.4], 1.0, "output time [0]"),
        (vec![0.6, 1.5], 1.0, "output time [1]"),
        (vec![0.6, f64::NAN], 1.0, "output time [1]"),
        (vec![0.6], 0.2, "time"),
    ] {
        let e = t
            .advance_sampled(t_end, &times, &mut |_, _| Ok(()))
            .unwrap_err()
            .to_string();
        assert!(e.contains(needle), "{e}");
        assert_eq!(t.time(), 0.5);
        assert_eq!(t.state(), y0.as_slice());
    }
    let times = frames(0.6, 200);
    let e = t
        .advance_sampled(5.0, &times, &mut |k, _| {
            if k == 100 {
                Err(breathing_torso::Error::State("stop here".into()))
            } else {
                Ok(())
            }
        })
        .unwrap_err();
    assert!(e.to_string().contains("stop here"));
    // the instance is at the end of the stretch it interpolated in, with that state's reads
    let at = t.time();
    assert!(at > 0.5 && at < 5.0, "{at}");
    let lung = t.read(Quantity::LungVolume).unwrap();
    let mut other = Torso::new(config()).unwrap();
    other.set_drive(Drive::quiet()).unwrap();
    other.advance_to(at).unwrap();
    assert!((lung - other.read(Quantity::LungVolume).unwrap()).abs() < 1e-5);
    // and goes on from there
    t.advance_to(at + 0.5).unwrap();
}

/// Quiet breathing read off its periodic breath: whole breaths simulated until one repeats
/// (three, instead of the five and a half the frames span), every frame from that breath on
/// within 0.2 um and 20 nL of the plain run from rest.
#[test]
fn periodic_runs_read_the_later_breaths_off_one_breath() {
    let d = drive(0.25, 0.2, 0.25);
    let times = frames(4.0, 1009);
    let mut periodic = TorsoMarkers::new(config()).unwrap();
    let mut a = Trajectory::default();
    periodic.run(&[(0.0, d)], &times, true, &mut a).unwrap();
    let report = periodic.last_run();
    println!("{report:?}");
    assert!(report.periodic);
    let breaths = report.simulated_s / 4.0;
    assert!(
        (breaths - breaths.round()).abs() < 1e-9 && breaths <= 3.0,
        "{breaths} breaths"
    );
    assert!(report.period_mismatch_m <= 1e-7);
    let mut plain = TorsoMarkers::new(config()).unwrap();
    plain.set_periodic(false);
    let mut b = Trajectory::default();
    plain.run(&[(0.0, d)], &times, true, &mut b).unwrap();
    assert!(!plain.last_run().periodic);
    assert!(plain.last_run().simulated_s >= *times.last().unwrap());
    // from the breath the periodic run found periodic on, the plain run's transient has
    // decayed below the periodicity tolerance too (the frames before it are read off the
    // periodic breath, the plain run's are still the transient)
    let settled = times.partition_point(|t| *t < report.simulated_s - 4.0);
    let dm = max_distance(&a.markers[settled..], &b.markers[settled..]);
    let dl = a.lung_volume[settled..]
        .iter()
        .zip(&b.lung_volume[settled..])
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    println!(
        "periodic vs plain from {} s: markers {dm:.2e} m, lung {dl:.2e} L",
        times[settled]
    );
    assert!(dm < 2e-7, "markers differ by {dm} m");
    assert!(dl < 2e-5, "lung volumes differ by {dl} L");
    // later frames repeat with the period
    let k = 300;
    assert_eq!(a.markers[k], a.markers[k + 224]);
}

/// A faster, stronger drive needs a third breath before its response is periodic; the
/// frames of the breath before are then read off the periodic one too (the periodic
/// response, not the transient). A drive whose response never settles within the frames
/// falls back to simulating all of them, and so do drives with too few breaths.
#[test]
fn periodic_runs_check_breath_by_breath_and_fall_back() {
    let mut m = TorsoMarkers::new(config()).unwrap();
    let mut plain = TorsoMarkers::new(config()).unwrap();
    plain.set_periodic(false);
    let d = Drive {
        enabled: true,
        frequency: 0.4,
        inspiratory_fraction: 0.5,
        ribs: Wave {
            amplitude: 0.8,
            phase: 0.0,
        },
        diaphragm: Wave {
            amplitude: 0.8,
            phase: 1.0,
        },
        abdominals: Wave::default(),
    };
    let times = frames(2.5, 1009);
    let (mut a, mut b) = (Trajectory::default(), Trajectory::default());
    m.run(&[(0.0, d)], &times, false, &mut a).unwrap();
    plain.run(&[(0.0, d)], &times, false, &mut b).unwrap();
    let r = m.last_run();
    println!("{r:?}");
    let breaths = r.simulated_s / 2.5;
    assert!(r.periodic && (breaths - breaths.round()).abs() < 1e-9 && breaths <= 4.0);
    // from the breath found periodic on, the two agree
    let later = times.partition_point(|t| *t < r.simulated_s - 2.5);
    let dm = max_distance(&a.markers[later..], &b.markers[later..]);
    assert!(dm < 2e-7, "{dm}");
    // and the periodic run's second-breath frames are those one period later
    assert!(max_distance(&a.markers[..10], &a.markers[140..150]) < 1e-12);

    // a lightly damped model (damping ratio 0.01 instead of 1): its response from rest still
    // rings at the end of the frames, so it is never found periodic (at 0.02 it rang until
    // the dome's membrane edges became tension-only, whose slack edges now damp it out)
    let mut light = config();
    let mut p = Params::for_posture(light.subject.posture);
    p.damping_ratio = 0.01;
    light.params = Some(p);
    let mut lm = TorsoMarkers::new(light.clone()).unwrap();
    let mut lplain = TorsoMarkers::new(light).unwrap();
    lplain.set_periodic(false);
    let ribs_only = drive(0.25, 0.3, 0.0);
    let times = frames(4.0, 1009);
    lm.run(&[(0.0, ribs_only)], &times, false, &mut a).unwrap();
    lplain
        .run(&[(0.0, ribs_only)], &times, false, &mut b)
        .unwrap();
    let r = lm.last_run();
    println!("{r:?}");
    assert!(!r.periodic && r.simulated_s >= *times.last().unwrap());
    assert!(r.period_mismatch_m > 1e-7);
    let d = max_distance(&a.markers, &b.markers);
    assert!(d < 1e-6, "{d}");

    // frames ending within the second breath: plain
    let short = frames(4.0, 200);
    m.run(&[(0.0, drive(0.25, 0.2, 0.25))], &short, false, &mut a)
        .unwrap();
    assert!(!m.last_run().periodic && m.last_run().period_mismatch_m.is_nan());
    assert!((m.last_run().simulated_s - short[199]).abs() < 1e-12);
    // frames into the fourth breath: the second one, the first to repeat itself (the
    // transient from rest has decayed below 0.1 um within the first), serves them
    let short = frames(4.0, 560);
    m.run(&[(0.0, drive(0.25, 0.2, 0.25))], &short, false, &mut a)
        .unwrap();
    println!("{:?}", m.last_run());
    assert!(m.last_run().periodic && (m.last_run().simulated_s - 8.0).abs() < 1e-9);
}

/// A drive schedule (breath-to-breath variability) is simulated over every frame, each
/// segment from its start, and agrees with stopping at every frame.
#[test]
fn schedules_switch_drives_at_their_times() {
    let times = frames(0.0, 400);
    let schedule = [
        (0.0, drive(0.25, 0.2, 0.25)),
        (3.0, drive(0.3, 0.3, 0.2)),
        (5.5, drive(0.2, 0.1, 0.3)),
    ];
    let mut m = TorsoMarkers::new(config()).unwrap();
    let mut a = Trajectory::default();
    m.run(&schedule, &times, true, &mut a).unwrap();
    let mut t = Torso::new(config()).unwrap();
    // from the rest pose, as the fit's runs
    t.start_at_rest();
    t.set_drive(schedule[0].1).unwrap();
    let mut next = 1;
    let mut worst: f64 = 0.0;
    for (k, &tk) in times.iter().enumerate() {
        while next < schedule.len() && schedule[next].0 <= tk {
            t.advance_to(schedule[next].0).unwrap();
            t.set_drive(schedule[next].1).unwrap();
            next += 1;
        }
        t.advance_to(tk).unwrap();
        let lung = t.read(Quantity::LungVolume).unwrap();
        worst = worst.max((lung - a.lung_volume[k]).abs());
        let dm = t
            .markers()
            .unwrap()
            .iter()
            .zip(&a.markers[k])
            .map(|(p, q)| (p - q).norm())
            .fold(0.0, f64::max);
        assert!(dm < 1e-6, "frame {k}: markers differ by {dm} m");
    }
    assert!(worst < 1e-5, "lung volumes differ by {worst} L");
}

/// The fit's default tolerances (rtol 1e-6, atol 1e-8): the periodic run's markers agree
/// with an rtol 1e-9 run within 0.1 um, and its lung volume within 1 uL.
#[test]
fn the_fit_tolerance_keeps_markers_within_a_tenth_of_a_micrometre() {
    let d = drive(0.25, 0.2, 0.25);
    let times = frames(4.0, 1009);
    let run = |rtol: f64, atol: f64| {
        let mut c = config();
        c.solver.rtol = rtol;
        c.solver.atol = atol;
        let mut m = TorsoMarkers::new(c).unwrap();
        let mut a = Trajectory::default();
        m.run(&[(0.0, d)], &times, true, &mut a).unwrap();
        assert!(m.last_run().periodic);
        a
    };
    let reference = run(1e-9, 1e-11);
    let fit = run(1e-6, 1e-8);
    let dm = max_distance(&fit.markers, &reference.markers);
    let dl = fit
        .lung_volume
        .iter()
        .zip(&reference.lung_volume)
        .map(|(x, y)| (x - y).abs())
        .fold(0.0, f64::max);
    println!("rtol 1e-6 vs 1e-9: markers {dm:.2e} m, lung {dl:.2e} L");
    assert!(dm < 1e-7, "markers differ by {dm} m");
    assert!(dl < 1e-6, "lung volumes differ by {dl} L");
}
