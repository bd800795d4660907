"""Cross-checks of `torso validate` against independent implementations: scipy's
resample_poly and pearsonr, a direct ddof=1 Bland-Altman (and pingouin's), statsmodels OLS
and F tests for the cosinor fits, the equality tests and the robust (AR-error GLS) test.

The tests build nothing themselves: they call the release binary (`cargo build --release`
first), which scripts/test.sh does before running pytest.
"""

import json
import math
import pathlib
import subprocess

import numpy as np
import pytest
import scipy.signal
import scipy.stats
import statsmodels.api as sm

ROOT = pathlib.Path(__file__).resolve().parents[2]
TORSO = ROOT / "target" / "release" / "torso"

FS_SIM = 56.0


def run(*args, check=True):
    proc = subprocess.run([str(TORSO), *map(str, args)], capture_output=True, text=True)
    if check and proc.returncode != 0:
        raise AssertionError(f"torso {' '.join(map(str, args))} failed:\n{proc.stderr}")
    return proc


def lung(t):
    a = 2 * math.pi * 0.27 * t
    return 2.5 + 0.25 * (1 - np.cos(a)) + 0.03 * np.sin(2 * a)


def write_sim(path, n=1008):
    t = np.arange(n) / FS_SIM
    np.savetxt(path, np.column_stack([t, lung(t)]), delimiter=",", header="time,lung_volume", comments="", fmt="%.17g")


@pytest.fixture(scope="module")
def validated(tmp_path_factory):
    if not TORSO.exists():
        pytest.skip("build the release binary first: cargo build --release")
    d = tmp_path_factory.mktemp("validate")
    write_sim(d / "sim.csv")
    run("synth-spirometry", "--from", d / "sim.csv", "--out", d / "spiro.csv", "--noise", "0.015",
        "--drift", "0.002", "--start-offset", "0.75", "--scale", "1.04", "--seed", "3")
    run("validate", "--sim", d / "sim.csv", "--spiro", d / "spiro.csv", "--out", d / "out", "--seed", "5")
    out = d / "out"
    report = json.loads((out / "validation.json").read_text())
    aligned = np.genfromtxt(out / "aligned.csv", delimiter=",", names=True)
    return d, report, aligned


def rel(a, b):
    return abs(a - b) / max(abs(b), 1e-300)


def test_resampling_matches_scipy(validated):
    d, report, _ = validated
    spiro = np.genfromtxt(d / "spiro.csv", delimiter=",", names=True)
    ours = np.genfromtxt(d / "out" / "spiro_resampled.csv", delimiter=",", names=True)["volume"]
    theirs = scipy.signal.resample_poly(spiro["volume"], 14, 25)
    assert report["preparation"]["resample_ratio"] == [14, 25]
    assert ours.shape == theirs.shape
    span = theirs.max() - theirs.min()
    assert np.max(np.abs(ours - theirs)) < 1e-6 * span


@pytest.mark.parametrize("n,up,down", [(1750, 14, 25), (1001, 25, 14), (433, 3, 7), (500, 2, 1)])
def test_resampler_on_random_signals(tmp_path, n, up, down):
    """Rates chosen so the ratio reduces to up/down (10 down Hz to 10 up Hz, records of 6.2 s
    or more, over two periods of the 0.48 Hz simulated curve); the spirogram is read back
    resampled."""
    if not TORSO.exists():
        pytest.skip("build the release binary first")
    rng = np.random.default_rng(n)
    fs_spiro, fs_sim = 10.0 * down, 10.0 * up
    x = np.cumsum(rng.normal(size=n)) * 0.01 + np.sin(np.arange(n) / n * 40)
    np.savetxt(tmp_path / "spiro.csv", np.column_stack([np.arange(n) / fs_spiro, x]), delimiter=",",
               header="time,volume", comments="", fmt="%.17g")
    m = int(math.ceil(n * up / down))
    ts = np.arange(m) / fs_sim
    np.savetxt(tmp_path / "sim.csv", np.column_stack([ts, np.sin(ts * 3) + 2]), delimiter=",",
               header="time,volume", comments="", fmt="%.17g")
    run("validate", "--sim", tmp_path / "sim.csv", "--spiro", tmp_path / "spiro.csv", "--out",
        tmp_path / "out", "--bars-iterations", "260", "--max-lag", "5", "--bootstrap", "19")
    ours = np.genfromtxt(tmp_path / "out" / "spiro_resampled.csv", delimiter=",", names=True)["volume"]
    theirs = scipy.signal.resample_poly(x, up, down)
    assert ours.shape == theirs.shape
    assert np.max(np.abs(ours - theirs)) < 1e-6 * (theirs.max() - theirs.min())


def test_pearson_matches_scipy(validated):
    _, report, a = validated
    res = scipy.stats.pearsonr(a["sim"], a["spiro"])
    p = report["pearson"]
    assert rel(p["r"], res.statistic) < 1e-9
    ci = res.confidence_interval(0.95)
    assert rel(p["ci_low"], ci.low) < 1e-9 and rel(p["ci_high"], ci.high) < 1e-9
    assert p["n"] == len(a)


def test_bland_altman_matches_direct_and_pingouin(validated):
    _, report, a = validated
    d = a["sim"] - a["spiro"]
    s = d.std(ddof=1)
    ba = report["bland_altman"]
    assert rel(ba["bias"] + 1.0, d.mean() + 1.0) < 1e-12
    assert rel(ba["sd"], s) < 1e-10
    assert rel(ba["loa_low"], d.mean() - 1.96 * s) < 1e-10
    assert rel(ba["loa_high"], d.mean() + 1.96 * s) < 1e-10
    assert rel(ba["loa_se"], math.sqrt(3 * s * s / len(d))) < 1e-10
    pg = pytest.importorskip("pingouin")
    # pingouin's plot draws its limits at mean +- 1.96 sd (ddof = 1): read them off the axes.
    import matplotlib
    matplotlib.use("Agg")
    ax = pg.plot_blandaltman(a["sim"], a["spiro"])
    ys = sorted({round(float(line.get_ydata()[0]), 12) for line in ax.get_lines()})
    for value in (ba["loa_low"], ba["bias"], ba["loa_high"]):
        assert min(abs(value - y) for y in ys) < 1e-9


def design(t, f0, harmonics):
    cols = [np.ones_like(t)]
    for k in range(1, harmonics + 1):
        cols += [np.cos(2 * math.pi * k * f0 * t), np.sin(2 * math.pi * k * f0 * t)]
    return np.column_stack(cols)


def test_cosinor_matches_statsmodels(validated):
    _, report, a = validated
    for name in ("sim", "spiro"):
        c = report["cosinor"][name]
        x = design(a["time"], c["frequency_hz"], c["harmonics"])
        fit = sm.OLS(a[name], x).fit()
        for ours, theirs in zip(c["coefficients"], fit.params):
            assert rel(ours, theirs) < 1e-6 or abs(ours - theirs) < 1e-9 * abs(fit.params[0])
        for ours, theirs in zip(c["standard_errors"], fit.bse):
            assert rel(ours, theirs) < 1e-6
        assert rel(c["zero_amplitude"]["f"], fit.fvalue) < 1e-6
        assert rel(c["rss"], fit.ssr) < 1e-9
        # Amplitudes, acrophases and delta-method errors from the statsmodels estimates.
        cov = fit.cov_params()
        for comp in c["components"]:
            k = comp["harmonic"]
            b, g = fit.params[2 * k - 1], fit.params[2 * k]
            amp = math.hypot(b, g)
            assert rel(comp["amplitude"], amp) < 1e-6
            assert abs(comp["acrophase"] - math.atan2(-g, b)) < 1e-6
            grad = np.zeros(len(fit.params))
            grad[2 * k - 1], grad[2 * k] = b / amp, g / amp
            assert rel(comp["amplitude_se"], math.sqrt(grad @ cov @ grad)) < 1e-6
            grad[2 * k - 1], grad[2 * k] = g / amp**2, -b / amp**2
            assert rel(comp["acrophase_se"], math.sqrt(grad @ cov @ grad)) < 1e-6


def test_cosinor_equality_tests_match_statsmodels(validated):
    _, report, a = validated
    c = report["cosinor"]["sim"]
    eq = report["cosinor"]["equality"]
    x = design(a["time"], c["frequency_hz"], c["harmonics"])
    n, p = x.shape
    # Interaction model on the stacked data: [X, D X]; H0: D X = 0 (or all but D's intercept).
    dmy = np.r_[np.zeros(n), np.ones(n)][:, None]
    xs = np.vstack([x, x])
    full = sm.OLS(np.r_[a["sim"], a["spiro"]], np.hstack([xs, dmy * xs])).fit()
    r_all = np.hstack([np.zeros((p, p)), np.eye(p)])
    ft = full.f_test(r_all)
    assert rel(eq["f_with_intercept"]["f"], float(ft.fvalue)) < 1e-6
    assert eq["f_with_intercept"]["df_den"] == ft.df_denom
    assert rel(eq["f_with_intercept"]["p_value"], float(ft.pvalue)) < 1e-6 or float(ft.pvalue) < 1e-290
    ft = full.f_test(r_all[1:])
    assert rel(eq["f_without_intercept"]["f"], float(ft.fvalue)) < 1e-6
    # Paired differences: iid F.
    d = a["sim"] - a["spiro"]
    ft = sm.OLS(d, x).fit().f_test(np.eye(p))
    assert rel(eq["paired_f"]["f"], float(ft.fvalue)) < 1e-6


def ar_filter(v, ar, start):
    """v_t - sum_j ar_j v_{t-j} for t = start..n-1 (rows of a matrix or samples of a vector)."""
    out = v[start:].copy()
    for j, aj in enumerate(ar, 1):
        out -= aj * v[start - j:len(v) - j]
    return out


def reml_criterion(ar, x, d, start):
    """(m - k) ln RSS + ln det(X~'X~) of the filtered regression (conditional REML)."""
    xt, dt = ar_filter(x, ar, start), ar_filter(d, ar, start)
    fit = sm.OLS(dt, xt).fit()
    m, k = xt.shape
    return (m - k) * math.log(fit.ssr) + np.linalg.slogdet(xt.T @ xt)[1]


def test_robust_equality_test_matches_statsmodels(validated):
    """The AR-error GLS F test: order by BIC on statsmodels' Yule-Walker fits of the OLS
    residuals, REML optimum of the criterion evaluated here with statsmodels OLS, and the
    F statistics of the filtered regression by statsmodels' f_test."""
    from statsmodels.regression.linear_model import yule_walker

    _, report, a = validated
    c = report["cosinor"]["sim"]
    eq = report["cosinor"]["equality"]
    x = design(a["time"], c["frequency_hz"], c["harmonics"])
    n, p = x.shape
    d = a["sim"] - a["spiro"]
    big_p = eq["robust_config"]["max_order"]
    resid = sm.OLS(d, x).fit().resid
    bic = [n * math.log(np.mean(resid**2)) if k == 0 else
           n * math.log(yule_walker(resid, order=k, method="mle", demean=False, result_object=False)[1] ** 2) + k * math.log(n)
           for k in range(big_p + 1)]
    assert eq["robust_ar_order"] == int(np.argmin(bic))
    ar = np.array(eq["robust_ar"])
    assert len(ar) == eq["robust_ar_order"]
    if len(ar):
        best = reml_criterion(ar, x, d, big_p)
        # No nearby point does better (the search's tolerance is 1e-7 in the PACF).
        for j in range(len(ar)):
            for step in (-1e-3, 1e-3):
                trial = ar.copy()
                trial[j] += step
                assert reml_criterion(trial, x, d, big_p) >= best - 1e-6
    xt, dt = ar_filter(x, ar, big_p), ar_filter(d, ar, big_p)
    fit = sm.OLS(dt, xt).fit()
    # statsmodels' F uses m - k residual df; ours also subtracts the AR order.
    df = len(dt) - p - len(ar)
    for name, r in (("robust_with_intercept", np.eye(p)), ("robust_without_intercept", np.eye(p)[1:])):
        ft = fit.f_test(r)
        ours = eq[name]["f"]
        assert rel(ours["f"], float(ft.fvalue) * df / fit.df_resid) < 1e-6
        assert ours["df_den"] == df
        assert 0 < eq[name]["p_value"] <= 1
        # A bootstrap p-value has the form (1 + c) / (B + 1).
        b = eq["robust_config"]["bootstrap"]
        assert abs(eq[name]["p_value"] * (b + 1) - round(eq[name]["p_value"] * (b + 1))) < 1e-9


def test_alignment_recovers_known_lag(tmp_path):
    if not TORSO.exists():
        pytest.skip("build the release binary first")
    write_sim(tmp_path / "sim.csv")
    for frames in (0, 17, 42):
        out = tmp_path / f"out{frames}"
        run("synth-spirometry", "--from", tmp_path / "sim.csv", "--out", tmp_path / "spiro.csv",
            "--start-offset", frames / FS_SIM, "--noise", "0.005", "--scale", "0.97")
        run("validate", "--sim", tmp_path / "sim.csv", "--spiro", tmp_path / "spiro.csv", "--out", out,
            "--bars-iterations", "300")
        report = json.loads((out / "validation.json").read_text())
        assert report["preparation"]["lag_frames"] == -frames


def test_flow_input_is_integrated(tmp_path):
    if not TORSO.exists():
        pytest.skip("build the release binary first")
    write_sim(tmp_path / "sim.csv")
    run("synth-spirometry", "--from", tmp_path / "sim.csv", "--out", tmp_path / "flow.csv", "--flow",
        "--drift", "0.01", "--noise", "0.002")
    run("validate", "--sim", tmp_path / "sim.csv", "--spiro", tmp_path / "flow.csv", "--out", tmp_path / "o",
        "--bars-iterations", "300")
    report = json.loads((tmp_path / "o" / "validation.json").read_text())
    assert report["spiro_kind"] == "flow"
    # The fitted line also absorbs the trend of the incomplete last breath (18 s holds 4.9
    # breaths of 0.5 L), a few mL/s here.
    assert abs(report["preparation"]["drift_removed_l_per_s"] - 0.01) < 5e-3
    assert report["pearson"]["r"] > 0.99


@pytest.mark.parametrize(
    "text,where,what",
    [
        ("time,volume\n0,1\n0.01,abc\n", ":3:6:", "not a finite number"),
        ("# note\ntime,volume\n0,1\n0.01,2\n0.005,3\n", ":5:1:", "does not increase"),
        ("t,volume\n0,1\n", ":1:1:", "no `time` column"),
        ("time,pressure\n0,1\n", ":1:1:", "no `volume` or `flow` column"),
        ("time,volume\n0,1\n0.01,2\n", ":3:0:", "at least 32"),
    ],
)
def test_bad_csv_errors_name_line_and_column(tmp_path, text, where, what):
    if not TORSO.exists():
        pytest.skip("build the release binary first")
    write_sim(tmp_path / "sim.csv")
    (tmp_path / "spiro.csv").write_text(text)
    proc = run("validate", "--sim", tmp_path / "sim.csv", "--spiro", tmp_path / "spiro.csv", "--out",
               tmp_path / "o", check=False)
    assert proc.returncode != 0
    assert f"spiro.csv{where}" in proc.stderr, proc.stderr
    assert what in proc.stderr, proc.stderr
