"""Eigenvalues of a right-hand-side Jacobian written by `examples/jacobian_dump.rs`: the
fastest modes, the state components they live in, and the largest step Dormand-Prince 5(4)
can take with every h * lambda inside its stability region.

    cargo run --release --example jacobian_dump -- 1 1.5 /tmp/jac1.bin
    .venv/bin/python python/spectrum.py /tmp/jac1.bin [--modes 12]
"""

import argparse

import numpy as np

RIBS = 24


def component_name(i, n):
    """Names state component i of the layout in src/dynamics/state.rs."""
    nv = (n - RIBS - 7 - RIBS - 6) // 6
    vx = RIBS + 7
    td = vx + 3 * nv
    sv = td + RIBS
    sw = sv + 3
    vv = sw + 3
    if i < RIBS:
        return f"rib angle {i}"
    if i < RIBS + 3:
        return f"sternum position {i - RIBS}"
    if i < vx:
        return f"sternum quaternion {i - RIBS - 3}"
    if i < td:
        return f"vertex {(i - vx) // 3} position"
    if i < sv:
        return f"rib rate {i - td}"
    if i < sw:
        return f"sternum velocity {i - sv}"
    if i < vv:
        return f"sternum angular velocity {i - sw}"
    return f"vertex {(i - vv) // 3} velocity"


def dopri5_stability(z):
    """|R(z)| of Dormand-Prince 5(4) (its 5th-order solution, 7 stages with FSAL)."""
    coefficients = [1, 1, 1 / 2, 1 / 6, 1 / 24, 1 / 120, 1 / 600]
    return np.abs(sum(c * z**k for k, c in enumerate(coefficients)))


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("file")
    parser.add_argument("--modes", type=int, default=12)
    parser.add_argument("--slow", type=int, default=0,
                        help="also list this many of the slowest oscillating modes "
                             "(frequency and damping ratio)")
    args = parser.parse_args()
    n = int(np.fromfile(args.file, dtype="<u8", count=1)[0])
    jac = np.fromfile(args.file, dtype="<f8", offset=8).reshape(n, n).T
    values, vectors = np.linalg.eig(jac)
    order = np.argsort(-np.abs(values))
    print(f"{args.file}: {n} states")
    shown = 0
    for k in order:
        if values[k].imag < 0:
            continue
        weight = np.abs(vectors[:, k])
        top = np.argsort(-weight)[:3]
        angle = np.degrees(np.arctan2(abs(values[k].imag), -values[k].real))
        names = ", ".join(component_name(i, n) for i in top)
        print(f"|lambda| {abs(values[k]):7.1f} /s  ({values[k].real:8.1f} {values[k].imag:+8.1f}i, "
              f"{angle:4.1f} deg from the negative real axis): {names}")
        shown += 1
        if shown >= args.modes:
            break
    if args.slow:
        osc = [k for k in range(n) if values[k].imag > 1e-9]
        osc.sort(key=lambda k: abs(values[k]))
        print("slowest oscillating modes:")
        for k in osc[:args.slow]:
            weight = np.abs(vectors[:, k])
            top = np.argsort(-weight)[:3]
            zeta = -values[k].real / abs(values[k])
            names = ", ".join(component_name(i, n) for i in top)
            print(f"  {abs(values[k]) / (2 * np.pi):6.2f} Hz, damping ratio {zeta:5.3f}: {names}")
        damping = -values.real / np.abs(values)
        inertial = values.imag > 1e-9
        print(f"oscillating pairs: {inertial.sum()}, below 20 Hz: "
              f"{(inertial & (np.abs(values) < 2 * np.pi * 20)).sum()}, "
              f"median damping ratio {np.median(damping[inertial]):.3f}, "
              f"below 0.2: {(inertial & (damping < 0.2)).sum()}")
    lo, hi = 1e-6, 1.0
    for _ in range(80):
        h = (lo * hi) ** 0.5
        if np.all(dopri5_stability(h * values) <= 1 + 1e-9):
            lo = h
        else:
            hi = h
    print(f"largest stable Dormand-Prince 5(4) step: {lo * 1e3:.2f} ms "
          f"(spectral radius {np.abs(values).max():.1f} /s)")


if __name__ == "__main__":
    main()
