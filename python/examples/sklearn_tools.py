# %% [markdown]
# # robokrige with scikit-learn's tools, and a planned campaign
#
# `ErrorModel` is a scikit-learn regressor: X holds the joints, their
# directions λ and any covariates; y the TCP error (ex, ey, ez). This runs
# cross-validation, a grid search over the correlation family and the
# nugget, a pipeline that scales the covariates, and then plans which poses
# to measure next. A notebook in the percent format that also runs as a
# script (about a minute):
#
#     python python/examples/sklearn_tools.py
#
# It needs pandas and scikit-learn (`pip install pandas scikit-learn`).
# Ctrl-C stops any of the long calls within a second.

# %%
import pathlib
from typing import List

import numpy as np
from sklearn.compose import ColumnTransformer
from sklearn.model_selection import GridSearchCV, cross_val_score
from sklearn.pipeline import make_pipeline
from sklearn.preprocessing import StandardScaler

import robokrige as rk

HERE = pathlib.Path(__file__).resolve() if "__file__" in globals() else pathlib.Path("python/examples/x")
DATA = HERE.parents[2] / "datasets"

# %% [markdown]
# ## 1. X and y from the shipped COMAU campaign (300 poses)
# The directions are columns of X. A campaign without them gets them from
# its visiting order once, before any split (`rk.derive_directions(q)`): a
# CV splitter picks rows, and the order of a fold's rows is not the robot's.

# %%
df = rk.read_campaign(DATA / "comau_lhs.csv")
joints: List[str] = [f"q{j}" for j in range(1, 7)]
directions: List[str] = [f"dir{j}" for j in range(1, 7)]
X = df[joints + directions].to_numpy()
Y = df[["ex", "ey", "ez"]].to_numpy()
same = np.mean(rk.derive_directions(X[:, :6]) == X[:, 6:])
print(f"X {X.shape}, y {Y.shape}; λ derived from the visiting order matches the dir columns on {same:.0%} of entries")

# %% [markdown]
# ## 2. Cross-validation and a grid search (R², scikit-learn's score)

# %%
scores = cross_val_score(rk.ErrorModel(), X, Y, cv=5)
print(f"5-fold R²: {scores.mean():.4f} (± {scores.std():.4f})")
search = GridSearchCV(
    rk.ErrorModel(), {"corr": ["gaussian", "matern52", "matern32", "exponential"], "nugget": [True, False]}, cv=5
).fit(X, Y)
print("grid search:", search.best_params_, f"R² {search.best_score_:.4f}")
auto = rk.ErrorModel().fit(X, Y)
print("corr='auto' chose, per axis:", auto.families_)

# %% [markdown]
# ## 3. A pipeline: covariates scaled, joints and directions passed through
# A scaler must not touch the joints (degrees: periodic joints, the robot's
# kinematics) nor λ (±1). The columns keep their names (pandas output), and
# the estimator reads them by name. The covariates enter the model as
# inputs; it z-scores its inputs itself, so the scaler changes nothing here.

# %%
warm = rk.read_campaign(DATA / "comau_temperature.csv")
Xt = warm[joints + directions + ["time_s", "temp_c"]]
Yt = warm[["ex", "ey", "ez"]]
scale = ColumnTransformer(
    [("covariates", StandardScaler(), ["time_s", "temp_c"])], remainder="passthrough", verbose_feature_names_out=False
).set_output(transform="pandas")
pipe = make_pipeline(scale, rk.ErrorModel())
print(f"with the temperature: 5-fold R² {cross_val_score(pipe, Xt, Yt, cv=5).mean():.4f}")
without = cross_val_score(rk.ErrorModel(), Xt[joints + directions], Yt, cv=5).mean()
print(f"without it:           5-fold R² {without:.4f}")

# %% [markdown]
# ## 4. Which poses to measure next
# Continue the campaign by 50 poses that lower the model's integrated
# prediction variance the most, in an order that realises their planned
# directions, and say how many more a held-out error of 0.037 mm needs.

# %%
plan = rk.plan("comau-nj220", 50, campaign=df, target_mm=0.037)
print(plan.summary["text"], end="")
print(f"{int(plan.measure.sum())} poses to measure, {int((~plan.measure).sum())} via-points; first pose {plan.q[0]}")
