# %% [markdown]
# # fit → CV → compensate → diagnose, from Python
#
# The README's closed loop (`examples/closed_loop.rs`) on the shipped COMAU
# campaign, with the `robokrige` package: a notebook in the percent format
# (Jupyter, VS Code and jupytext open it cell by cell) that also runs as a
# script:
#
#     python python/examples/closed_loop.py [--out closed_loop.png]
#
# It needs pandas and matplotlib (`pip install pandas matplotlib`).

# %%
import argparse
import pathlib
import sys

import matplotlib

if __name__ == "__main__" and "ipykernel" not in sys.modules:
    matplotlib.use("Agg")  # a script: draw to a file
import matplotlib.pyplot as plt
import numpy as np

import robokrige as rk

ap = argparse.ArgumentParser()
ap.add_argument("--out", default="closed_loop.png", help="the figure (PNG)")
args, _ = ap.parse_known_args()

DATA = pathlib.Path(__file__).resolve().parents[2] / "datasets" if "__file__" in globals() else pathlib.Path("datasets")
print("robokrige", rk.__version__, "| wheel build:", rk.build_target_cpu())

# %% [markdown]
# ## 1. Fit
# One universal-Kriging model per axis over `[θ, λ]`: the command line's
# defaults (a nugget for the tracker noise, each axis's correlation family
# chosen by CV, BFGS). 300 laser-tracker poses of a simulated COMAU NJ 220.

# %%
lhs = rk.read_campaign(DATA / "comau_lhs.csv")
model = rk.ErrorModel(robot="comau-nj220").fit(lhs)
print(model, "families", model.families_)

# %% [markdown]
# ## 2. Honest accuracy: 10-fold CV, refitted in every fold

# %%
cv = rk.cross_validate(rk.ErrorModel(), lhs, folds=10, progress=True)
s = cv["summary"]
print(f"CV mean 3D error {s['mean_3d_mm']:.4f} mm; RMSE x/y/z", " / ".join(f"{v:.4f}" for v in s["rms_mm"]))

# %% [markdown]
# ## 3. Pre-compensate the Ø100 mm circle for the nominal controller
# and run the commands on the simulated robot (its truth file) to measure
# the errors before and after.

# %%
comp = rk.compensate(
    model,
    "comau-nj220",
    DATA / "comau_circle.csv",
    iterative=True,
    truth=DATA / "comau_circle.truth.json",
)
ev = comp["evaluation"]["summary"]
print(
    f"compensated: {len(comp['history'])} iterations, {comp['stop']}; measured mean / max 3D error "
    f"{ev['before']['mean_abs_mm']:.3f} / {ev['before']['max_abs_mm']:.3f} mm -> "
    f"{ev['after']['mean_abs_mm']:.3f} / {ev['after']['max_abs_mm']:.3f} mm"
)

# %% [markdown]
# ## 4. What is the model missing?
# A campaign with a laser-tracker bump in it: `diagnose` traces the CV
# residual to a step in the measurement order, adds it and re-validates.

# %%
bumped = rk.read_campaign(DATA / "comau_tracker_step.csv")
effects, improved, report = rk.diagnose(bumped, progress=True)
for _, e in effects[effects["accepted"]].iterrows():
    print(f"added {e['label']} (q {e['q_value']:.4f})")
print(f"CV RMSE {report['before']['pooled_rmse_mm']:.4f} -> {report['after']['pooled_rmse_mm']:.4f} mm")
effects[["round", "label", "score", "p_value", "q_value", "significant", "accepted"]].head(6)

# %% [markdown]
# ## The figure

# %%
fig, ax = plt.subplots(2, 2, figsize=(11, 8))
r3 = np.linalg.norm(cv["residuals"], axis=1)
ax[0, 0].hist(r3, bins=30, color="tab:blue")
ax[0, 0].set(title="10-fold CV, out-of-fold 3D error", xlabel="mm", ylabel="poses")

before, after = (np.linalg.norm(comp["evaluation"][k], axis=1) for k in ("before", "after"))
ax[0, 1].plot(before, label="nominal commands")
ax[0, 1].plot(after, label="compensated (EJS)")
ax[0, 1].set(title="circle on the simulated robot", xlabel="trajectory point", ylabel="measured 3D error (mm)")
ax[0, 1].legend()

rows = np.arange(len(bumped))
ax[1, 0].plot(rows, np.linalg.norm(report["before_residuals"], axis=1), ".", ms=3, label="before")
ax[1, 0].plot(rows, np.linalg.norm(report["after_residuals"], axis=1), ".", ms=3, label="after adding the step")
ax[1, 0].set(title="diagnose: CV residual in measurement order", xlabel="row", ylabel="3D residual (mm)")
ax[1, 0].legend()

verify = rk.read_campaign(DATA / "comau_verify.csv")
mean, std = model.predict(verify, return_std=True)
measured = verify[["ex", "ey", "ez"]].to_numpy()
for a, name in enumerate(("ex", "ey", "ez")):
    ax[1, 1].errorbar(measured[:, a], mean[:, a], yerr=2 * std[:, a], fmt="o", ms=3, label=name)
lim = [measured.min() - 0.05, measured.max() + 0.05]
ax[1, 1].plot(lim, lim, "k:", lw=1)
ax[1, 1].set(title="verification poses: predicted (±2σ) vs measured", xlabel="measured (mm)", ylabel="predicted (mm)")
ax[1, 1].legend()
fig.tight_layout()
fig.savefig(args.out, dpi=110)
print("figure:", args.out)
