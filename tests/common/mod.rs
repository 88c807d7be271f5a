//! Shared by the integration tests.

use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A folder for a test's files under the system's temporary folder,
/// removed with everything in it when dropped. Kept in a `thread_local!`
/// it lives as long as the test: the test harness runs each test on a
/// thread of its own and drops its thread-locals when the test ends, pass
/// or fail.
#[allow(dead_code)] // not every test binary that shares this module uses it
pub struct Scratch(PathBuf);

#[allow(dead_code)]
impl Scratch {
    /// A new empty folder `{prefix}-{process id}-{n}`, n counting the
    /// folders this test binary made.
    pub fn new(prefix: &str) -> Self {
        static N: AtomicUsize = AtomicUsize::new(0);
        let n = N.fetch_add(1, Ordering::Relaxed);
        let dir = std::env::temp_dir().join(format!("{prefix}-{}-{n}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        Scratch(dir)
    }

    /// The folder.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.0).ok();
    }
}

/// Run the `robokrige` binary: (exit code, stdout, stderr).
#[allow(dead_code)] // not every test binary that shares this module uses it
pub fn rk(args: &[&str]) -> (i32, String, String) {
    let out = Command::new(env!("CARGO_BIN_EXE_robokrige"))
        .args(args)
        .output()
        .unwrap();
    (
        out.status.code().unwrap_or(-1),
        String::from_utf8_lossy(&out.stdout).into(),
        String::from_utf8_lossy(&out.stderr).into(),
    )
}

/// Row `i` of a smooth synthetic six-joint campaign (q1..q6 in degrees,
/// then ex,ey,ez in mm), for the bad-input catalogues.
#[allow(dead_code)] // not every test binary that shares this module uses it
pub fn synthetic_row(i: usize) -> String {
    let t = i as f64;
    let q: Vec<String> = (0..6)
        .map(|j| format!("{:.4}", 20.0 * ((t * 0.37 + j as f64) * 1.3).sin()))
        .collect();
    format!(
        "{},{:.4},{:.4},{:.4}",
        q.join(","),
        0.1 * (t * 0.3).sin(),
        0.1 * (t * 0.2).cos(),
        0.05 * t / 24.0
    )
}

/// The first `rows` rows of the shipped `datasets/comau_lhs.csv`.
#[allow(dead_code)] // not every test binary that shares this module uses it
pub fn comau_lhs(rows: usize) -> robokrige::dataset::Dataset {
    let d = robokrige::dataset::read_csv(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/datasets/comau_lhs.csv"
    )))
    .unwrap();
    d.select(&(0..rows).collect::<Vec<_>>())
}

/// PCC + PCA with the papers' constants (the rows of `robot`'s Jacobian
/// among the candidates when given), and its per-axis reports.
#[allow(dead_code)] // not every test binary that shares this module uses it
pub fn fit_pcc_pca(
    data: &robokrige::dataset::Dataset,
    opts: &robokrige::kriging::KrigingOptions,
    robot: Option<&robokrige::kinematics::Robot>,
) -> (
    robokrige::model::ErrorModel,
    Vec<robokrige::selection::PccPcaReport>,
) {
    let model = robokrige::params::ErrorModelParams::new()
        .kriging(opts.clone())
        .trend(robokrige::methods::Method::EjsPca.trend(robot))
        .check()
        .unwrap()
        .fit(data)
        .unwrap();
    let Some(robokrige::selection::Selection::PccPca { outputs }) = model.selection() else {
        panic!("no PCC + PCA report");
    };
    let reports = outputs.clone();
    (model, reports)
}

/// One output solved at given ξ and ν (no search), the first `theta.len()`
/// input columns correlation inputs.
#[allow(dead_code)]
pub fn fit_at(
    x: &[Vec<f64>],
    y: &[f64],
    trend: &robokrige::kriging::Trend,
    theta: &[f64],
    nugget: f64,
    min_jitter: Option<f64>,
) -> robokrige::Result<robokrige::kriging::KrigingModel> {
    use robokrige::kriging::{Hyperparameters, KrigingOptions, KrigingParams, Tuning};
    KrigingParams::new(trend.clone())
        .options(KrigingOptions::default().min_jitter(min_jitter))
        .tuning(Tuning::Fixed(Hyperparameters::new(theta.to_vec(), nugget)))
        .correlation_inputs(theta.len())
        .check()?
        .fit(x, y)
        .map(|(model, _)| model)
}

/// One output with its hyperparameters searched with `opts`.
#[allow(dead_code)]
pub fn fit_searched(
    x: &[Vec<f64>],
    y: &[f64],
    trend: &robokrige::kriging::Trend,
    opts: &robokrige::kriging::KrigingOptions,
) -> robokrige::Result<(
    robokrige::kriging::KrigingModel,
    robokrige::kriging::FitReport,
)> {
    robokrige::kriging::KrigingParams::new(trend.clone())
        .options(opts.clone())
        .check()?
        .fit(x, y)
}

/// `diagnose` options fast enough for a test: Hooke–Jeeves with 2 starts
/// and 300 evaluations, a nugget, 5 folds, 999 permutations, at most 2
/// effects.
#[allow(dead_code)]
pub fn quick_diagnose() -> robokrige::diagnose::DiagnoseOptions {
    use robokrige::kriging::{KrigingOptions, OptimizerKind};
    robokrige::diagnose::DiagnoseOptions::default()
        .kriging(
            KrigingOptions::default()
                .optimizer(OptimizerKind::HookeJeeves)
                .nugget(true)
                .max_evals(300)
                .starts(2),
        )
        .folds(5)
        .permutations(999)
        .max_effects(2)
}
