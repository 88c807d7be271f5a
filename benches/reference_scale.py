#!/usr/bin/env python3
"""Reference fits at the sizes of the likelihood-core scale table.

Run after `cargo bench --bench likelihood_core -- --scale`, which writes
target/bench-data/{train,test}_M.csv and floor_M.txt (simulated COMAU
campaigns, 200 held-out poses of the same true robot):

    OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 \
        python3 benches/reference_scale.py 300,600,1200 [--only sklearn,egobox]

Inputs: the extended joint space [q1..q6, dir1..dir6], z-scored on the
training rows; outputs ex, ey, ez fitted independently (the fit time is the
sum over the three). Held-out: RMS of the 3D error over the test poses,
divided by the floor sqrt(sx^2 + sy^2 + sz^2) (the simulator's noise RMS).

  * scikit-learn GaussianProcessRegressor(ConstantKernel() * RBF(ARD ones)
    + WhiteKernel(), normalize_y=True), default L-BFGS-B, no restarts.
  * egobox Gpx.builder(regr_spec=CONSTANT, corr_spec=SQUARED_EXPONENTIAL,
    seed=42), its defaults otherwise (interpolating, COBYLA multistart).
"""

import sys
import time

import numpy as np


def load(path):
    data = np.genfromtxt(path, delimiter=",", names=True, dtype=float)
    names = data.dtype.names
    q = [n for n in names if n.startswith("q")]
    d = [n for n in names if n.startswith("dir")]
    x = np.column_stack([data[n] for n in q + d])
    y = np.column_stack([data[n] for n in ("ex", "ey", "ez")])
    return x, y


def sklearn_fit_predict(xt, yt, xv):
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    out = []
    for a in range(3):
        k = ConstantKernel() * RBF(np.ones(xt.shape[1])) + WhiteKernel()
        gp = GaussianProcessRegressor(kernel=k, normalize_y=True)
        gp.fit(xt, yt[:, a])
        out.append(gp.predict(xv))
    return np.column_stack(out)


def egobox_fit_predict(xt, yt, xv):
    import egobox as egx

    out = []
    for a in range(3):
        gp = egx.Gpx.builder(
            regr_spec=egx.RegressionSpec.CONSTANT,
            corr_spec=egx.CorrelationSpec.SQUARED_EXPONENTIAL,
            seed=42,
        ).fit(xt, yt[:, a : a + 1])
        out.append(np.asarray(gp.predict(xv)).reshape(-1))
    return np.column_stack(out)


def families(libs):
    """The splits of `cargo bench --bench likelihood_core -- --families`."""
    import glob

    print("| campaign | library | fit s | held-out RMS 3D / floor |")
    print("|---|---|---|---|")
    for train in sorted(glob.glob("target/bench-data/fam_*_train.csv")):
        base = train[: -len("_train.csv")]
        xt, yt = load(train)
        xv, yv = load(base + "_test.csv")
        floor, name = open(base + "_floor.txt").read().split(" ", 1)
        floor = float(floor)
        mu, sd = xt.mean(axis=0), xt.std(axis=0, ddof=1)
        sd[sd == 0] = 1.0
        xt, xv = (xt - mu) / sd, (xv - mu) / sd
        for lib, f in libs.items():
            t0 = time.perf_counter()
            p = f(xt, yt, xv)
            secs = time.perf_counter() - t0
            rms = np.sqrt(np.mean(np.sum((p - yv) ** 2, axis=1)))
            print(f"| {name.strip()} | {lib} | {secs:.1f} | {rms / floor:.2f}× |", flush=True)


def main():
    if "--families" in sys.argv:
        families({"sklearn": sklearn_fit_predict, "egobox": egobox_fit_predict})
        return
    sizes = [int(v) for v in (sys.argv[1] if len(sys.argv) > 1 else "300,600,1200").split(",")]
    only = None
    if "--only" in sys.argv:
        only = sys.argv[sys.argv.index("--only") + 1].split(",")
    libs = {"sklearn": sklearn_fit_predict, "egobox": egobox_fit_predict}
    print("| m | library | fit s | held-out RMS 3D / floor |")
    print("|---|---|---|---|")
    for m in sizes:
        xt, yt = load(f"target/bench-data/train_{m}.csv")
        xv, yv = load(f"target/bench-data/test_{m}.csv")
        floor = float(open(f"target/bench-data/floor_{m}.txt").read())
        mu, sd = xt.mean(axis=0), xt.std(axis=0, ddof=1)
        sd[sd == 0] = 1.0
        xt, xv = (xt - mu) / sd, (xv - mu) / sd
        for name, f in libs.items():
            if only and name not in only:
                continue
            t0 = time.perf_counter()
            try:
                p = f(xt, yt, xv)
            except Exception as e:  # a library that fails is reported, not fatal
                print(f"| {m} | {name} | failed: {e} | - |")
                continue
            secs = time.perf_counter() - t0
            rms = np.sqrt(np.mean(np.sum((p - yv) ** 2, axis=1)))
            print(f"| {m} | {name} | {secs:.1f} | {rms / floor:.2f}× |", flush=True)


if __name__ == "__main__":
    main()
