"""robokrige (Python, the command line's defaults) against scikit-learn's
GaussianProcessRegressor on the same data: fit time and held-out error.

    python python/benches/vs_sklearn.py --train datasets/comau_lhs.csv \
        --test HELD_OUT.csv [--truth HELD_OUT.truth.json] [--rounds 3]

Inputs: the extended joint space [q1..qN, dir1..dirN]. scikit-learn:
ConstantKernel() * RBF(ARD, ones) + WhiteKernel(), normalize_y=True, its
default L-BFGS-B without restarts, one GP per axis on inputs z-scored on the
training rows (as benches/reference_scale.py). Held-out error: RMS and mean
of the 3D error |measured − predicted| over the test poses (mm), and the RMS
over the simulator's noise floor when the truth file is given. Fit times are
medians over the rounds (wall clock, this machine's threads).
"""

import argparse
import json
import statistics
import time

import numpy as np

import robokrige as rk


def arrays(path):
    t = rk.read_campaign(path, as_frame=False)
    n = sum(1 for k in t if k.startswith("q") and k[1:].isdigit())
    q = np.column_stack([t[f"q{j}"] for j in range(1, n + 1)])
    d = np.column_stack([t[f"dir{j}"] for j in range(1, n + 1)])
    e = np.column_stack([t[a] for a in ("ex", "ey", "ez")])
    return q, d, e


def robokrige_fit_predict(q, d, e, qv, dv):
    m = rk.ErrorModel().fit(q, d, e)
    return m, m.predict(qv, dv)


def sklearn_fit_predict(q, d, e, qv, dv):
    from sklearn.gaussian_process import GaussianProcessRegressor
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    x, xv = np.hstack([q, d]), np.hstack([qv, dv])
    mu, sd = x.mean(axis=0), x.std(axis=0)
    sd[sd == 0] = 1.0
    x, xv = (x - mu) / sd, (xv - mu) / sd
    gps, out = [], []
    for a in range(3):
        k = ConstantKernel() * RBF(np.ones(x.shape[1])) + WhiteKernel()
        gp = GaussianProcessRegressor(kernel=k, normalize_y=True)
        gp.fit(x, e[:, a])
        gps.append(gp)
        out.append(gp.predict(xv))
    return gps, np.column_stack(out)


def main() -> None:
    ap = argparse.ArgumentParser()
    ap.add_argument("--train", default="datasets/comau_lhs.csv")
    ap.add_argument("--test", required=True)
    ap.add_argument("--truth")
    ap.add_argument("--rounds", type=int, default=3)
    a = ap.parse_args()
    q, d, e = arrays(a.train)
    qv, dv, ev = arrays(a.test)
    floor = None
    if a.truth:
        f = json.load(open(a.truth)).get("noise_floor_mm")
        floor = float(np.sqrt(np.sum(np.square(f)))) if f else None
    rows = {}
    for name, fn in (("robokrige", robokrige_fit_predict), ("sklearn", sklearn_fit_predict)):
        times, pred = [], None
        for _ in range(a.rounds):
            t0 = time.perf_counter()
            _, pred = fn(q, d, e, qv, dv)
            times.append(time.perf_counter() - t0)
        err = np.linalg.norm(ev - pred, axis=1)
        rows[name] = {
            "fit_predict_s_median": statistics.median(times),
            "fit_predict_s_all": times,
            "heldout_rms_3d_mm": float(np.sqrt(np.mean(err**2))),
            "heldout_mean_3d_mm": float(np.mean(err)),
            "heldout_rms_over_floor": None if floor is None else float(np.sqrt(np.mean(err**2)) / floor),
        }
    print(json.dumps({"train": a.train, "rows": len(q), "test": a.test, "poses": len(qv),
                      "noise_floor_3d_mm": floor, "wheel_build": rk.build_target_cpu(),
                      "results": rows}, indent=1))


if __name__ == "__main__":
    main()
