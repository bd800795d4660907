"""Size of kernel (HAC) Wald tests on the paired cosinor regression, the tests `torso
validate` no longer uses: why the robust equality test is an AR-error GLS test instead.

Setting as `stats::montecarlo` (examples/equality_size.rs): N samples at 56 Hz, cosinor
with 4 harmonics of 0.25 Hz, d = e1 - e2 with e1, e2 independent AR(1) series, so every
coefficient of d is zero (a true null). Wald test of all 9 coefficients, F(9, N - 9)
reference, level 0.05. Tests:

- Newey-West (1987) Bartlett covariance at fixed lags, from statsmodels' `cov_hac`
  (`use_correction=False`), the former `torso validate` default being one breathing period
  (224 samples);
- Andrews & Monahan (1992, Econometrica 60:953) VAR(1) prewhitening of the scores
  x_t e_t (singular values of the VAR matrix capped at 0.97), quadratic-spectral kernel
  with the Andrews (1991, Econometrica 59:817, eq. 6.4) AR(1) plug-in bandwidth
  1.3221 (alpha(2) N)^(1/5) on the prewhitened scores, recoloured by (I - A)^-1.

Then, at AR(1) 0.9, the bias of the autoregression fitted to the OLS residuals: the mean
Yule-Walker AR(1) coefficient, and the mean ratio of the first harmonic's coefficient
variance that coefficient implies to the true one, both computed from the AR(1)
autocovariances (Toeplitz, exact).

    .venv/bin/python python/hac_size.py [REPLICATIONS] [N]   (default 2000, 500)
"""

import sys

import numpy as np
import scipy.stats as st
from statsmodels.stats.sandwich_covariance import cov_hac
import statsmodels.api as sm

FS, F0, C = 56.0, 0.25, 4


def design(n):
    t = np.arange(n) / FS
    cols = [np.ones(n)]
    for k in range(1, C + 1):
        cols += [np.cos(2 * np.pi * k * F0 * t), np.sin(2 * np.pi * k * F0 * t)]
    return np.column_stack(cols)


def ar1(rng, n, phi):
    e = np.empty(n)
    e[0] = rng.normal() / np.sqrt(1 - phi**2) if phi else rng.normal()
    u = rng.normal(size=n)
    for i in range(1, n):
        e[i] = phi * e[i - 1] + u[i]
    return e


def qs_weights(n, bw):
    x = np.arange(1, n) / bw
    z = 6 * np.pi * x / 5
    return 25 / (12 * np.pi**2 * x**2) * (np.sin(z) / z - np.cos(z))


def andrews_monahan(x, resid):
    n, p = x.shape
    u = x * resid[:, None]
    a = np.linalg.lstsq(u[:-1], u[1:], rcond=None)[0].T
    uu, s, vt = np.linalg.svd(a)
    a = uu @ np.diag(np.minimum(s, 0.97)) @ vt
    v = u[1:] - u[:-1] @ a.T
    num = den = 0.0
    for j in range(p):
        y = v[:, j]
        rho = (y[1:] @ y[:-1]) / (y[:-1] @ y[:-1])
        s2 = np.mean((y[1:] - rho * y[:-1]) ** 2)
        num += 4 * rho**2 * s2**2 / (1 - rho) ** 8
        den += s2**2 / (1 - rho) ** 4
    bw = 1.3221 * (num / den * len(v)) ** 0.2
    w = qs_weights(len(v), bw)
    s_hat = v.T @ v
    for lag, wl in enumerate(w, 1):
        g = v[lag:].T @ v[:-lag]
        s_hat += wl * (g + g.T)
    s_hat *= n / len(v)
    b = np.linalg.inv(np.eye(p) - a)
    xi = np.linalg.inv(x.T @ x)
    return xi @ (b @ s_hat @ b.T) @ xi


def main(reps, n):
    x = design(n)
    p = x.shape[1]
    print(f"| N | phi | Newey-West L = 10 | Newey-West L = 224 | Andrews-Monahan prewhitened QS |")
    print("|---|---|---|---|---|")
    for phi in (0.0, 0.5, 0.9):
        rng = np.random.default_rng(1)
        rej = np.zeros(3)
        for _ in range(reps):
            d = ar1(rng, n, phi) - ar1(rng, n, phi)
            fit = sm.OLS(d, x).fit()
            b = fit.params
            for i, cov in enumerate(
                (cov_hac(fit, nlags=10, use_correction=False),
                 cov_hac(fit, nlags=224, use_correction=False),
                 andrews_monahan(x, fit.resid))):
                w = b @ np.linalg.solve(cov, b) / p
                rej[i] += st.f.sf(w, p, n - p) < 0.05
        r = rej / reps
        print(f"| {n} | {phi} | {r[0]:.3f} | {r[1]:.3f} | {r[2]:.3f} |")
    residual_ar1_bias(x, reps, n, 0.9)


def harmonic_variance(x, phi):
    from scipy.linalg import toeplitz
    g = toeplitz(phi ** np.arange(len(x)) / (1 - phi**2))
    xi = np.linalg.inv(x.T @ x)
    return (xi @ x.T @ g @ x @ xi)[1, 1]


def residual_ar1_bias(x, reps, n, phi):
    rng = np.random.default_rng(2)
    truth = harmonic_variance(x, phi)
    est, ratio = [], []
    for _ in range(min(reps, 400)):
        d = ar1(rng, n, phi)
        res = sm.OLS(d, x).fit().resid
        a = (res[1:] @ res[:-1]) / (res @ res)
        s2 = np.mean(res**2) * (1 - a**2)  # innovation variance of the fitted AR(1)
        est.append(a)
        ratio.append(s2 * harmonic_variance(x, a) / truth)
    print(f"\nAR({phi}) errors, N = {n}: Yule-Walker AR(1) of the OLS residuals {np.mean(est):.3f} "
          f"(true {phi}); implied variance of the first harmonic's coefficient / true: {np.mean(ratio):.2f}")


if __name__ == "__main__":
    main(int(sys.argv[1]) if len(sys.argv) > 1 else 2000, int(sys.argv[2]) if len(sys.argv) > 2 else 500)
