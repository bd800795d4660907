"""python/batch_fit.py on a small study (docs/results.md's block, run as written: 4 synthetic 6 s
recordings at LOD 0, fits bounded to a few evaluations) on a LocalCluster of 2 worker
processes: the table is complete, a rerun fits nothing, a worker killed mid-run and then the
driver killed lose no finished fit and the rerun completes the rest once each, a corrupt
recording is recorded as failed with its error text after three attempts, the report files are
written, and `--engine fmu` fits one recording. The recordings are made once (the block's)."""

import json
import os
import re
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import pandas as pd
import psutil
import pytest

from test_fmu_calls import fmu_path

ROOT = Path(__file__).resolve().parents[2]
SCRIPT = ROOT / "python" / "batch_fit.py"
TORSO = Path(os.environ.get("TORSO", ROOT / "target" / "release" / "torso"))  # the tool under test
#: cost / noise floor of a good fit of these synthetic recordings (batch_fit flags 1.3)
BAD = 1.3
FIT_ARGS = "--lod 0 --rtol 1e-4 --max-evals 10 --threads 1"


def batch(*args, check=True):
    proc = subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True,
                          timeout=300)
    if check:
        assert proc.returncode == 0, f"batch_fit {args} failed:\n{proc.stdout}\n{proc.stderr}"
    return proc


def fit(folder, out, *extra, check=True):
    return batch("fit", folder, "--out", out, "--workers", 2, "--torso", TORSO, "--fit-args", FIT_ARGS,
                 *extra, check=check)


def readme_commands():
    """The commands of docs/results.md's ```sh block that runs batch_fit.py (continuations
    joined)."""
    text = (ROOT / "docs" / "results.md").read_text()
    blocks = [b for b in re.findall(r"^```sh\n(.*?)^```$", text, flags=re.S | re.M) if "batch_fit.py" in b]
    assert len(blocks) == 1, f"docs/results.md: expected one ```sh block running batch_fit.py, found {len(blocks)}"
    return [c.strip() for c in blocks[0].replace("\\\n", " ").splitlines() if c.strip()]


@pytest.fixture(scope="module")
def readme_run():
    """docs/results.md's block, run as written from the repository's root (its out/ folder)."""
    if not os.access(TORSO, os.X_OK):
        pytest.fail(f"{TORSO} is missing: build it with `cargo build --release`")
    for d in ("out/study", "out/study-fit"):
        shutil.rmtree(ROOT / d, ignore_errors=True)
    outputs = []
    for cmd in readme_commands():
        proc = subprocess.run(["bash", "-euo", "pipefail", "-c", cmd], cwd=ROOT, capture_output=True,
                              text=True, timeout=300)
        assert proc.returncode == 0, f"docs/results.md command failed: {cmd}\n{proc.stdout}\n{proc.stderr}"
        outputs.append(proc.stdout)
    return ROOT / "out" / "study", ROOT / "out" / "study-fit", outputs


@pytest.fixture(scope="module")
def study(readme_run, tmp_path_factory):
    """A copy of the block's 4 recordings for the tests that break things."""
    folder = tmp_path_factory.mktemp("study") / "study"
    shutil.copytree(readme_run[0], folder)
    assert len(list(folder.rglob("*.csv"))) == 4
    return folder


def table(out):
    df = pd.read_parquet(out / "results.parquet")
    csv = pd.read_csv(out / "results.csv")
    assert len(csv) == len(df) and list(csv["recording"]) == list(df["recording"])
    return df


def test_readme_study_table_resume_and_report(readme_run):
    study, out, (_, first) = readme_run
    assert "Dask dashboard: http" in first
    df = table(out)
    assert sorted(df["recording"]) == sorted(str(p.relative_to(study)) for p in study.rglob("*.csv"))
    assert (df["status"] == "ok").all(), df[["recording", "status", "error"]]
    assert df["key"].is_unique
    assert set(df["group"]) == {"standing", "sitting", "supine"}
    for col in ("tidal_volume_l", "rate_bpm", "ta_phase_deg", "ribcage_share", "cost_mm", "noise_floor_mm",
                "evaluations"):
        assert df[col].notna().all(), col
    assert df["ribcage_share"].between(0.0, 1.0).all()
    assert df["tidal_volume_l"].between(0.05, 3.0).all()
    assert (df["worker_rss_mib"] > 20).all() and (df["fit_peak_rss_mib"] > 1).all()
    assert "memory: worker process RSS up to" in first
    assert df["fit_json"].map(lambda p: (out / p).is_file()).all()
    assert first.count("ETA") == 4
    for name in ("report.png", "report.svg", "report.html"):
        assert (out / name).stat().st_size > 1000, name
    page = (out / "report.html").read_text()
    assert "data:image/png;base64," in page and "rec000.csv" in page

    rows = {p: p.stat().st_mtime_ns for p in (out / "rows").glob("*.json")}
    fit_cmd = [c for c in readme_commands() if " fit " in c][0]
    second = subprocess.run(["bash", "-euo", "pipefail", "-c", fit_cmd], cwd=ROOT, capture_output=True,
                            text=True, timeout=300)
    assert second.returncode == 0, second.stderr
    assert "4 already fitted, 0 to fit" in second.stdout, second.stdout
    assert "ETA" not in second.stdout
    assert {p: p.stat().st_mtime_ns for p in (out / "rows").glob("*.json")} == rows
    for log in (out / "attempts").glob("*.log"):
        assert len(log.read_text().splitlines()) == 1, log
    assert len(table(out)) == 4


def descendants_running_fit(driver):
    """The worker processes (below the driver) that run a `torso fit` child right now."""
    try:
        procs = psutil.Process(driver.pid).children(recursive=True)
    except psutil.NoSuchProcess:
        return []
    workers = []
    for p in procs:
        try:
            if p.name() == "torso" and "fit" in p.cmdline():
                workers.append(p.parent())
        except psutil.NoSuchProcess:
            pass
    return workers


def test_killed_worker_then_killed_driver_lose_nothing(study, tmp_path):
    out = tmp_path / "out"
    cmd = [sys.executable, str(SCRIPT), "fit", str(study), "--out", str(out), "--workers", "2",
           "--torso", str(TORSO), "--fit-args", FIT_ARGS]
    driver = subprocess.Popen(cmd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                              start_new_session=True)
    try:
        deadline = time.monotonic() + 120
        workers = []
        while not workers and time.monotonic() < deadline and driver.poll() is None:
            workers = descendants_running_fit(driver)
            time.sleep(0.02)
        assert workers, "no worker ran a fit"
        workers[0].send_signal(signal.SIGKILL)  # a worker dies in the middle of a fit
        while not list((out / "rows").glob("*.json")) and time.monotonic() < deadline:
            time.sleep(0.02)
        assert list((out / "rows").glob("*.json")), "no fit finished after the worker was killed"
    finally:
        if driver.poll() is None:
            os.killpg(driver.pid, signal.SIGKILL)  # and then the driver, with its cluster
        driver.wait()
    finished = len(list((out / "rows").glob("*.json")))
    rerun = fit(study, out)
    assert f"{finished} already fitted, {4 - finished} to fit" in rerun.stdout, rerun.stdout
    df = table(out)
    assert len(df) == 4 and df["recording"].is_unique and (df["status"] == "ok").all(), df


def test_corrupt_recording_fails_after_three_attempts(study, tmp_path):
    folder = tmp_path / "mixed"
    folder.mkdir()
    good = next(study.rglob("rec000.csv"))
    shutil.copy(good, folder / "good.csv")
    (folder / "corrupt.csv").write_text("# grid: 10x6\ntime,marker[1].x\n0.0,not-a-number\n")
    out = tmp_path / "out"
    proc = fit(folder, out, check=False)
    assert proc.returncode == 1, proc.stdout + proc.stderr
    assert "corrupt.csv: FAILED after 3 attempts" in proc.stdout, proc.stdout
    df = table(out).set_index("recording")
    assert df.loc["good.csv", "status"] == "ok"
    bad = df.loc["corrupt.csv"]
    assert bad["status"] == "failed" and bad["attempts"] == 3
    assert "corrupt.csv" in bad["error"] and len(bad["error"]) > len("corrupt.csv: "), bad["error"]
    row = json.loads(next((out / "rows").glob(f"{bad['key']}.json")).read_text())
    assert row["status"] == "failed"
    # the rerun fits only the failed recording again (and it fails again, with the same text)
    again = fit(folder, out, check=False)
    assert "1 already fitted, 1 to fit" in again.stdout, again.stdout
    assert len(table(out)) == 2


def test_fmu_engine_on_one_recording(study, tmp_path):
    fmu = os.environ.get("FMU") or fmu_path()
    folder = tmp_path / "one"
    folder.mkdir()
    rec = next(study.rglob("rec000.csv"))
    for suffix in (".csv", ".args", ".truth.json"):
        shutil.copy(rec.with_suffix(suffix), folder / ("rec000" + suffix))
    out = tmp_path / "out"
    proc = batch("fit", folder, "--out", out, "--workers", 1, "--engine", "fmu", "--fmu", fmu,
                 "--fit-args", "--lod 0 --rtol 1e-4 --max-evals 10")
    assert "[1/1] rec000.csv: tidal" in proc.stdout, proc.stdout
    row = table(out).iloc[0]
    assert row["status"] == "ok" and row["engine"] == "fmu" and row["evaluations"] <= 10
    assert 0.05 < row["tidal_volume_l"] < 3.0 and row["cost_ratio"] < BAD


def test_package_engine_is_the_native_fit(study, tmp_path):
    """`--engine package` (breathing_torso.fit inside the worker) fits a recording to the
    same figures as `torso fit` on it (the same library, the same options); an option the
    package engine does not take is refused before any task runs."""
    pytest.importorskip("breathing_torso", reason="the package is not installed: bash scripts/build-wheel.sh")
    folder = tmp_path / "one"
    folder.mkdir()
    rec = next(study.rglob("rec000.csv"))
    for suffix in (".csv", ".args", ".truth.json"):
        shutil.copy(rec.with_suffix(suffix), folder / ("rec000" + suffix))
    rows = {}
    for engine in ("package", "native"):
        out = tmp_path / engine
        proc = batch("fit", folder, "--out", out, "--workers", 1, "--engine", engine, "--torso", TORSO,
                     "--fit-args", FIT_ARGS)
        assert "[1/1] rec000.csv: tidal" in proc.stdout, proc.stdout
        rows[engine] = table(out).iloc[0]
    assert rows["package"]["status"] == "ok" and rows["package"]["engine"] == "package"
    for col in ("tidal_volume_l", "rate_bpm", "ti_ttot", "ribcage_share", "ta_phase_deg", "cost_mm",
                "noise_floor_mm", "evaluations"):
        a, b = rows["package"][col], rows["native"][col]
        assert a == b or (a != a and b != b), (col, a, b)  # NaN (absent from both JSONs) too
    bad = batch("fit", folder, "--out", tmp_path / "bad", "--engine", "package", "--fit-args", "--lod 0 --frobnicate",
                check=False)
    assert bad.returncode == 2 and "--frobnicate: not an option --engine package passes" in bad.stdout
