#!/usr/bin/env python3
"""Independent reference for the UR10 holdout tables: a D-H calibration
followed by a plain Gaussian-process regression on sin/cos of the joints,
scored by K-fold cross-validation on the real UR10 series
(../shared/data/ipa-ur10, not part of this repository).

Usage (from the repository root; one core is plenty):

    OMP_NUM_THREADS=1 OPENBLAS_NUM_THREADS=1 MKL_NUM_THREADS=1 \\
        python3 benches/dh_gp_reference.py [DATA.csv ...] [--folds 10]
        [--seed 1] [--restarts 2] [--with-dir] [--no-cv] [--no-split]
        [--max-folds K] [--json out.json]

With no DATA the two series are used: ../shared/data/ipa-ur10/
series_b_joint_configurations.csv and series_c_random_poses.csv (relative
to the repository root). A missing file is reported and skipped (exit 0
if none is present). Columns read: q1..q6 (deg), dir1..dir6, ex, ey, ez
(mm, measured - nominal in the robot base frame).

Written and run with Python 3.11.7, numpy 2.4.6, scipy 1.17.1,
scikit-learn 1.9.1 (pip install numpy scipy scikit-learn).

Models
------
* nominal: e_hat = 0.
* D-H calibration: UR10 standard D-H (d1 127.3, a2 -612, a3 -572.3,
  d4 163.941, d5 115.7, d6 92.2 mm; alpha 90, 0, 0, 90, -90, 0 deg; theta
  offsets 0), tool (-0.14, 0.30, 92.82) mm in the flange frame (the series
  C value of the data README; the Series_B and Series_C folders hold the
  same probe-to-flange transform, so B uses it too, and the identified tool
  offset absorbs any difference). Nominal TCP = FK(q); measured TCP =
  nominal + e. Parameters (35): per link d_theta, d_d, d_a, d_alpha (24),
  Hayati d_beta (rotation about y) of links 2 and 3 (the links whose
  consecutive axes are parallel, alpha = 0), tool xyz offset (3), base
  translation (3) and small base rotation (rotation vector, 3). Redundancy:
  the Jacobian at the nominal on the training rows is column-scaled and its
  SVD truncated at singular values < 1e-3 x the largest; least squares
  (scipy.optimize.least_squares, method 'lm', x_scale='jac', numerical
  Jacobian) runs in the coordinates of the kept right singular vectors. On
  both series 25 of 35 are kept: 8 directions are exactly redundant
  (s/s_max ~ 1e-8: link 1's d_theta/d_d duplicate the base rz/z, d2/d3/d4
  lie on parallel axes, link 6's four duplicate the tool offset) and 2 nearly
  (s/s_max ~ 6e-5: link 5's (d_alpha, d_d) and (d_theta, d_a) pairs, as the
  tool point lies almost on axis 6); the next is 6e-3. Keeping those 2
  (tol 1e-6, 27 parameters) changes the 600/300 held-out mean by 0.0005 mm
  but lets d_d5 wander to 18 mm. The calibration predicts
  e_hat_DH = FK_cal(q) - FK_nom(q).
* D-H + GP sin/cos: on the training rows' calibration residual
  r = e - e_hat_DH, one scikit-learn GaussianProcessRegressor per axis (x, y,
  z fitted independently, each its own kernel hyperparameters) on the 12
  inputs [sin q_j, cos q_j], kernel ConstantKernel * RBF(ARD, 12 length
  scales) + WhiteKernel, normalize_y=True, L-BFGS-B with n_restarts_optimizer
  = --restarts (random restarts seeded). Prediction = e_hat_DH + GP mean.
  --with-dir adds the variant "with lambda": the 6 directions dir1..dir6 as
  6 more ARD inputs.

Scoring
-------
--folds K (default 10) cross-validation, partition
numpy.random.default_rng(seed=--seed).permutation(n) split by
numpy.array_split into K folds; everything (calibration included) is
refitted on each training fold. Reported over all held-out rows: mean and
max of the 3D error |e - e_hat|, RMS per axis; for the GP, the 95 % coverage:
the share of held-out (row, axis) pairs with |e - e_hat| <= 1.96 sd, where
sd = sqrt(GP latent variance + white-noise variance) (sklearn's
predict(return_std=True) already includes the WhiteKernel noise; also shown:
the latent-only sd, which should under-cover). Plus the split of the data
README (first 600 rows train, next 300 test), reported for each series.

Measured (2026-11-25, 2 shared cores, 1 BLAS thread; GP one per axis)
--------------------------------------------------------------------
10-fold CV, seed 1, --restarts 0 (one fold of C took 311 s at restarts 0,
so restarts 2 would have taken ~2.5 h; B used 0 too, for the same table):

| series B, 1 495 rows (564 s) | mean 3D | max 3D | RMS x / y / z | 95 % cov. x / y / z |
|---|---|---|---|---|
| nominal | 1.0248 | 2.1345 | 0.5843 / 0.7212 / 0.5610 | – |
| D-H calibration (per fold) | 0.3967 | 2.0175 | 0.2819 / 0.2411 / 0.2430 | – |
| D-H + GP sin/cos | 0.1494 | 2.1759 | 0.1388 / 0.1170 / 0.1005 | 0.930 / 0.975 / 0.982 |

| series C, 2 773 rows (2 734 s) | mean 3D | max 3D | RMS x / y / z | 95 % cov. x / y / z |
|---|---|---|---|---|
| nominal | 0.9014 | 2.2378 | 0.8465 / 0.4135 / 0.2945 | – |
| D-H calibration (per fold) | 0.4371 | 1.5251 | 0.3372 / 0.2720 / 0.2278 | – |
| D-H + GP sin/cos | 0.1730 | 1.3499 | 0.1468 / 0.1050 / 0.0905 | 0.934 / 0.947 / 0.944 |

Split of the data README (series C, first 600 / next 300, --restarts 2):
nominal 0.8683, D-H 0.4352, D-H + GP sin/cos 0.2467 (with lambda 0.2457)
mm mean 3D. The ey GP's optimum depends on the optimiser's path: sklearn's
own gradient (same objective to 1e-14) reached ln L -537.0 instead of
-606.8 and 0.2304 mm; both are this reference, the spread is its noise.
"""

import argparse
import json
import os
import sys
import time
import warnings

import numpy as np

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))
DEFAULT_DATA = [
    os.path.join(ROOT, "..", "shared", "data", "ipa-ur10", "series_b_joint_configurations.csv"),
    os.path.join(ROOT, "..", "shared", "data", "ipa-ur10", "series_c_random_poses.csv"),
]

# UR10 standard D-H, mm and rad.
D = np.array([127.3, 0.0, 0.0, 163.941, 115.7, 92.2])
A = np.array([0.0, -612.0, -572.3, 0.0, 0.0, 0.0])
ALPHA = np.radians([90.0, 0.0, 0.0, 90.0, -90.0, 0.0])
TOOL = np.array([-0.14, 0.30, 92.82])
BETA_LINKS = (1, 2)  # 0-based: links 2 and 3 (alpha = 0, next axis parallel)

# Parameter layout of the full vector (all deltas, zero = nominal).
N_LINK = 6
I_TH, I_D, I_A, I_AL = 0, 6, 12, 18
I_BE = 24
I_TOOL = I_BE + len(BETA_LINKS)
I_BT = I_TOOL + 3
I_BR = I_BT + 3
N_PAR = I_BR + 3
PAR_NAMES = (
    [f"dtheta{i + 1}" for i in range(6)]
    + [f"dd{i + 1}" for i in range(6)]
    + [f"da{i + 1}" for i in range(6)]
    + [f"dalpha{i + 1}" for i in range(6)]
    + [f"dbeta{i + 1}" for i in BETA_LINKS]
    + ["tool_x", "tool_y", "tool_z", "base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz"]
)
SVD_TOL = 1e-3


def rotvec_matrix(w):
    th = np.linalg.norm(w)
    if th < 1e-15:
        return np.eye(3)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def fk(q, p):
    """TCP positions (N, 3) in mm, base frame, for joints q (N, 6) in rad."""
    n = q.shape[0]
    beta = np.zeros(6)
    beta[list(BETA_LINKS)] = p[I_BE:I_TOOL]
    R = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
    t = np.zeros((n, 3))
    for i in range(N_LINK):
        th = q[:, i] + p[I_TH + i]
        d = D[i] + p[I_D + i]
        a = A[i] + p[I_A + i]
        al = ALPHA[i] + p[I_AL + i]
        ct, st = np.cos(th), np.sin(th)
        ca, sa = np.cos(al), np.sin(al)
        cb, sb = np.cos(beta[i]), np.sin(beta[i])
        # Rz(th) Tz(d) Tx(a) Rx(al) Ry(beta)
        Ri = np.empty((n, 3, 3))
        Ri[:, 0, 0], Ri[:, 0, 1], Ri[:, 0, 2] = ct, -st * ca, st * sa
        Ri[:, 1, 0], Ri[:, 1, 1], Ri[:, 1, 2] = st, ct * ca, -ct * sa
        Ri[:, 2, 0], Ri[:, 2, 1], Ri[:, 2, 2] = 0.0, sa, ca
        if beta[i] != 0.0:
            Ry = np.array([[cb, 0, sb], [0, 1, 0], [-sb, 0, cb]])
            Ri = Ri @ Ry
        ti = np.column_stack([a * ct, a * st, np.full(n, d)])
        t = t + np.einsum("nij,nj->ni", R, ti)
        R = R @ Ri
    tool = TOOL + p[I_TOOL:I_BT]
    pos = t + R @ tool
    Rb = rotvec_matrix(p[I_BR:I_BR + 3])
    return pos @ Rb.T + p[I_BT:I_BR]


def num_jac(q, p, h=1e-6):
    J = np.empty((3 * q.shape[0], len(p)))
    for j in range(len(p)):
        dp = np.zeros_like(p)
        dp[j] = h
        J[:, j] = ((fk(q, p + dp) - fk(q, p - dp)) / (2 * h)).ravel()
    return J


class DHCalibration:
    def fit(self, q, e):
        from scipy.optimize import least_squares

        p0 = np.zeros(N_PAR)
        nominal = fk(q, p0)
        measured = nominal + e
        J = num_jac(q, p0)
        scale = np.linalg.norm(J, axis=0)
        scale[scale == 0] = 1.0
        _, s, vt = np.linalg.svd(J / scale, full_matrices=False)
        keep = s > SVD_TOL * s[0]
        self.rank = int(keep.sum())
        basis = vt[keep].T / scale[:, None]  # p = basis @ z
        self.basis = basis

        def resid(z):
            return (fk(q, basis @ z) - measured).ravel()

        sol = least_squares(resid, np.zeros(self.rank), method="lm", x_scale="jac",
                            xtol=1e-12, ftol=1e-12)
        self.p = basis @ sol.x
        self.cost_rms = float(np.sqrt(np.mean(sol.fun ** 2)))
        return self

    def predict(self, q):
        return fk(q, self.p) - fk(q, np.zeros(N_PAR))


def features(q, dirs, with_dir):
    f = [np.sin(q), np.cos(q)]
    if with_dir:
        f.append(dirs)
    return np.column_stack(f)


class FastLML:
    """The log marginal likelihood sklearn's GaussianProcessRegressor
    maximises for ConstantKernel * RBF(ARD) + WhiteKernel with
    normalize_y=True and its default alpha = 1e-10, with its gradient in the
    same log-hyperparameters theta = [ln c, ln l_1..l_d, ln noise], computed
    in O(n^2 d) for the gradient instead of sklearn's (n, n, d + 2) kernel
    gradient tensor (same values to round-off: `self_check`). Only the speed
    differs; sklearn still draws the restarts, keeps the best and predicts."""

    def __init__(self, x, y, alpha=1e-10):
        self.x = x
        std = np.std(y)
        self.y = (y - np.mean(y)) / (std if std > 0 else 1.0)
        self.alpha = alpha

    def __call__(self, theta):
        from scipy.linalg import cho_solve, cholesky, lapack

        n = len(self.y)
        c, ell, nz = np.exp(theta[0]), np.exp(theta[1:-1]), np.exp(theta[-1])
        xs = self.x / ell
        sq = np.sum(xs ** 2, axis=1)
        kr = np.exp(-0.5 * np.maximum(sq[:, None] + sq[None, :] - 2 * xs @ xs.T, 0.0))
        K = c * kr
        K[np.diag_indices(n)] += nz + self.alpha
        try:
            L = cholesky(K, lower=True, check_finite=False)
        except np.linalg.LinAlgError:
            return np.inf, np.zeros_like(theta)
        a = cho_solve((L, True), self.y, check_finite=False)
        lml = -0.5 * self.y @ a - np.log(np.diag(L)).sum() - 0.5 * n * np.log(2 * np.pi)
        kinv, info = lapack.dpotri(L, lower=1)
        kinv = np.tril(kinv) + np.tril(kinv, -1).T
        W = np.outer(a, a) - kinv  # d lml / d theta_k = 0.5 tr(W dK/dtheta_k)
        M = W * (c * kr)
        g = np.empty_like(theta)
        g[0] = 0.5 * M.sum()
        row = M.sum(axis=1)
        g[1:-1] = (xs ** 2).T @ row - np.einsum("ik,ik->k", xs, M @ xs)
        g[-1] = 0.5 * nz * np.trace(W)
        return -lml, -g

    def optimizer(self, obj_func, initial_theta, bounds):
        from scipy.optimize import minimize

        r = minimize(self, initial_theta, method="L-BFGS-B", jac=True, bounds=bounds)
        return r.x, r.fun


def make_kernel(d):
    from sklearn.gaussian_process.kernels import RBF, ConstantKernel, WhiteKernel

    return (ConstantKernel(1.0, (1e-3, 1e3))
            * RBF(np.ones(d), (1e-2, 1e3))
            + WhiteKernel(1e-1, (1e-6, 1e1)))


def self_check(seed=0):
    """FastLML against sklearn's own log_marginal_likelihood (value and
    gradient) at random hyperparameters on random sin/cos-like inputs."""
    from sklearn.gaussian_process import GaussianProcessRegressor

    rng = np.random.default_rng(seed)
    q = rng.uniform(-2 * np.pi, 2 * np.pi, (200, 6))
    x = features(q, None, False)
    y = np.sin(q[:, 0]) + 0.3 * np.cos(2 * q[:, 3]) + 0.1 * rng.standard_normal(200)
    gp = GaussianProcessRegressor(kernel=make_kernel(12), normalize_y=True, optimizer=None).fit(x, y)
    fast = FastLML(x, y)
    worst = 0.0
    for _ in range(3):
        th = rng.uniform(gp.kernel_.bounds[:, 0], gp.kernel_.bounds[:, 1]) * 0.3
        v, g = gp.log_marginal_likelihood(th, eval_gradient=True)
        fv, fg = fast(th)
        worst = max(worst, abs(v + fv) / (1 + abs(v)), np.max(np.abs(g + fg)) / (1 + np.max(np.abs(g))))
    if worst > 1e-8:
        raise SystemExit(f"FastLML disagrees with sklearn's log marginal likelihood (rel. {worst:.2e})")
    return worst


def fit_gp_axis(x, y, restarts, seed):
    from sklearn.gaussian_process import GaussianProcessRegressor

    fast = FastLML(x, y)
    gp = GaussianProcessRegressor(kernel=make_kernel(x.shape[1]), normalize_y=True,
                                  optimizer=fast.optimizer,
                                  n_restarts_optimizer=restarts, random_state=seed)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # ConvergenceWarning at bounds
        gp.fit(x, y)
    return gp


def gp_predict(gp, x):
    mean, sd = gp.predict(x, return_std=True)
    noise = gp.kernel_.k2.noise_level * gp._y_train_std ** 2
    latent = np.sqrt(np.maximum(sd ** 2 - noise, 0.0))
    return mean, sd, latent, float(np.sqrt(noise))


def fit_predict(qtr, dtr, etr, qte, dte, restarts, variants, seed):
    """All models on one train/test split. Returns dict model -> arrays."""
    out = {"nominal": {"pred": np.zeros((len(qte), 3))}}
    t0 = time.time()
    cal = DHCalibration().fit(qtr, etr)
    dh_te = cal.predict(qte)
    out["D-H calibration"] = {"pred": dh_te, "rank": cal.rank, "train_rms": cal.cost_rms,
                              "seconds": time.time() - t0}
    res = etr - cal.predict(qtr)
    for name, with_dir in variants:
        t0 = time.time()
        xtr, xte = features(qtr, dtr, with_dir), features(qte, dte, with_dir)
        pred, sd, lat, kern = np.empty((len(qte), 3)), np.empty((len(qte), 3)), np.empty((len(qte), 3)), []
        for ax in range(3):
            gp = fit_gp_axis(xtr, res[:, ax], restarts, seed + ax)
            m, s, l, nz = gp_predict(gp, xte)
            pred[:, ax], sd[:, ax], lat[:, ax] = dh_te[:, ax] + m, s, l
            kern.append({"kernel": str(gp.kernel_), "noise_sd_mm": nz,
                         "lml": float(gp.log_marginal_likelihood_value_)})
        out[name] = {"pred": pred, "sd": sd, "latent_sd": lat, "kernels": kern,
                     "seconds": time.time() - t0}
    return out


def score(e, pred, sd=None, latent=None):
    err = e - pred
    d3 = np.linalg.norm(err, axis=1)
    s = {"n": int(len(e)), "mean3d": float(d3.mean()), "max3d": float(d3.max()),
         "rms": [float(v) for v in np.sqrt(np.mean(err ** 2, axis=0))]}
    if sd is not None:
        inside = np.abs(err) <= 1.96 * sd
        s["coverage95"] = float(inside.mean())
        s["coverage95_axis"] = [float(v) for v in inside.mean(axis=0)]
        s["coverage95_latent_only"] = float((np.abs(err) <= 1.96 * latent).mean())
    return s


def table(title, scores):
    lines = [f"| {title} | mean 3D (mm) | max 3D (mm) | RMS x / y / z (mm) | 95 % coverage x / y / z (all; latent-only sd) |",
             "|---|---|---|---|---|"]
    for name, s in scores.items():
        cov = "–"
        if "coverage95" in s:
            cx, cy, cz = s["coverage95_axis"]
            cov = f"{cx:.3f} / {cy:.3f} / {cz:.3f} ({s['coverage95']:.3f}; {s['coverage95_latent_only']:.3f})"
        rx, ry, rz = s["rms"]
        lines.append(f"| {name} | {s['mean3d']:.4f} | {s['max3d']:.4f} | {rx:.4f} / {ry:.4f} / {rz:.4f} | {cov} |")
    return "\n".join(lines)


def load(path):
    data = np.genfromtxt(path, delimiter=",", names=True, dtype=float)
    q = np.radians(np.column_stack([data[f"q{i}"] for i in range(1, 7)]))
    dirs = np.column_stack([data[f"dir{i}"] for i in range(1, 7)])
    e = np.column_stack([data[k] for k in ("ex", "ey", "ez")])
    return q, dirs, e


def scores_of(e, out):
    return {name: score(e, r["pred"], r.get("sd"), r.get("latent_sd")) for name, r in out.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("data", nargs="*", default=DEFAULT_DATA)
    ap.add_argument("--folds", type=int, default=10)
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--restarts", type=int, default=2)
    ap.add_argument("--with-dir", action="store_true", help="also the variant with the 6 directions as inputs")
    ap.add_argument("--no-cv", action="store_true")
    ap.add_argument("--no-split", action="store_true", help="skip the 600/300 split")
    ap.add_argument("--max-folds", type=int, default=None, help="run only the first K folds (timing)")
    ap.add_argument("--json", default=None)
    args = ap.parse_args()

    variants = [("D-H + GP sin/cos", False)]
    if args.with_dir:
        variants.append(("D-H + GP sin/cos + λ", True))
    present = [p for p in args.data if os.path.exists(p)]
    for p in args.data:
        if p not in present:
            print(f"data not found, skipped: {p}", file=sys.stderr)
    if not present:
        print("no data file present (the UR10 series live in ../shared/data/ipa-ur10, outside the repository); nothing to do")
        return 0

    check = self_check()
    print(f"FastLML vs sklearn log_marginal_likelihood: max rel. difference {check:.1e}")
    report = {"settings": {"folds": args.folds, "seed": args.seed, "restarts": args.restarts,
                           "with_dir": args.with_dir, "svd_tol": SVD_TOL,
                           "tool_mm": TOOL.tolist(), "fast_lml_check": check}, "series": {}}
    for path in present:
        name = os.path.basename(path)
        q, dirs, e = load(path)
        n = len(e)
        rep = {"rows": n}
        print(f"\n## {name} ({n} rows)\n")

        cal = DHCalibration().fit(q, e)
        rep["all_rows_calibration"] = {
            "rank": cal.rank, "n_params": N_PAR,
            "rms_nominal": [float(v) for v in np.sqrt(np.mean(e ** 2, axis=0))],
            "rms_calibrated": [float(v) for v in np.sqrt(np.mean((e - cal.predict(q)) ** 2, axis=0))],
            "params": dict(zip(PAR_NAMES, cal.p.tolist())),
        }
        a = rep["all_rows_calibration"]
        print("Calibration on all rows (fit quality, not a prediction): "
              f"{cal.rank} of {N_PAR} parameters kept; RMS x/y/z "
              + " / ".join(f"{v:.4f}" for v in a["rms_nominal"]) + " -> "
              + " / ".join(f"{v:.4f}" for v in a["rms_calibrated"]) + " mm\n")

        if not args.no_split and n >= 900:
            t0 = time.time()
            out = fit_predict(q[:600], dirs[:600], e[:600], q[600:900], dirs[600:900],
                              args.restarts, variants + ([("D-H + GP sin/cos + λ", True)] if not args.with_dir else []),
                              args.seed)
            sc = scores_of(e[600:900], out)
            secs = time.time() - t0
            rep["split_600_300"] = {"scores": sc, "seconds": secs,
                                    "kernels": {k: v["kernels"] for k, v in out.items() if "kernels" in v}}
            print(table("first 600 train / next 300 test", sc))
            print(f"\n({secs:.1f} s)\n")

        if not args.no_cv:
            t0 = time.time()
            perm = np.random.default_rng(seed=args.seed).permutation(n)
            folds = np.array_split(perm, args.folds)
            if args.max_folds:
                folds = folds[:args.max_folds]
            held = np.concatenate(folds)
            preds = {}
            fold_info = []
            for k, te in enumerate(folds):
                tf = time.time()
                tr = np.setdiff1d(perm, te)
                out = fit_predict(q[tr], dirs[tr], e[tr], q[te], dirs[te], args.restarts, variants,
                                  args.seed + 10 * k)
                for m, r in out.items():
                    dst = preds.setdefault(m, {key: np.empty((n, 3)) for key in ("pred", "sd", "latent_sd") if key in r})
                    for key in dst:
                        dst[key][te] = r[key]
                fs = scores_of(e[te], out)
                fold_info.append({"fold": k, "n_test": int(len(te)), "seconds": time.time() - tf,
                                  "dh_rank": out["D-H calibration"]["rank"],
                                  "dh_train_rms_mm": out["D-H calibration"]["train_rms"],
                                  "mean3d": {m: s["mean3d"] for m, s in fs.items()},
                                  "kernels": {m: r["kernels"] for m, r in out.items() if "kernels" in r}})
                print(f"fold {k + 1}/{len(folds)}: {time.time() - tf:.1f} s, "
                      + ", ".join(f"{m} {s['mean3d']:.4f}" for m, s in fs.items()), flush=True)
            sc = {m: score(e[held], r["pred"][held],
                           r["sd"][held] if "sd" in r else None,
                           r["latent_sd"][held] if "latent_sd" in r else None)
                  for m, r in preds.items()}
            secs = time.time() - t0
            rep["cv"] = {"scores": sc, "seconds": secs, "folds": fold_info}
            print()
            print(table(f"{len(folds)}-fold CV (seed {args.seed}), D-H refitted per fold, restarts {args.restarts}", sc))
            print(f"\n({secs:.1f} s)\n")
        report["series"][name] = rep

    if args.json:
        with open(args.json, "w") as f:
            json.dump(report, f, indent=1)
        print(f"wrote {args.json}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
