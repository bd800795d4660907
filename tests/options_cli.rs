//! The `torso` options behave alike across subcommands, run as a user runs the binary: one
//! name for the ODE solver (`--solver`; `simulate` and `render-skin` still take their former
//! `--method`), no solver options where none is used, negative numbers read as values and
//! checked against their range, errors naming the flag typed rather than the FMI variable, a
//! readable drive line, a warning instead of a tidal volume for runs shorter than a breath,
//! no folders created outside the working directory, grids of 1..16 as in the FMU, and
//! `render-skin` writing into the working directory by default.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A fresh empty folder for one test.
fn scratch(name: &str) -> PathBuf {
    let dir = std::env::temp_dir().join(format!("options_cli_{name}_{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// Runs `torso args` in `dir`: (exit code, stdout, stderr).
fn torso_in(dir: &Path, args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(args)
        .current_dir(dir)
        .output()
        .expect("run torso");
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
    )
}

fn torso(args: &[&str]) -> (i32, String, String) {
    torso_in(&std::env::temp_dir(), args)
}

/// A fast scene for the runs that integrate.
const FAST: [&str; 4] = ["--lod", "0", "--rtol", "1e-4"];

#[test]
fn the_solver_option_is_solver_everywhere() {
    for cmd in [
        &["simulate"][..],
        &["render-skin"],
        &["fit", "--slp", "missing.csv"],
        &["synth", "--out", "r.csv", "--truth", "t.json"],
    ] {
        let args: Vec<&str> = cmd.iter().copied().chain(["--solver", "rk99"]).collect();
        let (code, _, err) = torso(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(
            err.contains("invalid value rk99 for `--solver`"),
            "{args:?}: {err}"
        );
        let help = torso(&[cmd[0], "--help"]).1;
        assert!(
            help.contains("--solver <SOLVER>"),
            "{} --help:\n{help}",
            cmd[0]
        );
    }
    // the former name still works where it meant the solver, and is not advertised
    for cmd in ["simulate", "render-skin"] {
        let (code, _, err) = torso(&[cmd, "--method", "rk99"]);
        assert_eq!(code, 1, "{cmd}: {err}");
        assert!(err.contains("`--solver`"), "{cmd}: {err}");
        let help = torso(&[cmd, "--help"]).1;
        assert!(!help.contains("--method"), "{cmd} --help:\n{help}");
    }
    // fit's --method stays its search method
    let (_, _, err) = torso(&["fit", "--slp", "missing.csv", "--method", "rk99"]);
    assert!(err.contains("nelder-mead"), "{err}");
}

#[test]
fn export_obj_takes_no_solver_options() {
    for flag in ["--solver", "--method", "--rtol"] {
        let (code, _, err) = torso(&["export-obj", flag, "1e-3", "out"]);
        assert_eq!(code, 2, "export-obj {flag}: {err}");
        assert!(
            err.contains(&format!("unexpected argument '{flag}'")),
            "{err}"
        );
    }
}

#[test]
fn negative_numbers_are_values_and_errors_name_the_flag() {
    for cmd in [
        &["simulate"][..],
        &["render-skin"],
        &["export-obj", "out"],
        &["fit", "--slp", "missing.csv"],
        &["synth", "--out", "r.csv", "--truth", "t.json"],
    ] {
        let args: Vec<&str> = cmd.iter().copied().chain(["--stature", "-1"]).collect();
        let (code, _, err) = torso(&args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(
            err.contains("invalid value -1 for `--stature`: allowed range is [1.4, 2.1]"),
            "{args:?}: {err}"
        );
    }
    for (args, flag) in [
        (&["simulate", "--age", "200"][..], "--age"),
        (&["simulate", "--breast-size", "-0.5"], "--breast-size"),
        (&["simulate", "--lod", "5"], "--lod"),
        (&["simulate", "--rtol", "-1e-6"], "--rtol"),
        (&["simulate", "--frequency", "-0.2"], "--frequency"),
        (&["simulate", "--ribs-amplitude", "2"], "--ribs-amplitude"),
        (&["simulate", "--posture", "upside-down"], "--posture"),
        (&["simulate", "--scenario", "panting"], "--scenario"),
        (&["simulate", "--duration", "-3"], "--duration"),
        (&["fit", "--slp", "missing.csv", "--mass", "500"], "--mass"),
        (&["simulate", "--ti-ttot", "0.9"], "--ti-ttot"),
        (
            &[
                "synth",
                "--out",
                "r.csv",
                "--truth",
                "t.json",
                "--ti-ttot",
                "-0.4",
            ],
            "--ti-ttot",
        ),
        (
            &["fit", "--slp", "missing.csv", "--ti-ttot", "often"],
            "--ti-ttot",
        ),
        (&["bench", "core", "--ti-ttot", "0.1"], "--ti-ttot"),
    ] {
        let (code, _, err) = torso(args);
        assert_eq!(code, 1, "{args:?}: {err}");
        assert!(err.contains(&format!("for `{flag}`")), "{args:?}: {err}");
        for fmi in ["subject.", "drive.", "scene.", "solver."] {
            assert!(!err.contains(fmi), "{args:?} names an FMI variable: {err}");
        }
    }
}

#[test]
fn a_request_for_help_is_answered_wherever_it_stands() {
    // A real-valued option takes values starting with '-', so these once read `--help` as the
    // tolerance or the stature and reported it as not a number.
    for (args, usage) in [
        (
            &["simulate", "--rtol", "--help"][..],
            "Usage: torso simulate",
        ),
        (&["simulate", "--stature", "-h"], "Usage: torso simulate"),
        (
            &["fit", "--slp", "x.csv", "--ti-ttot", "--help"],
            "Usage: torso fit",
        ),
        (
            &["bench", "core", "--rtol", "--help"],
            "Usage: torso bench core",
        ),
    ] {
        let (code, out, err) = torso(args);
        assert_eq!(code, 0, "{args:?}: {err}");
        assert!(out.contains(usage), "{args:?}:\n{out}\n{err}");
        assert!(!err.contains("invalid value"), "{args:?}: {err}");
    }
    // A value that merely starts like a flag is still a value.
    let (code, _, err) = torso(&["simulate", "--rtol", "-help"]);
    assert_ne!(code, 0, "{err}");
    assert!(err.contains("'-help' for '--rtol"), "{err}");
}

#[test]
fn simulate_prints_a_readable_drive_and_warns_on_short_runs() {
    let dir = scratch("short");
    let args: Vec<&str> = ["simulate", "--duration", "2"]
        .into_iter()
        .chain(FAST)
        .collect();
    let (code, out, err) = torso_in(&dir, &args);
    assert_eq!(code, 0, "{out}{err}");
    assert!(!out.contains("Drive {") && !out.contains("Wave {"), "{out}");
    assert!(
        out.contains("drive: 0.25 Hz (15.0 breaths/min)")
            && out.contains("ribs 0.096 at +0.000 rad")
            && out.contains("diaphragm 0.240 at +0.100 rad"),
        "{out}"
    );
    assert!(
        err.contains("warning: the run (2 s) is shorter than one breath (4 s at 0.25 Hz)"),
        "{err}"
    );
    assert!(!out.contains("tidal volume"), "{out}");
    // one breath is enough for a tidal volume, and then no warning
    let args: Vec<&str> = ["simulate", "--duration", "4"]
        .into_iter()
        .chain(FAST)
        .collect();
    let (code, out, err) = torso_in(&dir, &args);
    assert_eq!(code, 0, "{out}{err}");
    let tv: f64 = out
        .lines()
        .find_map(|l| l.strip_prefix("tidal volume"))
        .and_then(|l| l.trim().strip_suffix('L'))
        .map(|v| v.trim().parse().unwrap())
        .unwrap_or_else(|| panic!("no tidal volume in\n{out}"));
    assert!(tv > 0.2, "tidal volume {tv} L of a quiet breath");
    assert!(!err.contains("warning"), "{err}");
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn outputs_create_folders_only_below_the_working_directory() {
    let dir = scratch("out");
    let missing = format!("/nonexistent_torso_{}", std::process::id());
    let out_file = format!("{missing}/x.csv");
    let (code, _, err) = torso_in(&dir, &["simulate", "--duration", "0.1", "--out", &out_file]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(&format!(
            "output folder {missing} does not exist; create it first"
        )),
        "{err}"
    );
    assert!(!Path::new(&missing).exists(), "{missing} was created");
    // `..` leaves the working directory too
    let (code, _, err) = torso_in(&dir, &["simulate", "--out", "../options_cli_up/x.csv"]);
    assert_eq!(code, 1, "{err}");
    assert!(err.contains("does not exist; create it first"), "{err}");
    assert!(!dir.join("../options_cli_up").exists());
    // a relative folder, and an absolute one under the working directory, are created
    let args: Vec<&str> = ["simulate", "--duration", "0.1", "--out", "a/b/x.csv"]
        .into_iter()
        .chain(FAST)
        .collect();
    let (code, out, err) = torso_in(&dir, &args);
    assert_eq!(code, 0, "{out}{err}");
    assert!(dir.join("a/b/x.csv").is_file());
    let cwd = std::fs::canonicalize(&dir).unwrap();
    let absolute = cwd.join("c/x.csv");
    let args: Vec<&str> = ["simulate", "--duration", "0.1", "--out"]
        .into_iter()
        .chain([absolute.to_str().unwrap()])
        .chain(FAST)
        .collect();
    let (code, out, err) = torso_in(&cwd, &args);
    assert_eq!(code, 0, "{out}{err}");
    assert!(absolute.is_file());
    // an output folder named outright is made when its parent exists, as mkdir would
    let other = scratch("out_elsewhere");
    let named = other.join("gen");
    let (code, out, err) = torso_in(&dir, &["export-obj", "--lod", "0", named.to_str().unwrap()]);
    assert_eq!(code, 0, "{out}{err}");
    assert!(named.join("skin.obj").is_file());
    let deep = format!("{missing}/gen");
    let (code, _, err) = torso_in(&dir, &["export-obj", "--lod", "0", &deep]);
    assert_eq!(code, 1, "{err}");
    assert!(
        err.contains(&format!("output folder {missing} does not exist")),
        "{err}"
    );
    assert!(!Path::new(&missing).exists(), "{missing} was created");
    let _ = std::fs::remove_dir_all(&other);
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn grids_of_one_to_sixteen_as_in_the_fmu() {
    let dir = scratch("grid");
    let args = [
        "synth",
        "--grid",
        "1x1",
        "--duration",
        "1",
        "--out",
        "r.csv",
        "--truth",
        "t.json",
    ];
    let args: Vec<&str> = args.into_iter().chain(FAST).collect();
    let (code, out, err) = torso_in(&dir, &args);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("of a 1x1 grid"), "{out}");
    let head = std::fs::read_to_string(dir.join("r.csv")).unwrap();
    assert!(head.starts_with("# grid: 1x1"), "{head}");
    for bad in ["0x6", "17x6", "10x", "ten"] {
        let (code, _, err) = torso_in(
            &dir,
            &[
                "synth", "--grid", bad, "--out", "r.csv", "--truth", "t.json",
            ],
        );
        assert_eq!(code, 1, "--grid {bad}: {err}");
        assert!(
            err.contains(&format!(
                "invalid value {bad} for `--grid`: allowed range is ROWSxCOLS with 1..16 each"
            )),
            "{err}"
        );
    }
    let _ = std::fs::remove_dir_all(&dir);
}

#[test]
fn render_skin_writes_into_the_working_directory() {
    let dir = scratch("render");
    let args: Vec<&str> = ["render-skin"].into_iter().chain(FAST).collect();
    let (code, out, err) = torso_in(&dir, &args);
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("wrote skin.png"), "{out}");
    let png = std::fs::read(dir.join("skin.png")).unwrap();
    assert_eq!(&png[1..4], b"PNG");
    assert!(!dir.join("docs").exists(), "render-skin wrote into docs/");
    let _ = std::fs::remove_dir_all(&dir);
}

/// A reader that closes the pipe early (`torso simulate ... | head -1`) ends the run quietly:
/// on Unix by SIGPIPE, as command-line tools end, not by a panic on the failed write (exit
/// code 101 and "failed printing to stdout" on stderr).
#[cfg(unix)]
#[test]
fn a_closed_pipe_ends_the_run_without_a_panic() {
    use std::io::{BufRead, BufReader};
    use std::os::unix::process::ExitStatusExt;
    use std::process::Stdio;
    let mut child = Command::new(env!("CARGO_BIN_EXE_torso"))
        .args(["simulate", "--duration", "30", "--out", "/dev/stdout"])
        .args(FAST)
        .current_dir(std::env::temp_dir())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .expect("run torso");
    let mut first = String::new();
    BufReader::new(child.stdout.take().unwrap())
        .read_line(&mut first)
        .unwrap();
    // The reader is dropped here: the pipe is closed after one line.
    let out = child.wait_with_output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!first.is_empty());
    assert!(!stderr.contains("panicked"), "{stderr}");
    assert_eq!(out.status.signal(), Some(13), "{:?} {stderr}", out.status);
}
