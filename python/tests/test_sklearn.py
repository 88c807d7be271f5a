"""ErrorModel as a scikit-learn regressor: check_estimator, cross_val_score,
GridSearchCV, Pipeline, clone, R², and the column layouts of fit(X, y)."""

import json
import os
import pickle
import subprocess
import sys
import textwrap
import warnings

import numpy as np
import pytest

import robokrige as rk

from conftest import need


@pytest.fixture(scope="module")
def sk():
    return need("sklearn")


@pytest.fixture(scope="module")
def comau(datasets):
    """The shipped COMAU campaign as the issue builds it: X = [q, dirs], Y = errors."""
    t = rk.read_campaign(datasets / "comau_lhs.csv", as_frame=False)
    q = np.column_stack([t[f"q{j}"] for j in range(1, 7)])
    d = np.column_stack([t[f"dir{j}"] for j in range(1, 7)])
    e = np.column_stack([t[a] for a in ("ex", "ey", "ez")])
    return q, d, e


def test_the_issues_three_lines_run_on_the_comau_campaign(sk, comau):
    from sklearn.model_selection import GridSearchCV, cross_val_score
    from sklearn.utils.estimator_checks import check_estimator

    q, dirs, errors = comau
    X = np.hstack([q, dirs])  # n × 12
    Y = errors  # n × 3
    scores = cross_val_score(rk.ErrorModel(), X, Y, cv=3, scoring="neg_mean_squared_error")
    # the MSE per axis is about the simulated tracker noise (0.022 mm)², far below the errors' spread
    assert scores.shape == (3,) and np.all(-scores < 1e-3) and np.all(-scores > 1e-5), scores
    assert np.all(-scores < 0.05 * np.var(Y))
    search = GridSearchCV(rk.ErrorModel(), {"nugget": [True, False]}, cv=3).fit(X, Y)
    assert search.best_params_ == {"nugget": True}  # tracker data is noisy
    assert search.best_estimator_.n_features_in_ == 12 and search.best_score_ > 0.95
    with warnings.catch_warnings():
        # its random X has no direction columns: each fit says so
        warnings.simplefilter("ignore", rk.RobokrigeWarning)
        check_estimator(rk.ErrorModel())


def test_check_estimator_runs_every_check_and_every_one_passes(sk):
    """Every check of check_estimator, none skipped: SCIPY_ARRAY_API is set in
    a fresh interpreter so that the array-API check runs too; no expected
    failure is declared."""
    code = textwrap.dedent(
        """
        import json, warnings
        import robokrige as rk
        from sklearn.utils.estimator_checks import check_estimator
        results = []
        def record(estimator, check_name, exception, status, expected_to_fail, expected_to_fail_reason):
            results.append([check_name, status, repr(exception)])
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")
            check_estimator(rk.ErrorModel(), on_fail=None, callback=record)
        print(json.dumps(results))
        """
    )
    env = dict(os.environ, SCIPY_ARRAY_API="1")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, env=env, check=True)
    results = json.loads(out.stdout.strip().splitlines()[-1])
    assert len(results) >= 50
    bad = [r for r in results if r[1] != "passed"]
    assert not bad, bad
    names = {r[0] for r in results}
    # the regressor's checks ran: multi-output, 1-D y, NaN refused, sparse refused
    for check in ("check_regressor_multioutput", "check_regressors_train", "check_supervised_y_2d",
                  "check_estimators_nan_inf", "check_estimator_sparse_array", "check_array_api_input",
                  "check_methods_subset_invariance", "check_fit2d_1sample"):
        assert check in names, check


def test_gridsearch_over_corr_and_nugget_agrees_with_auto(sk, comau):
    """GridSearchCV over the correlation family and the nugget (5 folds, R²)
    picks what the library's corr="auto" picks on every axis of the COMAU
    campaign: the Gaussian, with a nugget. (With the issue's 3 unshuffled
    folds it picks Matérn 5/2 by 3e-5 in R²: the two are tied there; see
    python/README.md.)"""
    from sklearn.model_selection import GridSearchCV

    q, d, e = comau
    X = np.hstack([q, d])
    families = ["gaussian", "matern52", "matern32", "exponential"]
    search = GridSearchCV(rk.ErrorModel(), {"corr": families, "nugget": [True, False]}, cv=5).fit(X, e)
    assert search.best_params_ == {"corr": "gaussian", "nugget": True}, search.cv_results_["mean_test_score"]
    scores = dict(zip(map(str, search.cv_results_["params"]), search.cv_results_["mean_test_score"]))
    # the rougher families are clearly worse here: the simulated error is smooth
    assert scores[str({"corr": "exponential", "nugget": True})] < scores[str({"corr": "gaussian", "nugget": True})] - 0.005
    auto = rk.ErrorModel().fit(X, e)
    assert auto.families_ == ["gaussian"] * 3


def test_pipeline_scaling_the_covariates_changes_nothing(sk, datasets):
    """A StandardScaler on the covariate columns (a ColumnTransformer with
    pandas output, so that the columns keep their names and the estimator
    reads them by name): the model z-scores its inputs itself, so the
    predictions equal those without the scaler. The joints and directions
    are passed through untouched: scaled angles would no longer be degrees
    (periodic joints, the robot's kinematics) and scaled λ no longer ±1."""
    pd = need("pandas")
    from sklearn.compose import ColumnTransformer
    from sklearn.model_selection import cross_val_score
    from sklearn.pipeline import make_pipeline
    from sklearn.preprocessing import StandardScaler

    df = rk.read_campaign(datasets / "comau_temperature.csv")
    X = df.drop(columns=["id", "ex", "ey", "ez", "x", "y", "z"])
    Y = df[["ex", "ey", "ez"]]
    covariates = ["time_s", "temp_c"]
    scale = ColumnTransformer(
        [("covariates", StandardScaler(), covariates)], remainder="passthrough", verbose_feature_names_out=False
    ).set_output(transform="pandas")
    pipe = make_pipeline(scale, rk.ErrorModel()).fit(X, Y)
    plain = rk.ErrorModel().fit(X, Y)
    assert isinstance(scale.transform(X), pd.DataFrame)
    assert pipe[-1].extras_ == covariates == plain.extras_
    assert np.max(np.abs(pipe.predict(X) - plain.predict(X))) < 1e-9
    # the temperature is an input: the model without it explains much less
    joints = X.drop(columns=covariates)
    with_cov = cross_val_score(pipe, X, Y, cv=3).mean()
    without = cross_val_score(rk.ErrorModel(), joints, Y, cv=3).mean()
    assert with_cov > without + 0.05, (with_cov, without)


def test_clone_keeps_the_parameters_unmodified(sk):
    from sklearn.base import clone

    m = rk.ErrorModel(space="js", corr="gaussian", covariates=["temp_c"], n_joints=6, dirs="columns")
    c = clone(m)
    assert c.get_params() == m.get_params() and c is not m
    # parameters are stored as given (scikit-learn's rule): checked by fit
    odd = rk.ErrorModel(dirs="sideways", seed=-3)
    assert clone(odd).get_params()["dirs"] == "sideways"
    with pytest.raises(rk.RobokrigeError, match="dirs 'sideways'"):
        odd.fit(np.zeros((5, 2)), np.zeros((5, 3)))
    fitted = rk.ErrorModel(corr="gaussian", dirs="none").fit(np.random.default_rng(0).uniform(-30, 30, (20, 2)), np.zeros((20, 3)))
    assert not hasattr(clone(fitted), "models_")


def test_unfitted_raises_scikit_learns_not_fitted_error(sk):
    from sklearn.exceptions import NotFittedError
    from sklearn.utils.validation import check_is_fitted

    m = rk.ErrorModel()
    with pytest.raises(NotFittedError):
        check_is_fitted(m)
    with pytest.raises(NotFittedError, match="not fitted yet"):
        m.predict(np.zeros((3, 12)))
    assert issubclass(rk.NotFittedError, (rk.RobokrigeError, NotFittedError, AttributeError))
    assert not hasattr(m, "space_")


def test_score_is_scikit_learns_r2(sk, comau):
    from sklearn.metrics import r2_score

    rng = np.random.default_rng(1)
    y = rng.normal(size=(30, 3))
    p = y + rng.normal(scale=0.3, size=(30, 3))
    w = rng.uniform(0.5, 2.0, 30)
    assert rk.r2_score(y, p) == pytest.approx(r2_score(y, p), abs=1e-14)
    assert rk.r2_score(y, p, w) == pytest.approx(r2_score(y, p, sample_weight=w), abs=1e-14)
    assert rk.r2_score(y[:, 0], p[:, 0]) == pytest.approx(r2_score(y[:, 0], p[:, 0]), abs=1e-14)
    const = np.ones((10, 2))
    assert rk.r2_score(const, const) == r2_score(const, const) == 1.0
    assert rk.r2_score(const, const + 0.1) == r2_score(const, const + 0.1) == 0.0
    q, d, e = comau
    X = np.hstack([q, d])
    m = rk.ErrorModel(corr="gaussian").fit(X[:200], e[:200])
    assert m.score(X[200:], e[200:]) == pytest.approx(r2_score(e[200:], m.predict(X[200:])), abs=1e-14)
    # the mean 3D error left, what score meant before
    assert rk.mean_3d_error(m, q[200:], d[200:], e[200:]) == pytest.approx(
        np.mean(np.linalg.norm(e[200:] - m.predict(X[200:]), axis=1)), abs=1e-14
    )


def test_fit_xy_gives_the_campaign_forms_model_file(comau, datasets):
    """fit(X, y) with X = [q, dirs] is the library's fit on that campaign:
    the same model file as fit(q, dirs, errors) and as the CSV."""
    q, d, e = comau
    via_xy = rk.ErrorModel(corr="gaussian").fit(np.hstack([q, d]), e)
    via_campaign = rk.ErrorModel(corr="gaussian").fit(q, d, e)
    assert via_xy.to_json() == via_campaign.to_json()
    assert via_xy.n_features_in_ == via_campaign.n_features_in_ == 12
    # the campaign form predicts from X = [q, dirs] too, and from q and dirs
    assert np.array_equal(via_campaign.predict(np.hstack([q, d])[:5]), via_xy.predict(q[:5], d[:5]))


def test_layouts_of_x(comau):
    q, d, e = comau
    q, d, e = q[:80], d[:80], e[:80]
    opts = dict(corr="gaussian", starts=2)
    # auto: ±1 columns after the joints are directions, else none (joint space, with a warning)
    m = rk.ErrorModel(**opts).fit(np.hstack([q, d]), e)
    assert m._layout.dirs == "columns" and m.space_ == "ejs"
    with pytest.warns(rk.RobokrigeWarning, match="no direction columns"):
        js = rk.ErrorModel(**opts).fit(q, e)
    assert js.space_ == "js" and js.n_joints_ == 6 and js.n_features_in_ == 6
    with warnings.catch_warnings():
        warnings.simplefilter("error", rk.RobokrigeWarning)
        rk.ErrorModel(dirs="none", **opts).fit(q, e)  # asked for: no warning
    # derive: from the row order of X, as the campaign form without dirs
    derived = rk.ErrorModel(dirs="derive", **opts).fit(q, e)
    assert derived.space_ == "ejs"
    assert derived.to_json() == rk.ErrorModel(**opts).fit(q, errors=e).to_json()
    assert np.array_equal(rk.derive_directions(q), rk.as_data(q).dirs)
    # covariates: the last columns, named; they enter the model
    temp = np.linspace(20, 23, 80)
    c = rk.ErrorModel(covariates=["temp"], **opts).fit(np.column_stack([q, d, temp]), e)
    assert c.extras_ == ["temp"] and c.n_features_in_ == 13 and c.n_joints_ == 6
    assert c.predict(np.column_stack([q, d, temp])[:4]).shape == (4, 3)
    # n_joints fixes the split
    assert rk.ErrorModel(n_joints=6, **opts).fit(np.hstack([q, d]), e)._layout.dirs == "columns"
    with pytest.raises(rk.RobokrigeError, match="X has 12 columns: 5 joints"):
        rk.ErrorModel(n_joints=5, dirs="columns", **opts).fit(np.hstack([q, d]), e)
    with pytest.raises(rk.RobokrigeError, match="direction must be \\+1 or -1"):
        rk.ErrorModel(dirs="columns", **opts).fit(np.hstack([q, q]), e)
    with pytest.raises(rk.RobokrigeError, match="X has 5 features, but ErrorModel is expecting 12"):
        m.predict(q[:, :5])
    with pytest.raises(rk.RobokrigeError, match="models the directions"):
        rk.ErrorModel(method="ejs-hj").fit(q, e)


def test_dataframe_columns_are_read_by_name(comau):
    pd = need("pandas")
    q, d, e = comau
    q, d, e = q[:80], d[:80], e[:80]
    cols = {f"q{j + 1}": q[:, j] for j in range(6)} | {f"dir{j + 1}": d[:, j] for j in range(6)}
    cols["temp"] = np.linspace(20, 23, 80)
    X = pd.DataFrame(cols)
    shuffled = X[["temp"] + [f"dir{j}" for j in range(6, 0, -1)] + [f"q{j}" for j in range(1, 7)]]
    a = rk.ErrorModel(corr="gaussian", starts=2).fit(X, e)
    b = rk.ErrorModel(corr="gaussian", starts=2).fit(shuffled, e)
    assert a.to_json() == b.to_json() and a.extras_ == ["temp"]
    assert list(b.feature_names_in_) == list(shuffled.columns)
    assert np.array_equal(a.predict(shuffled), b.predict(X))
    # an array in the fitted DataFrame's column order
    assert np.array_equal(b.predict(shuffled.to_numpy()), b.predict(shuffled))
    with pytest.raises(rk.RobokrigeError, match="neither joints"):
        rk.ErrorModel(covariates=[]).fit(X, e)
    with pytest.raises(rk.RobokrigeError, match="reserves"):
        rk.ErrorModel().fit(X.assign(x=1.0), e)


def test_any_number_of_outputs(comau):
    """1-D y and n × k: predictions in y's shape; the library fits three at a
    time (the last padded), and a model file holds exactly three."""
    q, d, e = comau
    X = np.hstack([q, d])[:60]
    opts = dict(corr="gaussian", starts=2)
    one = rk.ErrorModel(**opts).fit(X, e[:60, 2])
    assert one.predict(X[:7]).shape == (7,) and one.n_outputs_ == 1
    three = rk.ErrorModel(**opts).fit(X, e[:60])
    # the same library fit of that output (the other two padded with zeros)
    assert np.allclose(one.predict(X[:7]), three.predict(X[:7])[:, 2], atol=1e-12, rtol=0)
    col = rk.ErrorModel(**opts).fit(X, e[:60, 2:3])
    assert col.predict(X[:7]).shape == (7, 1)
    five = rk.ErrorModel(**opts).fit(X, np.hstack([e[:60], e[:60, :2] * 2]))
    mean, std = five.predict(X[:7], return_std=True)
    assert mean.shape == std.shape == (7, 5) and len(five.models_) == 2
    assert np.allclose(mean[:, 3:], 2 * three.predict(X[:7])[:, :2], atol=1e-9)
    again = pickle.loads(pickle.dumps(five))
    assert np.array_equal(again.predict(X[:7]), mean)
    with pytest.raises(rk.RobokrigeError, match="fitted on 5 output"):
        five.save("never.json")
    with pytest.raises(rk.RobokrigeError, match="three outputs"):
        rk.ErrorModel(robot="comau-nj220", **opts).fit(X, e[:60, 0])
