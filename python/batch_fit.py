#!/usr/bin/env python3
"""Fit a whole study's recordings on Dask, resumably, into one table and one cohort report.

Subcommands:

* `fit DIR --out OUT`: every recording under DIR (`--glob`, `*.csv` by default, searched
  recursively) is fitted by one Dask task, on a LocalCluster (`--workers N` processes of one
  thread each, default one per core) or on an existing cluster (`--scheduler ADDRESS`). A task
  runs the native `torso fit` (`--torso PATH`) or, with `--engine fmu`, `python/fit_slp.py`
  on the FMU (`--fmu PATH`) as a subprocess, so a worker needs only the binary or the FMU;
  with `--engine package` it calls `breathing_torso.fit` (the Python package, the same
  library as `torso fit`) in the worker itself, so a worker needs only the package installed.
  Paths are passed as the driver sees them: on an existing cluster, the recordings, the output
  folder and the binary must be at the same paths on every worker (a shared file system).
  `--fit-args "..."` pass through to every fit; a file `<stem>.args` beside a recording adds
  that recording's own options (its subject, say).
* `report OUT`: the cohort report of a finished (or partial) run.
* `make-synthetic N DIR`: N synthetic recordings with seeded variety of subject, posture and
  drive (`torso synth`), each with its `.truth.json` and `.args`.
* `overhead`: Dask's own cost per task, measured with no-op tasks.

Resumable and safe: a recording's key is the sha256 of its bytes and of its fitting options.
Each finished fit writes `OUT/fits/<key>.json` (the fit's own JSON) and then, atomically,
`OUT/rows/<key>.json` (its row); the table `OUT/results.parquet` and `OUT/results.csv` is
rebuilt from the row files, so a killed worker or a killed driver loses no finished result. A
rerun skips keys whose row says `ok`. A failing task is retried twice (Dask `retries=2`) and
then recorded with `status = failed` and its error text. Every attempt appends a line to
`OUT/attempts/<key>.log`.

Fields of a fit's JSON are read defensively: one that is absent gives NaN, so that fields
`torso fit` gains later (breath timing, shares) are picked up when present.
"""

from __future__ import annotations

import argparse
import glob as globmod
import hashlib
import importlib.util
import json
import logging
import math
import os
import shlex
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
ENGINES = ("native", "fmu", "package")
#: cost / noise floor above which a fit is flagged as bad in the report.
BAD_FIT_RATIO = 1.3
#: columns of the results table, in order (more may follow).
COLUMNS = [
    "recording", "group", "key", "sha256", "options", "status", "error", "attempts",
    "tidal_volume_l", "rate_bpm", "ti_ttot", "ribcage_share", "ta_phase_deg",
    "cost_mm", "noise_floor_mm", "cost_ratio", "evaluations", "wall_s", "fit_json", "finished_utc",
]


def say(*parts):
    """Print one progress line, flushed (so that it shows when the output is piped)."""
    print(*parts, flush=True)


# ---------------------------------------------------------------------------- keys and rows

def sha256_file(path: Path) -> str:
    """The sha256 of a file's bytes, as hex."""
    h = hashlib.sha256()
    with open(path, "rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            h.update(block)
    return h.hexdigest()


def recording_options(path: Path, fit_args: list[str]) -> list[str]:
    """The fitting options of one recording: the batch's `--fit-args`, then its `<stem>.args`."""
    extra = path.with_suffix(".args")
    own = shlex.split(extra.read_text()) if extra.is_file() else []
    return list(fit_args) + own


def task_key(sha: str, engine: str, options: list[str]) -> str:
    """The key of a task: the recording's content hash and the fitting options (engine included)."""
    return hashlib.sha256(f"{sha}\n{engine}\n{shlex.join(options)}".encode()).hexdigest()[:24]


def package_keywords(options: list[str]) -> dict:
    """The keywords of `breathing_torso.fit` for `torso fit` options (`--fit-args` and a
    recording's `.args`): the subject, model and search options; a ValueError names an
    option the package engine does not take (`--out` and `--slp` are the task's own)."""
    p = argparse.ArgumentParser(prog="--engine package", add_help=False, exit_on_error=False)
    for flag in ("--sex", "--posture", "--solver", "--grid", "--units", "--method", "--ti-ttot", "--anterior"):
        p.add_argument(flag)
    for flag in ("--age", "--stature", "--mass", "--breast-size", "--rtol", "--rate"):
        p.add_argument(flag, type=float)
    for flag in ("--lod", "--max-evals", "--seed", "--threads"):
        p.add_argument(flag, type=int)
    for flag in ("--skin-fit", "--marker-offsets", "--fit-size", "--no-fit-size", "--no-drift"):
        p.add_argument(flag, action="store_true")
    try:
        a, unknown = p.parse_known_args(options)
    except argparse.ArgumentError as e:
        raise ValueError(f"--fit-args: {e}") from None
    if unknown:
        raise ValueError(f"--fit-args: {' '.join(unknown)}: not an option --engine package passes to the fit")
    kw = {"subject": {k: v for k, v in (("sex", a.sex), ("age", a.age), ("stature", a.stature),
                                          ("mass", a.mass), ("breast_size", a.breast_size)) if v is not None}}
    for name in ("posture", "solver", "grid", "units", "method", "rtol", "rate", "lod", "seed", "threads"):
        if getattr(a, name) is not None:
            kw[name] = getattr(a, name)
    if a.max_evals is not None:
        kw["max_evals"] = a.max_evals
    if a.ti_ttot is not None:
        kw["ti_ttot"] = None if a.ti_ttot == "auto" else float(a.ti_ttot)
    if a.anterior:
        kw["anterior"] = a.anterior.split(",")
    kw["skin_fit"], kw["marker_offsets"], kw["drift"] = a.skin_fit, a.marker_offsets, not a.no_drift
    if a.fit_size or a.no_fit_size:
        kw["fit_size"] = a.fit_size
    return kw


def write_atomic(path: Path, text: str):
    """Write `text` to `path` through a temporary file and a rename (never a half-written file)."""
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=".tmp-")
    with os.fdopen(fd, "w") as f:
        f.write(text)
    os.replace(tmp, path)


def pick(d: dict, *names):
    """The first of `names` found in `d` (a dotted name also searches nested objects) as a
    float; NaN when none is present or it is not a number."""
    for name in names:
        node = d
        if name in node:
            node = node[name]
        else:
            for part in name.split("/"):
                node = node.get(part) if isinstance(node, dict) else None
                if node is None:
                    break
        if node is None:
            continue
        try:
            return float(node)
        except (TypeError, ValueError):
            continue
    return math.nan


def wrap_deg(a: float) -> float:
    """An angle in degrees wrapped to (-180, 180]."""
    if math.isnan(a):
        return a
    w = math.fmod(a + 180.0, 360.0)
    if w <= 0:
        w += 360.0
    return w - 180.0


def tidal_from_csv(path: Path) -> float:
    """Peak-to-peak of a fitted lung-volume CSV (`time,volume.lung`), L; NaN when unreadable."""
    try:
        values = []
        with open(path) as f:
            header = f.readline().strip().split(",")
            col = header.index("volume.lung")
            for line in f:
                if line.strip():
                    values.append(float(line.split(",")[col]))
        return max(values) - min(values) if values else math.nan
    except (OSError, ValueError, IndexError):
        return math.nan


def figures(fit: dict, recording: Path, fit_json: Path) -> dict:
    """The key figures of one fit's JSON (NaN for what it does not hold)."""
    tidal = pick(fit, "breaths_summary/mean/tidal_volume_l", "fitted_breath/tidal_volume_l",
                 "tidal_volume_l", "volume.tidal", "tidal_volume", "breath/tidal_volume_l")
    if math.isnan(tidal):
        csv = fit.get("lung_volume_csv")
        candidates = [fit_json.with_name(fit_json.stem + "_lung_volume.csv")]
        if isinstance(csv, str):
            candidates.insert(0, Path(csv))
        for c in candidates:
            if c.is_file():
                tidal = tidal_from_csv(c)
                break
    freq = pick(fit, "drive.frequency", "frequency/hz")
    rate = pick(fit, "rate_bpm", "breathing_rate_bpm")
    if math.isnan(rate) and not math.isnan(freq):
        rate = 60.0 * freq
    # Thoraco-abdominal phase: the Lissajous angle of the fitted model's compartments, mean over
    # its breaths (torso fit's breaths_summary; positive when the abdomen leads); for a fit
    # result without it, the fitted drive's phase lead of the diaphragm over the ribs, the same
    # sign convention.
    phase = pick(fit, "breaths_summary/mean/phase_angle_deg")
    if math.isnan(phase):
        ribs = pick(fit, "drive.ribs.phase")
        dia = pick(fit, "drive.diaphragm.phase")
        if not (math.isnan(ribs) or math.isnan(dia)):
            phase = wrap_deg(math.degrees(dia - ribs))
    noise = pick(fit, "noise_floor_m", "cost/noise_floor_m")
    if math.isnan(noise):
        truth = recording.with_suffix(".truth.json")
        if truth.is_file():
            try:
                noise = pick(json.loads(truth.read_text()), "noise_floor_m")
            except ValueError:
                pass
    if math.isnan(noise):
        # A real recording: the floor torso fit estimates from the recording itself.
        noise = pick(fit, "noise_floor_estimate_m")
    cost = pick(fit, "cost_m")
    return {
        "tidal_volume_l": tidal,
        "rate_bpm": rate,
        "ti_ttot": pick(fit, "recording_breaths/median_ti_ttot", "breaths/median_ti_ttot", "ti_ttot", "Ti/Ttot", "timing/ti_ttot", "breath_timing/ti_ttot"),
        "ribcage_share": pick(fit, "fitted_breath/rib_cage_share", "ribcage_share", "share.ribcage",
                              "shares/ribcage", "shares/rib_cage", "share/ribcage"),
        "ta_phase_deg": phase,
        "cost_mm": cost * 1e3,
        "noise_floor_mm": noise * 1e3,
        "cost_ratio": cost / noise if noise > 0 else math.nan,
        "evaluations": pick(fit, "evaluations"),
        "wall_s": pick(fit, "wall_s"),
    }


# ---------------------------------------------------------------------------- one task

def fit_one(recording: str, key: str, sha: str, out: str, engine: str, options: list[str],
            torso: str, fmu: str, group: str, rel: str) -> dict:
    """Fit one recording (runs on a worker): the fit's JSON to `out/fits/<key>.json`, its row
    to `out/rows/<key>.json`; raises with the fit's error text when it fails."""
    import psutil  # a dependency of dask.distributed

    out = Path(out)
    rec = Path(recording)
    fit_json = out / "fits" / f"{key}.json"
    fit_json.parent.mkdir(parents=True, exist_ok=True)
    attempts = out / "attempts" / f"{key}.log"
    attempts.parent.mkdir(parents=True, exist_ok=True)
    with open(attempts, "a") as f:
        f.write(f"{time.strftime('%Y-%m-%dT%H:%M:%SZ', time.gmtime())} pid {os.getpid()}\n")
    if engine == "package":
        return fit_in_process(rec, key, sha, out, options, group, rel, fit_json, attempts)
    if engine == "native":
        cmd = [torso, "fit", "--slp", str(rec), "--out", str(fit_json), *options]
    else:
        cmd = [sys.executable, str(ROOT / "python" / "fit_slp.py"), "--fmu", fmu, "--slp", str(rec),
               "--out", str(fit_json), *options]
    start = time.perf_counter()
    peak_rss = 0
    with tempfile.TemporaryFile("w+") as log_out, tempfile.TemporaryFile("w+") as log_err:
        proc = subprocess.Popen(cmd, stdout=log_out, stderr=log_err, text=True)
        child = psutil.Process(proc.pid)
        while proc.poll() is None:  # the fit's peak resident memory, sampled every 50 ms
            try:
                peak_rss = max(peak_rss, child.memory_info().rss)
            except psutil.Error:
                pass
            time.sleep(0.05)
        log_out.seek(0)
        log_err.seek(0)
        stdout, stderr = log_out.read(), log_err.read()
    # The fit's progress lines (`fit: ...`, `fit_slp: ...`) are not its error message.
    stderr = "\n".join(line for line in stderr.splitlines() if not line.startswith(("fit: ", "fit_slp: ")))
    wall = time.perf_counter() - start
    if proc.returncode != 0 or not fit_json.is_file():
        text = (stderr.strip() or stdout.strip() or f"exit status {proc.returncode}")
        raise RuntimeError(f"{rel}: {text[-2000:]}")
    fit = json.loads(fit_json.read_text())
    row = {"recording": rel, "group": group, "key": key, "sha256": sha, "options": shlex.join(options),
           "engine": engine, "status": "ok", "error": "",
           "attempts": sum(1 for _ in open(attempts)), "fit_json": str(fit_json.relative_to(out)),
           "finished_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    row.update(figures(fit, rec, fit_json))
    if math.isnan(row["wall_s"]):
        row["wall_s"] = wall
    row["task_wall_s"] = wall
    # memory: the fit's process (sampled while it ran) and the worker process itself
    row["fit_peak_rss_mib"] = peak_rss / 2**20
    row["worker_rss_mib"] = psutil.Process().memory_info().rss / 2**20
    write_atomic(out / "rows" / f"{key}.json", json.dumps(row, indent=1, allow_nan=True))
    return row


def fit_in_process(rec: Path, key: str, sha: str, out: Path, options: list[str], group: str, rel: str,
                   fit_json: Path, attempts: Path) -> dict:
    """`fit_one` with `--engine package`: `breathing_torso.fit` in this worker (the GIL
    released while it runs), its JSON written where `torso fit` writes it."""
    import psutil  # a dependency of dask.distributed

    import breathing_torso

    start = time.perf_counter()
    try:
        breathing_torso.fit(rec, fit_json, as_frame=False, **package_keywords(options))
    except (ValueError, OSError, breathing_torso.TorsoError) as e:
        raise RuntimeError(f"{rel}: {e}") from None
    wall = time.perf_counter() - start
    fit = json.loads(fit_json.read_text())
    rss = psutil.Process().memory_info().rss / 2**20
    row = {"recording": rel, "group": group, "key": key, "sha256": sha, "options": shlex.join(options),
           "engine": "package", "status": "ok", "error": "",
           "attempts": sum(1 for _ in open(attempts)), "fit_json": str(fit_json.relative_to(out)),
           "finished_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
    row.update(figures(fit, rec, fit_json))
    if math.isnan(row["wall_s"]):
        row["wall_s"] = wall
    row["task_wall_s"] = wall
    # the fit runs in the worker: its memory is the worker's
    row["fit_peak_rss_mib"] = rss
    row["worker_rss_mib"] = rss
    write_atomic(out / "rows" / f"{key}.json", json.dumps(row, indent=1, allow_nan=True))
    return row


# ---------------------------------------------------------------------------- table

def read_rows(out: Path) -> list[dict]:
    """Every row file under `out/rows` (a half-written one cannot exist: rows are renamed in)."""
    rows = []
    for p in sorted((out / "rows").glob("*.json")):
        try:
            rows.append(json.loads(p.read_text()))
        except ValueError as e:
            say(f"warning: {p} is not a row ({e}); ignored")
    return rows


def write_table(out: Path):
    """Rebuild `results.parquet` and `results.csv` from the row files; returns the DataFrame."""
    import pandas as pd

    rows = read_rows(out)
    df = pd.DataFrame(rows)
    for c in COLUMNS:
        if c not in df.columns:
            df[c] = math.nan if c not in ("recording", "group", "key", "status", "error") else ""
    df = df[COLUMNS + [c for c in df.columns if c not in COLUMNS]]
    df = df.sort_values("recording", kind="stable").reset_index(drop=True)
    tmp = out / ".results.parquet.tmp"
    df.to_parquet(tmp, index=False)
    os.replace(tmp, out / "results.parquet")
    write_atomic(out / "results.csv", df.to_csv(index=False))
    return df


def read_groups(path: Path | None) -> dict:
    """The `recording name -> group` map of a groups CSV (columns `recording,group`; the name
    may be the file name, its stem, or the path relative to the folder)."""
    if path is None:
        return {}
    import csv

    with open(path, newline="") as f:
        reader = csv.DictReader(f)
        if not reader.fieldnames or len(reader.fieldnames) < 2:
            raise SystemExit(f"error: {path}: expected a header `recording,group`")
        name_col, group_col = reader.fieldnames[0], reader.fieldnames[1]
        return {row[name_col].strip(): row[group_col].strip() for row in reader}


def group_of(rel: Path, groups: dict) -> str:
    """A recording's group: the groups file's, else its subfolder, else `all`."""
    for name in (str(rel), rel.name, rel.stem):
        if name in groups:
            return groups[name]
    return str(rel.parent) if str(rel.parent) != "." else "all"


# ---------------------------------------------------------------------------- fit command

def find_recordings(folder: Path, pattern: str) -> list[Path]:
    """The recordings under `folder` matching `pattern`, recursively, sorted."""
    files = sorted(Path(p) for p in globmod.glob(str(folder / "**" / pattern), recursive=True))
    return [p for p in files if p.is_file() and not p.name.endswith(".truth.json")]


def make_client(args):
    """A Dask client on the given scheduler, or on a new LocalCluster of processes."""
    from dask.distributed import Client, LocalCluster

    if args.scheduler:
        return Client(args.scheduler)
    workers = args.workers or os.cpu_count() or 1
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True,
                           dashboard_address=":0", silence_logs=logging.ERROR)
    return Client(cluster)


def cmd_fit(args) -> int:
    from dask.distributed import as_completed

    folder = Path(args.folder).resolve()
    out = Path(args.out).resolve()
    if not folder.is_dir():
        say(f"error: {folder} is not a folder")
        return 2
    torso = str(Path(args.torso).resolve()) if args.engine == "native" else ""
    if args.engine == "native" and not os.access(torso, os.X_OK):
        say(f"error: --torso {args.torso}: no such executable (build it with `cargo build --release`)")
        return 2
    fmu = str(Path(args.fmu).resolve()) if args.engine == "fmu" else ""
    if args.engine == "fmu" and not Path(fmu).is_file():
        say(f"error: --fmu {args.fmu}: no such file (build it with `target/release/torso fmu build`)")
        return 2
    if args.engine == "package":
        try:
            import breathing_torso  # noqa: F401
            package_keywords(shlex.split(args.fit_args))
        except ImportError:
            say("error: --engine package: the breathing_torso package is not installed (pip install target/wheels/breathing_torso-*manylinux*.whl)")
            return 2
        except ValueError as e:
            say(f"error: {e}")
            return 2
    groups = read_groups(Path(args.groups) if args.groups else None)
    fit_args = shlex.split(args.fit_args)
    recordings = [r for r in find_recordings(folder, args.glob) if out not in r.parents]
    if not recordings:
        say(f"error: no recording matches {args.glob} under {folder}")
        return 2
    (out / "rows").mkdir(parents=True, exist_ok=True)
    done = {r["key"] for r in read_rows(out) if r.get("status") == "ok"}
    todo = []
    for rec in recordings:
        rel = rec.relative_to(folder)
        options = recording_options(rec, fit_args)
        sha = sha256_file(rec)
        key = task_key(sha, args.engine, options)
        if key not in done:
            todo.append((rec, rel, sha, key, options))
    say(f"{len(recordings)} recordings under {folder}: {len(recordings) - len(todo)} already fitted, "
        f"{len(todo)} to fit")
    if not todo:
        write_table(out)
        if args.report:
            write_report(out, groups)
        return 0
    client = make_client(args)
    try:
        say(f"Dask dashboard: {client.dashboard_link}")
        if importlib.util.find_spec("bokeh") is None:  # the dashboard's web pages need it
            say("  (the dashboard needs bokeh: `pip install dask[diagnostics]`, as python/requirements.txt does)")
        nworkers = len(client.scheduler_info()["workers"])
        say(f"{nworkers} workers ({'scheduler ' + args.scheduler if args.scheduler else 'LocalCluster'})")
        futures = {}
        for rec, rel, sha, key, options in todo:
            fut = client.submit(fit_one, str(rec), key, sha, str(out), args.engine, options, torso, fmu,
                                group_of(rel, groups), str(rel), key=f"fit-{key}", pure=False,
                                retries=args.retries)
            futures[fut] = (rec, rel, sha, key, options)
        start = time.perf_counter()
        finished = failed = 0
        last_table = 0.0
        for fut in as_completed(list(futures)):
            rec, rel, sha, key, options = futures[fut]
            finished += 1
            elapsed = time.perf_counter() - start
            eta = elapsed / finished * (len(todo) - finished)
            if fut.status == "finished":
                r = fut.result()
                say(f"[{finished}/{len(todo)}] {rel}: tidal {r['tidal_volume_l']:.3f} L, "
                    f"{r['rate_bpm']:.1f} /min, cost {r['cost_mm']:.3f} mm / floor {r['noise_floor_mm']:.3f} mm "
                    f"({r['cost_ratio']:.2f}), {r['evaluations']:.0f} evaluations, {r['task_wall_s']:.1f} s; "
                    f"ETA {eta:.0f} s")
            else:
                failed += 1
                try:
                    err = str(fut.exception())
                except Exception as e:  # a cancelled future, a lost scheduler
                    err = f"{type(e).__name__}: {e}"
                attempts_log = out / "attempts" / f"{key}.log"
                n = sum(1 for _ in open(attempts_log)) if attempts_log.is_file() else 0
                row = {"recording": str(rel), "group": group_of(rel, groups), "key": key, "sha256": sha,
                       "options": shlex.join(options), "engine": args.engine, "status": "failed",
                       "error": err, "attempts": n,
                       "finished_utc": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime())}
                write_atomic(out / "rows" / f"{key}.json", json.dumps(row, indent=1))
                say(f"[{finished}/{len(todo)}] {rel}: FAILED after {n} attempts: {err.splitlines()[-1] if err else ''}; "
                    f"ETA {eta:.0f} s")
            if time.perf_counter() - last_table > 5.0 or finished == len(todo):
                write_table(out)
                last_table = time.perf_counter()
        say(f"done: {finished - failed} fitted, {failed} failed in {time.perf_counter() - start:.1f} s wall; "
            f"table {out / 'results.parquet'}")
        df = write_table(out)
        if "worker_rss_mib" in df.columns and df["worker_rss_mib"].notna().any():
            say(f"memory: worker process RSS up to {df['worker_rss_mib'].max():.0f} MiB, "
                f"a fit's process peak RSS (sampled every 50 ms) up to {df['fit_peak_rss_mib'].max():.0f} MiB")
    finally:
        cluster = getattr(client, "cluster", None)
        client.close()
        if cluster is not None:
            cluster.close()
    if args.report:
        write_report(out, groups)
    return 1 if failed else 0


# ---------------------------------------------------------------------------- report

METRICS = [
    ("tidal_volume_l", "tidal volume [L]"),
    ("rate_bpm", "breathing rate [1/min]"),
    ("ti_ttot", "Ti/Ttot"),
    ("ribcage_share", "rib-cage share"),
    ("ta_phase_deg", "thoraco-abdominal phase [deg]\n(Lissajous, + abdomen leads)"),
]


def write_report(out: Path, groups: dict | None = None) -> list[Path]:
    """Write `report.png`, `report.svg` and the self-contained `report.html` of the table."""
    import base64
    import html

    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    df = write_table(out)
    if groups:
        df["group"] = [groups.get(r, groups.get(Path(r).name, groups.get(Path(r).stem, g)))
                       for r, g in zip(df["recording"], df["group"])]
    ok = df[df["status"] == "ok"].copy()
    names = sorted(ok["group"].astype(str).unique()) if len(ok) else []
    fig, axes = plt.subplots(2, 3, figsize=(15, 8.5))
    rng = np.random.default_rng(0)
    for ax, (col, label) in zip(axes.flat, METRICS):
        data = [ok.loc[ok["group"] == g, col].astype(float).dropna().to_numpy() for g in names]
        if any(len(d) for d in data):
            ax.boxplot([d if len(d) else [np.nan] for d in data], showfliers=False)
            for i, d in enumerate(data):
                ax.plot(i + 1 + rng.uniform(-0.12, 0.12, len(d)), d, "o", ms=4, alpha=0.7, color="C0")
            ax.set_xticks(range(1, len(names) + 1), names, rotation=30, ha="right")
        else:
            ax.text(0.5, 0.5, "not in the fits' JSON", ha="center", va="center", transform=ax.transAxes)
            ax.set_xticks([])
        ax.set_title(label, fontsize=10)
    ax = axes.flat[5]
    bad = ok["cost_ratio"].astype(float) > BAD_FIT_RATIO
    ax.plot(ok.loc[~bad, "noise_floor_mm"], ok.loc[~bad, "cost_mm"], "o", color="C0", label="fit")
    ax.plot(ok.loc[bad, "noise_floor_mm"], ok.loc[bad, "cost_mm"], "o", color="red",
            label=f"cost > {BAD_FIT_RATIO} x floor")
    finite = ok[["noise_floor_mm", "cost_mm"]].astype(float).to_numpy()
    finite = finite[np.isfinite(finite).all(axis=1)]
    if len(finite):
        lo, hi = 0.0, float(finite.max()) * 1.1
        ax.plot([lo, hi], [lo, hi], "k-", lw=0.8, label="cost = floor")
        ax.plot([lo, hi], [lo, BAD_FIT_RATIO * hi], "r--", lw=0.8, label=f"{BAD_FIT_RATIO} x floor")
    ax.set_xlabel("noise floor [mm]")
    ax.set_ylabel("fit cost [mm]")
    ax.set_title("cost against noise floor", fontsize=10)
    ax.legend(fontsize=8)
    nfail = int((df["status"] != "ok").sum())
    fig.suptitle(f"Cohort: {len(ok)} fitted recordings in {len(names)} groups, {nfail} failed")
    fig.tight_layout()
    png, svg, page = out / "report.png", out / "report.svg", out / "report.html"
    fig.savefig(png, dpi=110)
    fig.savefig(svg)
    plt.close(fig)

    def fmt(v):
        if isinstance(v, float):
            return "" if math.isnan(v) else f"{v:.4g}"
        return html.escape(str(v))

    cols = ["recording", "group", "status", "tidal_volume_l", "rate_bpm", "ti_ttot", "ribcage_share",
            "ta_phase_deg", "cost_mm", "noise_floor_mm", "cost_ratio", "evaluations", "wall_s", "error"]
    rows_html = []
    for _, r in df.iterrows():
        flagged = r["status"] != "ok" or (isinstance(r["cost_ratio"], float) and r["cost_ratio"] > BAD_FIT_RATIO)
        style = ' style="color:red"' if flagged else ""
        rows_html.append(f"<tr{style}>" + "".join(f"<td>{fmt(r[c])}</td>" for c in cols) + "</tr>")
    summary = []
    for g in names:
        sub = ok[ok["group"] == g]
        cells = [html.escape(g), str(len(sub))]
        for col, _ in METRICS:
            v = sub[col].astype(float).dropna()
            cells.append(f"{v.median():.4g} ({v.quantile(0.25):.4g}-{v.quantile(0.75):.4g})" if len(v) else "")
        summary.append("<tr>" + "".join(f"<td>{c}</td>" for c in cells) + "</tr>")
    flagged = df[(df["status"] != "ok") | (df["cost_ratio"].astype(float) > BAD_FIT_RATIO)]
    flagged_html = "".join(
        f"<li>{html.escape(str(r['recording']))}: "
        + (f"failed: {html.escape(str(r['error']))}" if r["status"] != "ok"
           else f"cost {r['cost_mm']:.3f} mm = {r['cost_ratio']:.2f} x noise floor")
        + "</li>" for _, r in flagged.iterrows()) or "<li>none</li>"
    img = base64.b64encode(png.read_bytes()).decode()
    page.write_text(f"""<!DOCTYPE html>
<html><head><meta charset="utf-8"><title>Cohort report</title>
<style>body{{font-family:sans-serif;margin:1.5em}} table{{border-collapse:collapse;font-size:12px}}
td,th{{border:1px solid #ccc;padding:2px 6px;text-align:right}} td:first-child{{text-align:left}}</style>
</head><body>
<h1>Cohort report</h1>
<p>{len(df)} recordings, {len(ok)} fitted, {nfail} failed. Flagged: fits whose cost exceeds
{BAD_FIT_RATIO} x the noise floor, and failures (red below). Empty cells: the fit's JSON does not
hold that figure.</p>
<h2>Flagged</h2><ul>{flagged_html}</ul>
<img alt="cohort figure" style="max-width:100%" src="data:image/png;base64,{img}">
<h2>Per group (median, interquartile range)</h2>
<table><tr><th>group</th><th>n</th>{''.join(f'<th>{html.escape(m[1])}</th>' for m in METRICS)}</tr>
{''.join(summary)}</table>
<h2>Per recording</h2>
<table><tr>{''.join(f'<th>{c}</th>' for c in cols)}</tr>
{''.join(rows_html)}</table>
</body></html>
""")
    say(f"wrote {png}, {svg} and {page}")
    return [png, svg, page]


def cmd_report(args) -> int:
    out = Path(args.out)
    if not (out / "rows").is_dir():
        say(f"error: {out} holds no rows/ folder (run `fit` first)")
        return 2
    write_report(out, read_groups(Path(args.groups) if args.groups else None))
    return 0


# ---------------------------------------------------------------------------- synthetic study

def cmd_make_synthetic(args) -> int:
    """N recordings with seeded variety: sex, age, stature, mass, posture, rate and drive."""
    import random

    rnd = random.Random(args.seed)
    folder = Path(args.dir)
    torso = str(Path(args.torso).resolve())
    postures = ["standing", "sitting", "supine"]
    for i in range(args.n):
        sex = rnd.choice(["male", "female"])
        stature = round(rnd.uniform(1.62, 1.90) if sex == "male" else rnd.uniform(1.52, 1.78), 3)
        bmi = rnd.uniform(19.0, 29.0)
        subject = ["--sex", sex, "--age", f"{rnd.randint(20, 75)}", "--stature", f"{stature}",
                   "--mass", f"{bmi * stature ** 2:.1f}", "--posture", postures[i % 3]]
        drive = ["--frequency", f"{rnd.uniform(0.2, 0.33):.4f}",
                 "--ribs-amplitude", f"{rnd.uniform(0.06, 0.16):.4f}",
                 "--diaphragm-amplitude", f"{rnd.uniform(0.15, 0.32):.4f}",
                 "--diaphragm-phase", f"{rnd.uniform(-0.3, 0.4):.4f}"]
        sub = folder / postures[i % 3]
        sub.mkdir(parents=True, exist_ok=True)
        stem = sub / f"rec{i:03d}"
        cmd = [torso, "synth", "--lod", str(args.lod), "--rtol", str(args.rtol), "--duration", str(args.duration),
               "--seed", str(args.seed * 1000 + i), "--out", f"{stem}.csv", "--truth", f"{stem}.truth.json",
               *subject, *drive]
        proc = subprocess.run(cmd, capture_output=True, text=True)
        if proc.returncode != 0:
            say(f"error: {shlex.join(cmd)}:\n{proc.stderr}")
            return 1
        (stem.with_suffix(".args")).write_text(shlex.join(subject) + "\n")
        say(f"wrote {stem}.csv ({' '.join(subject)})")
    return 0


# ---------------------------------------------------------------------------- Dask overhead

def noop(i):
    """A task that does nothing (measures Dask's own cost per task)."""
    return i


def cmd_overhead(args) -> int:
    """Time `--tasks` no-op tasks submitted one per call and gathered, after a warm-up."""
    client = make_client(args)
    try:
        client.gather(client.map(noop, range(20), pure=False))
        for batch in range(args.repeat):
            t = time.perf_counter()
            futs = [client.submit(noop, i, pure=False) for i in range(args.tasks)]
            client.gather(futs)
            dt = time.perf_counter() - t
            say(f"{args.tasks} no-op tasks on {len(client.scheduler_info()['workers'])} workers: "
                f"{dt:.3f} s, {dt / args.tasks * 1e3:.2f} ms per task")
        rss = client.run(lambda: __import__("psutil").Process().memory_info().rss)
        for w, v in rss.items():
            say(f"worker {w}: RSS {v / 2**20:.0f} MiB")
    finally:
        cluster = getattr(client, "cluster", None)
        client.close()
        if cluster is not None:
            cluster.close()
    return 0


# ---------------------------------------------------------------------------- command line

def main(argv=None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)

    def cluster_options(q):
        q.add_argument("--workers", type=int, default=0, help="LocalCluster worker processes (default: cores)")
        q.add_argument("--scheduler", default="", help="address of an existing Dask scheduler (tcp://host:8786)")

    f = sub.add_parser("fit", help="fit every recording under a folder")
    f.add_argument("folder")
    f.add_argument("--out", required=True, help="output folder (results table, fits, rows, report)")
    f.add_argument("--glob", default="*.csv", help="recordings to fit, searched recursively (default *.csv)")
    f.add_argument("--engine", choices=ENGINES, default="native")
    f.add_argument("--torso", default=str(ROOT / "target" / "release" / "torso"))
    f.add_argument("--fmu", default=str(ROOT / "fmu" / "BreathingTorso.fmu"))
    f.add_argument("--fit-args", default="", help='options for every fit, e.g. "--lod 0 --max-evals 60"')
    f.add_argument("--retries", type=int, default=2, help="retries of a failing task (default 2)")
    f.add_argument("--groups", default="", help="CSV recording,group (default: the subfolder)")
    f.add_argument("--report", action="store_true", help="write the cohort report at the end")
    cluster_options(f)
    r = sub.add_parser("report", help="write the cohort report of an output folder")
    r.add_argument("out")
    r.add_argument("--groups", default="")
    s = sub.add_parser("make-synthetic", help="write N synthetic recordings with seeded variety")
    s.add_argument("n", type=int)
    s.add_argument("dir")
    s.add_argument("--duration", type=float, default=18.0)
    s.add_argument("--lod", type=int, default=0)
    s.add_argument("--rtol", type=float, default=1e-4)
    s.add_argument("--seed", type=int, default=1)
    s.add_argument("--torso", default=str(ROOT / "target" / "release" / "torso"))
    o = sub.add_parser("overhead", help="measure Dask's cost per task with no-op tasks")
    o.add_argument("--tasks", type=int, default=200)
    o.add_argument("--repeat", type=int, default=3)
    cluster_options(o)
    args = p.parse_args(argv)
    return {"fit": cmd_fit, "report": cmd_report, "make-synthetic": cmd_make_synthetic,
            "overhead": cmd_overhead}[args.command](args)


if __name__ == "__main__":
    sys.exit(main())
