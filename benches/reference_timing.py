#!/usr/bin/env python3
"""Reference fit timings of Python Kriging/GP libraries on the robokrige data.

Run from the crate root (single-threaded BLAS, as for every Python reference):

    OPENBLAS_NUM_THREADS=1 OMP_NUM_THREADS=1 MKL_NUM_THREADS=1 \
        python3 benches/reference_timing.py [--smt-quadratic] [--only smt,egobox,sklearn] \
        [--outputs ex,ey,ez] [--json results.json]

egobox parallelises its multistart with rayon; set RAYON_NUM_THREADS=1 as
well for a strictly single-threaded figure (the value in effect is printed).

Data: datasets/comau_lhs.csv, all 300 rows, ejs space = [q1..q6, dir1..dir6]
(12 dims), outputs ex, ey, ez fitted independently (the time per output and
the sum over the outputs are reported). A quadratic trend is rank-deficient on
ejs (dir columns are +-1, so their squares are constant: rank(F) = 85 < 91;
SMT and egobox both refuse it: "F is too ill conditioned"), so the quadratic
rows use the js space [q1..q6] (6 dims, 28 basis functions) instead.

Libraries and settings (all defaults unless said):
  * SMT 2.15 KRG(poly=..., corr="squar_exp"): TNC multistart (n_start=10 ->
    12 starts), theta0=1e-2, theta_bounds=[1e-6, 20]. SMT quadratic (js) only
    with --smt-quadratic (20-45 s per output here; the js problem is small).
  * egobox 1.0 Gpx.builder(regr_spec=CONSTANT|LINEAR|QUADRATIC,
    corr_spec=SQUARED_EXPONENTIAL, seed=42): COBYLA multistart
    (theta_n_start=10, theta_max_eval=50), theta_init=0.1, bounds [1e-2, 10].
  * scikit-learn GaussianProcessRegressor(ConstantKernel()*RBF(ARD ones),
    normalize_y=True, n_restarts_optimizer=0, alpha=1e-10 default), on inputs
    z-scored like SMT (ddof=1) so that the length scales are in the same units.

theta is reported in the DACE/SMT convention R = exp(-sum theta_k d_k^2) on
inputs z-scored with the sample std:
  * egobox's squared exponential is exp(-1/2 sum (theta_k d_k)^2) on the same
    normalisation (checked: predictions equal the DACE formulas at
    theta_dace = theta_ego^2/2), so theta_dace = theta_ego^2 / 2;
  * sklearn RBF exp(-1/2 sum d_k^2/l_k^2) -> theta_dace = 1 / (2 l_k^2).
psi is the concentrated DACE objective det(R)^(1/m)*sigma2 (normalised units,
nugget 100*eps on the diagonal, as SMT) computed with numpy at that theta and
the row's trend (sklearn: constant trend; sklearn maximises the plain GP
marginal likelihood with zero mean and its own alpha=1e-10 jitter, so its theta
is not expected to minimise psi). psi_own is the library's own value when it
reports one (SMT and egobox: 10**(-reduced_likelihood/m)).
"""

import argparse
import json
import os
import platform
import sys
import time
import warnings

import numpy as np

HERE = os.path.dirname(os.path.abspath(__file__))
ROOT = os.path.abspath(os.path.join(HERE, ".."))
sys.dont_write_bytecode = True   # no __pycache__ in tests/fixtures
sys.path.insert(0, os.path.join(ROOT, "tests", "fixtures"))
from gen_kriging_fixtures import (  # noqa: E402  (numpy DACE reference)
    NumpyUK, SPACES, TRAIN_CSV, design, load_csv, zscore_params)


def psi_at(X, y, theta, trend):
    try:
        return NumpyUK(X, y, theta, trend).psi
    except Exception:  # noqa: BLE001  (e.g. R not positive definite)
        return float("nan")


def fit_smt(X, y, trend):
    from smt.surrogate_models import KRG
    sm = KRG(poly=trend, corr="squar_exp", print_global=False)
    sm.set_training_values(X, y)
    t0 = time.perf_counter()
    sm.train()
    secs = time.perf_counter() - t0
    th = np.asarray(sm.optimal_theta, float)
    return secs, th, 10.0 ** (-float(sm.optimal_rlf_value) / len(y))


def fit_egobox(X, y, trend):
    import egobox as egx
    spec = {"constant": egx.RegressionSpec.CONSTANT,
            "linear": egx.RegressionSpec.LINEAR,
            "quadratic": egx.RegressionSpec.QUADRATIC}[trend]
    t0 = time.perf_counter()
    gp = egx.Gpx.builder(regr_spec=spec,
                         corr_spec=egx.CorrelationSpec.SQUARED_EXPONENTIAL,
                         seed=42).fit(X, y)
    secs = time.perf_counter() - t0
    th_ego = np.asarray(gp.thetas[0], float)
    return secs, th_ego ** 2 / 2.0, 10.0 ** (-float(gp.likelihoods[0]) / len(y))


def fit_sklearn(X, y, trend):
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel
    mu, sd = zscore_params(X)
    S = (X - mu) / sd
    kernel = ConstantKernel(1.0) * RBF(length_scale=np.ones(X.shape[1]))
    gpr = GaussianProcessRegressor(kernel=kernel, normalize_y=True,
                                   n_restarts_optimizer=0, random_state=0)
    t0 = time.perf_counter()
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")   # length-scale bound ConvergenceWarnings
        gpr.fit(S, y)
    secs = time.perf_counter() - t0
    ls = np.asarray(gpr.kernel_.k2.length_scale, float)
    return secs, 1.0 / (2.0 * ls ** 2), float("nan")


FITTERS = {"smt": fit_smt, "egobox": fit_egobox, "sklearn": fit_sklearn}


def cpu_model():
    try:
        with open("/proc/cpuinfo") as fh:
            for line in fh:
                if line.startswith("model name"):
                    return line.split(":", 1)[1].strip()
    except OSError:
        pass
    return platform.processor()


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--smt-quadratic", action="store_true",
                    help="also time SMT KRG quadratic (js space, 20-45 s/output)")
    ap.add_argument("--only", default="smt,egobox,sklearn")
    ap.add_argument("--outputs", default="ex,ey,ez")
    ap.add_argument("--json", default=None, help="also dump the rows as JSON")
    args = ap.parse_args()
    libs = args.only.split(",")
    outputs = args.outputs.split(",")

    train = load_csv(TRAIN_CSV)
    plan = []
    for lib in ("smt", "egobox", "sklearn"):
        if lib not in libs:
            continue
        if lib == "sklearn":
            plan.append((lib, "ejs", "constant"))
            continue
        plan += [(lib, "ejs", "constant"), (lib, "ejs", "linear")]
        if lib != "smt" or args.smt_quadratic:
            plan.append((lib, "js", "quadratic"))

    import sklearn
    import smt
    import egobox
    info = {
        "nproc": os.cpu_count(), "cpu": cpu_model(),
        "python": platform.python_version(), "numpy": np.__version__,
        "smt": smt.__version__, "egobox": egobox.__version__,
        "sklearn": sklearn.__version__,
        "env": {k: os.environ.get(k) for k in
                ("OPENBLAS_NUM_THREADS", "OMP_NUM_THREADS", "MKL_NUM_THREADS",
                 "RAYON_NUM_THREADS")},
    }
    print("# " + json.dumps(info))
    rows = []
    hdr = (f"{'library':8s} {'space':5s} {'trend':9s} {'out':3s} {'seconds':>9s} "
           f"{'psi(numpy)':>14s} {'psi_own':>14s}  theta (DACE convention)")
    print(hdr)
    print("-" * len(hdr))
    for lib, space, trend in plan:
        X = design(train, space)
        for o in outputs:
            y = train[o]
            try:
                secs, th, psi_own = FITTERS[lib](X, y, trend)
            except Exception as e:  # noqa: BLE001
                print(f"{lib:8s} {space:5s} {trend:9s} {o:3s} FAILED: {e}", flush=True)
                rows.append({"library": lib, "space": space, "trend": trend,
                             "output": o, "error": str(e)})
                continue
            psi_trend = "constant" if lib == "sklearn" else trend
            psi = psi_at(X, y, th, psi_trend)
            rows.append({"library": lib, "space": space, "trend": trend, "output": o,
                         "seconds": secs, "theta": [float(v) for v in th],
                         "psi": psi, "psi_trend": psi_trend, "psi_own": psi_own})
            th_s = "[" + " ".join(f"{v:.3g}" for v in th) + "]"
            print(f"{lib:8s} {space:5s} {trend:9s} {o:3s} {secs:9.2f} {psi:14.8g} "
                  f"{psi_own:14.8g}  {th_s}", flush=True)

    print()
    print(f"{'library':8s} {'space':5s} {'trend':9s} {'ex (s)':>9s} {'sum ' + '+'.join(outputs) + ' (s)':>16s}")
    for lib, space, trend in plan:
        rs = [r for r in rows if (r["library"], r["space"], r["trend"]) == (lib, space, trend)
              and "seconds" in r]
        ex = [r["seconds"] for r in rs if r["output"] == "ex"]
        tot = sum(r["seconds"] for r in rs)
        print(f"{lib:8s} {space:5s} {trend:9s} {ex[0] if ex else float('nan'):9.2f} {tot:16.2f}")

    if args.json:
        with open(args.json, "w") as fh:
            json.dump({"info": info, "rows": rows}, fh, indent=1)


if __name__ == "__main__":
    main()
