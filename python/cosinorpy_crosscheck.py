"""Cross-check of the cosinor numbers of `torso validate` against CosinorPy.

CosinorPy needs numpy < 2, so it lives in its own venv, outside the test suite:

    python3 -m venv /tmp/cosinorpy-venv
    /tmp/cosinorpy-venv/bin/pip install "numpy<2" "pandas<2" CosinorPy seaborn
    /tmp/cosinorpy-venv/bin/python python/cosinorpy_crosscheck.py OUT_DIR

OUT_DIR is a `torso validate --out` directory. Compares the residual sums of squares and
zero-amplitude F statistics of both fits (`cosinor.fit_me`) and the p-value of the equality
test with the intercept (`cosinor.compare_pair_df_extended`, which computes 1 - cdf and so
loses digits below about 1e-15; use a pair whose p-value is not tiny). Exits 1 on a mismatch.
"""

import json
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")
import numpy as np  # noqa: E402
import pandas as pd  # noqa: E402
from CosinorPy import cosinor  # noqa: E402


def main(out_dir):
    out = pathlib.Path(out_dir)
    report = json.loads((out / "validation.json").read_text())
    a = np.genfromtxt(out / "aligned.csv", delimiter=",", names=True)
    c = report["cosinor"]
    period = 1.0 / c["sim"]["frequency_hz"]
    harmonics = c["sim"]["harmonics"]
    ok = True

    def check(name, ours, theirs, tol=1e-6):
        nonlocal ok
        good = abs(ours - theirs) <= tol * max(abs(theirs), 1e-12)
        ok &= good
        print(f"{name:40s} torso {ours:.12g}  CosinorPy {theirs:.12g}  {'ok' if good else 'MISMATCH'}")

    for name in ("sim", "spiro"):
        res = cosinor.fit_me(a["time"], a[name], n_components=harmonics, period=period, plot=False)
        results = res[0]
        check(f"{name}: RSS", c[name]["rss"], results.ssr)
        check(f"{name}: zero-amplitude F", c[name]["zero_amplitude"]["f"], results.fvalue)
    df = pd.DataFrame(
        {
            "test": ["sim"] * len(a) + ["spiro"] * len(a),
            "x": np.r_[a["time"], a["time"]],
            "y": np.r_[a["sim"], a["spiro"]],
        }
    )
    p_overall, p_params, p_f, *_ = cosinor.compare_pair_df_extended(
        df, "sim", "spiro", n_components=harmonics, period=period, plot=False
    )
    check("equality p (with intercept)", c["equality"]["f_with_intercept"]["p_value"], p_f, tol=1e-6)
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
