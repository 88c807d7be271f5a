//! The hyperparameter search: ln ψ (seed 003 eq 14) and its gradient as
//! objectives in log10 (ξ, ν), sized to the campaign (`FitPlan`): a
//! successive-halving BFGS multistart on a row subset, converged on all rows,
//! or the papers' GPS / Hooke–Jeeves.

use super::{KrigingOptions, KrigingProblem, OptimizerKind, TrainingInputs, Workspace};
use crate::cancel::Cancel;
use crate::optim::{self, Bounds, GpsOptions, HjOptions, OptimResult};
use rayon::prelude::*;

/// Maps an optimiser point (log10 ξ, and log10 ν with a nugget) to (ξ, ν).
pub(super) type Unpack<'a> = dyn Fn(&[f64]) -> (Vec<f64>, f64) + Sync + 'a;

/// `z ↦ ln ψ(unpack(z))` with its own workspace; +∞ where R cannot be
/// factorised or the likelihood is degenerate, and at once, without an
/// evaluation, once `cancel` is cancelled (every minimiser stops within a
/// few such points; the fit then returns [`crate::Error::Interrupted`]).
pub(super) fn ln_psi_objective<'a>(
    problem: &'a KrigingProblem,
    unpack: &'a Unpack<'_>,
    cancel: &'a Cancel,
) -> impl FnMut(&[f64]) -> f64 + 'a {
    let mut ws = Workspace::new(problem.m(), problem.f.ncols());
    move |z: &[f64]| {
        if cancel.is_cancelled() {
            return f64::INFINITY;
        }
        let (theta, nugget) = unpack(z);
        problem
            .psi(&theta, nugget, &mut ws)
            .map_or(f64::INFINITY, |v| v.ln_psi)
    }
}

/// `z ↦ (ln ψ, ∇ ln ψ)` with its own workspace; +∞ where R cannot be
/// factorised or the likelihood is degenerate, or once `cancel` is
/// cancelled.
fn ln_psi_grad_objective<'a>(
    problem: &'a KrigingProblem,
    unpack: &'a Unpack<'_>,
    cancel: &'a Cancel,
) -> impl FnMut(&[f64], &mut [f64]) -> f64 + 'a {
    let mut ws = Workspace::new(problem.m(), problem.f.ncols());
    move |z: &[f64], g: &mut [f64]| ln_psi_grad(problem, unpack, cancel, &mut ws, z, g)
}

/// `ln ψ(z)` with its gradient in `g`, in `ws`; +∞ where R cannot be
/// factorised or the likelihood is degenerate, or (without an evaluation)
/// once `cancel` is cancelled.
fn ln_psi_grad(
    problem: &KrigingProblem,
    unpack: &Unpack<'_>,
    cancel: &Cancel,
    ws: &mut Workspace,
    z: &[f64],
    g: &mut [f64],
) -> f64 {
    if cancel.is_cancelled() {
        return f64::INFINITY;
    }
    let (theta, nugget) = unpack(z);
    problem
        .psi_grad(&theta, nugget, ws, g)
        .map_or(f64::INFINITY, |v| v.ln_psi)
}

/// The workspaces of one multistart, passed from run to run and stage to
/// stage: as many as ran at once (at most the threads). A fresh m × m
/// workspace per run and stage (every 2 iterations in the final stage) went
/// through the allocator each time, and whether it came back as memory
/// already mapped depended on the allocator's state: `likelihood_core 300`
/// took 37 000 to 614 000 page faults from one run to the next, and its
/// mean 3-output fit 0.29 to 0.36 s with it.
struct WorkspacePool {
    rows: usize,
    terms: usize,
    free: std::sync::Mutex<Vec<Workspace>>,
}

impl WorkspacePool {
    fn new(problem: &KrigingProblem) -> Self {
        WorkspacePool {
            rows: problem.m(),
            terms: problem.f.ncols(),
            free: std::sync::Mutex::new(Vec::new()),
        }
    }

    /// A workspace as a new one would start (no jitter rung remembered).
    fn take(&self) -> Workspace {
        let pooled = self.free.lock().map(|mut v| v.pop()).unwrap_or(None);
        match pooled {
            Some(mut ws) => {
                ws.forget_rung();
                ws
            }
            None => Workspace::new(self.rows, self.terms),
        }
    }

    fn put(&self, ws: Workspace) {
        if let Ok(mut v) = self.free.lock() {
            v.push(ws);
        }
    }
}

/// Box of the BFGS starting points in log10 ξ: correlation lengths from
/// ~0.3 to ~30 input standard deviations (the UR10 campaigns' best basins
/// have ξ of 4–13 on q1–q3). A start at large ξ sits on a plateau
/// (R ≈ I, the gradient vanishes) and a start at tiny ξ on the jitter
/// ladder; the search itself still ranges over the whole box.
const START_LOG10_THETA: (f64, f64) = (-3.0, 1.0);
/// The same for log10 ν.
const START_LOG10_NUGGET: (f64, f64) = (-5.0, -1.0);
/// BFGS iterations of the screening stage. 4 was tried (2026-11-25):
/// `likelihood_core 300` took 10 % fewer evaluations with all 36 ln ψ the
/// same, and UR10 series B and C the same ln ψ, but the SMT reference's
/// js-quadratic ez ended in a worse basin (ψ 0.30262 against 0.30196).
const SCREEN_ITER: usize = 8;
/// Starts that run to convergence after the successive halving (with the
/// default 8 starts: the better half after [`SCREEN_ITER`] iterations). Two
/// finalists missed the GPS basin on the UR10 kinematic-trend fits (ey
/// ln ψ −1.76 against −1.96).
const FINALISTS: usize = 4;

/// Campaigns up to this many rows search ξ on all of them.
pub const SEARCH_ROWS: usize = 1000;
/// Campaigns up to this many rows converge ξ on all of them; larger ones
/// converge on a subset of this size, then solve once on all rows.
pub const REFINE_ROWS: usize = 3000;

/// How a fit of m rows will run and what it will hold in memory, known
/// before anything is allocated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FitPlan {
    /// Training rows.
    pub rows: usize,
    /// Rows of the multistart stage (BFGS) or of the whole search (GPS, HJ).
    pub search_rows: usize,
    /// Rows ξ is converged on.
    pub refine_rows: usize,
    /// Outputs fitted one after another (each factorisation then uses all
    /// threads) instead of in parallel.
    pub sequential_outputs: bool,
    /// Estimated peak memory, bytes.
    pub bytes: u64,
}

impl FitPlan {
    /// The plan for `outputs` outputs of `rows` rows with `opts`' optimiser
    /// and `converge_rows`, on
    /// `threads` threads: the largest of the search's workspaces (three
    /// m × m matrices per running start with the gradient, and below
    /// [`super::problem::PAR_MIN_ROWS`] rows a quarter more; the
    /// multistart's are pooled per output, so up to `threads` per output
    /// fitted at once), the final
    /// solve's factor per output running at once, plus the factors a fitted
    /// model keeps (up to m = 4096).
    pub fn new(rows: usize, outputs: usize, opts: &KrigingOptions, threads: usize) -> Self {
        let sq = |m: usize| crate::memory::square_bytes(m);
        let (search_rows, refine_rows, per_ws) = match opts.optimizer {
            OptimizerKind::Bfgs => {
                let refine = rows.min(opts.converge_rows);
                (refine.min(SEARCH_ROWS), refine, 3)
            }
            _ => (rows, rows, 2),
        };
        let sequential_outputs = rows > REFINE_ROWS;
        let running = threads.max(1) as u64;
        let gradient = opts.optimizer == OptimizerKind::Bfgs;
        // with the gradient, a sequential workspace holds the scratch of the
        // blocked inverse too
        let ws = |m: usize| {
            per_ws * sq(m)
                + if gradient {
                    sq(super::dense::scratch_order(m))
                } else {
                    0
                }
        };
        // the multistart's workspaces are pooled per output (WorkspacePool):
        // up to one per thread for every output fitted at once
        let pooled = if gradient && !sequential_outputs {
            running * outputs.max(1) as u64
        } else {
            running
        };
        let search = (pooled * ws(search_rows)).max(running * ws(refine_rows));
        let at_once = if sequential_outputs {
            1
        } else {
            outputs.min(threads.max(1)) as u64
        };
        let solve = at_once * sq(rows);
        let kept = if rows <= super::model::KEEP_FACTOR_MAX_M {
            outputs as u64 * sq(rows)
        } else {
            0
        };
        FitPlan {
            rows,
            search_rows,
            refine_rows,
            sequential_outputs,
            bytes: search.max(solve) + kept,
        }
    }

    /// The most rows whose plan fits in `bytes`.
    pub fn max_rows(bytes: u64, outputs: usize, opts: &KrigingOptions, threads: usize) -> usize {
        let (mut lo, mut hi) = (1usize, 1usize << 20);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if Self::new(mid, outputs, opts, threads).bytes <= bytes {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        lo
    }
}

impl std::fmt::Display for FitPlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} rows, about {} of memory",
            self.rows,
            crate::memory::human(self.bytes)
        )?;
        if self.refine_rows < self.rows {
            write!(
                f,
                "; ξ searched on {} rows and converged on {}, then one solve on all {} rows",
                self.search_rows, self.refine_rows, self.rows
            )?;
        } else if self.search_rows < self.rows {
            write!(
                f,
                "; starts screened on {} rows, ξ converged on all rows",
                self.search_rows
            )?;
        }
        Ok(())
    }
}

/// The default search, sized to the campaign:
/// - m ≤ [`SEARCH_ROWS`]: [`multistart_bfgs`] on all rows;
/// - m ≤ `converge_rows` ([`REFINE_ROWS`] by default): the multistart on a
///   seeded random subset of
///   [`SEARCH_ROWS`] rows finds the basin, then BFGS converges on **all**
///   rows from there: the result is a stationary point of the full
///   likelihood, at a few dozen full evaluations instead of hundreds;
/// - larger: the same with the convergence on a subset of `converge_rows`
///   rows ([`converge_subset`]); the fit then solves once on all rows at that ξ.
fn optimise_bfgs(
    problem: &KrigingProblem,
    bounds: &Bounds,
    unpack: &Unpack<'_>,
    opts: &KrigingOptions,
) -> Search {
    let m = problem.m();
    let search_rows = SEARCH_ROWS.min(opts.converge_rows);
    if m <= search_rows {
        let (best, starts, hinv) = multistart_bfgs(problem, bounds, unpack, opts);
        return Search {
            best,
            starts,
            rows: m,
            inverse_hessian: Some(hinv),
        };
    }
    let sub = SubsetData::new(problem, &row_subset(m, search_rows, opts.seed));
    let (found, starts, hinv) = multistart_bfgs(&sub.problem(problem), bounds, unpack, opts);
    // the subset's curvature is a far better start than the identity (on
    // 2 773 UR10 rows: 40 full-data iterations instead of 67). A ladder of
    // intermediate subsets (1 000 → 1 665 → 2 773 rows) was tried: fewer
    // full-data evaluations, but on UR10 series C two of three outputs
    // ended in worse optima (ln ψ −3.0306 and −2.0479 against −3.0314 and
    // −2.1142): the full-data stage's long early steps find basins the
    // subsets do not support yet.
    let mut r = converge_bfgs(problem, &found.x, Some(hinv), bounds, unpack, opts);
    r.best.evals += found.evals;
    r.starts = starts;
    r
}

/// The log-likelihood gain (nats) below which an iteration of a search
/// from a known basin no longer counts: ξ moving along a flat valley, the
/// predictor unchanged.
const LN_L_TOL: f64 = 0.01;

/// Tolerances of a BFGS started in a known basin ([`converge_bfgs`]: a
/// warm start with its curvature, or the optimum of a large campaign's
/// subset) on `rows` rows: an iteration that raises the log-likelihood
/// `ln L = −(m/2)(ln ψ + const)` by less than [`LN_L_TOL`] stops it, i.e.
/// lowers ln ψ by less than `2·LN_L_TOL/m` (3e-5 at 600 rows, 7e-6 at
/// 2 773), far inside the likelihood's own uncertainty (a 95 % interval of
/// one parameter spans 1.92 nats). Without it the last iterations crawl:
/// earlier `1e-7·|ln ψ|` on large campaigns let them crawl for 0.1 nats in
/// all per output, and on small ones the default `ftol` made the fold
/// refits of a `diagnose` CV on 600 rows of UR10 series C take 33–164
/// evaluations on z once harmonic trend terms were in (3–28 with this).
/// The price: a flat stretch before a further descent stops it there (a
/// warm fold refit on 180 rows of `comau_lhs` ended 0.12 nats below the
/// cold multistart on one output, its held-out predictions 8 % of their
/// RMS error apart; `tests/warm_start.rs`).
fn basin_tolerance(rows: usize) -> optim::QuasiNewtonOptions {
    optim::QuasiNewtonOptions {
        gtol: 1e-4,
        ftol: 1e-7,
        fatol: 2.0 * LN_L_TOL / rows as f64,
        ..optim::QuasiNewtonOptions::default()
    }
}

/// How a hyperparameter search went: the best point, the starts, the rows
/// of its last stage and, for BFGS, the inverse Hessian there.
pub(super) struct Search {
    pub(super) best: OptimResult,
    pub(super) starts: usize,
    pub(super) rows: usize,
    pub(super) inverse_hessian: Option<Hessian>,
}

/// BFGS from `x0` (inverse Hessian `hinv`, or the identity) to convergence
/// on all rows, or on a seeded subset of `opts.converge_rows` rows when
/// there are more (one start). Over [`SEARCH_ROWS`] rows, or from a start
/// with its curvature (`hinv`: a converged search's optimum on nearby
/// data), it stops at [`basin_tolerance`]; a start without one (a new
/// input's ξ set by hand) runs to the default tolerance, for such a
/// search begins on a flat stretch (ξ small: the input barely matters),
/// where the basin tolerance stopped it before it had moved (hysteresis
/// in `diagnose_table` refused, after/without 1.00–1.04 → 1.05–1.09).
pub(super) fn converge_bfgs(
    problem: &KrigingProblem,
    x0: &[f64],
    hinv: Option<Hessian>,
    bounds: &Bounds,
    unpack: &Unpack<'_>,
    opts: &KrigingOptions,
) -> Search {
    let m = problem.m();
    // a start with its curvature is a converged search's optimum, moved
    // little (a fold, one more trend term): its basin is known; a large
    // campaign's evaluations cost too much to crawl in any case
    let known_basin = m > SEARCH_ROWS || hinv.is_some();
    let full = optim::QuasiNewtonOptions {
        max_evals: opts.max_evals,
        ..if known_basin {
            basin_tolerance(m.min(opts.converge_rows))
        } else {
            optim::QuasiNewtonOptions::default()
        }
    };
    let refine_rows = m.min(opts.converge_rows);
    let refine_sub = converge_subset(m, opts).map(|rows| SubsetData::new(problem, &rows));
    let refine = refine_sub.as_ref().map(|s| s.problem(problem));
    let obj = ln_psi_grad_objective(refine.as_ref().unwrap_or(problem), unpack, &opts.cancel);
    let (best, h) = optim::quasi_newton_warm(obj, x0, hinv, bounds, &full);
    Search {
        best,
        starts: 1,
        rows: refine_rows,
        inverse_hessian: Some(h),
    }
}

/// The rows the default optimiser converges ξ on for a campaign of `m`
/// rows ([`KrigingOptions::converge_rows`]): `None` for all of them, else
/// the seeded subset it uses (sorted), so that a caller re-estimating ξ
/// on those rows itself gets the same ξ.
pub fn converge_subset(m: usize, opts: &KrigingOptions) -> Option<Vec<usize>> {
    (m > opts.converge_rows).then(|| row_subset(m, opts.converge_rows, opts.seed.wrapping_add(1)))
}

/// A problem's data restricted to some rows.
struct SubsetData {
    inputs: TrainingInputs,
    f: faer::Mat<f64>,
    y: Vec<f64>,
}

impl SubsetData {
    fn new(problem: &KrigingProblem, rows: &[usize]) -> Self {
        SubsetData {
            inputs: problem.inputs.select(rows),
            f: faer::Mat::from_fn(rows.len(), problem.f.ncols(), |i, j| {
                problem.f[(rows[i], j)]
            }),
            y: rows.iter().map(|&i| problem.y[i]).collect(),
        }
    }

    /// The same problem on these rows.
    fn problem<'a>(&'a self, like: &KrigingProblem<'a>) -> KrigingProblem<'a> {
        KrigingProblem {
            min_jitter: like.min_jitter,
            corr: like.corr,
            inputs: &self.inputs,
            f: &self.f,
            y: &self.y,
            prior: like.prior,
        }
    }
}

/// `k` of `m` row indices, drawn without replacement from `seed`, sorted.
pub(super) fn row_subset(m: usize, k: usize, seed: u64) -> Vec<usize> {
    use rand::SeedableRng;
    use rand::seq::SliceRandom;
    let mut idx: Vec<usize> = (0..m).collect();
    // a stream of its own: the seed mixed with a fixed odd constant
    let mut rng =
        rand::rngs::StdRng::seed_from_u64(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0x5b57_e7a1);
    idx.shuffle(&mut rng);
    idx.truncate(k);
    idx.sort_unstable();
    idx
}

/// Projected BFGS on the analytic gradient from several starts (the centre
/// of the start box and LHS points in it, `opts.starts` in all), by
/// successive halving: every start runs [`SCREEN_ITER`] iterations in
/// parallel; the better half continues for twice as many, and so on until
/// [`FINALISTS`] remain, which run to convergence unless they meet a better
/// one in its basin ([`converge_finalists`]); the best wins (ties by
/// start order). Runs continue with their own inverse Hessian. The
/// likelihood is multimodal, and a ranking after a few iterations favours
/// the basin that explains everything as noise (the nugget at its bound):
/// on the UR10 hybrid residual, keeping the best quarter after 8 iterations
/// missed the basin GPS finds on 2 of 3 outputs (ln ψ −0.80 against −1.02
/// on ey); the better half, converged, finds it.
fn multistart_bfgs(
    problem: &KrigingProblem,
    bounds: &Bounds,
    unpack: &Unpack<'_>,
    opts: &KrigingOptions,
) -> (OptimResult, usize, Hessian) {
    let d = problem.inputs.d;
    let mut start_box = bounds.clone();
    for k in 0..bounds.dim() {
        let (lo, hi) = if k < d {
            START_LOG10_THETA
        } else {
            START_LOG10_NUGGET
        };
        start_box.lo[k] = lo.clamp(bounds.lo[k], bounds.hi[k]);
        start_box.hi[k] = hi.clamp(bounds.lo[k], bounds.hi[k]);
    }
    let starts = optim::lhs_starts(&start_box, opts.starts, opts.seed);
    let full_iter = optim::QuasiNewtonOptions::default().max_iter;
    let screen = |iters: usize| optim::QuasiNewtonOptions {
        max_iter: iters,
        max_evals: opts.max_evals,
        ..optim::QuasiNewtonOptions::default()
    };
    let mut pool: Vec<Run> = starts
        .iter()
        .enumerate()
        .map(|(i, x)| Run::new(i, x.clone()))
        .collect();
    let workspaces = WorkspacePool::new(problem);
    let mut iters = SCREEN_ITER;
    let mut evals = 0;
    while pool.len() > FINALISTS {
        // successive halving: every run continues for `iters` iterations,
        // the better half (start order breaks ties) goes on for twice as many
        evals += run_all(
            &mut pool,
            problem,
            &workspaces,
            bounds,
            unpack,
            opts,
            &|_| screen(iters),
        );
        pool.sort_by(Run::order);
        pool.truncate(pool.len().div_ceil(2));
        iters *= 2;
    }
    evals += converge_finalists(
        &mut pool,
        problem,
        &workspaces,
        bounds,
        unpack,
        opts,
        full_iter,
    );
    pool.sort_by(Run::order);
    let best = pool.into_iter().next().expect("at least one start");
    let (mut result, hinv) = (best.result.expect("every run ran"), best.hinv);
    result.evals = evals;
    (result, starts.len(), hinv)
}

/// One BFGS run of the multistart, continued stage after stage with its
/// own inverse Hessian.
struct Run {
    /// Index of its start (breaks ties between equal ln ψ).
    start: usize,
    /// Where it stands.
    x: Vec<f64>,
    /// Its inverse Hessian (empty before the first stage).
    hinv: Hessian,
    /// ∇ ln ψ at `x` (empty before the first stage).
    grad: Vec<f64>,
    /// Its last stage's result.
    result: Option<OptimResult>,
    /// Iterations and evaluations over all its stages.
    iterations: usize,
    evals: usize,
    /// Converged, out of budget, or dropped as a duplicate.
    done: bool,
    /// ln ψ after each stage of [`converge_finalists`].
    finals: Vec<f64>,
}

impl Run {
    fn new(start: usize, x: Vec<f64>) -> Self {
        Run {
            start,
            x,
            hinv: Vec::new(),
            grad: Vec::new(),
            result: None,
            iterations: 0,
            evals: 0,
            done: false,
            finals: Vec::new(),
        }
    }

    fn f(&self) -> f64 {
        self.result.as_ref().map_or(f64::INFINITY, |r| r.f)
    }

    /// Better ln ψ first, then start order.
    fn order(a: &Run, b: &Run) -> std::cmp::Ordering {
        a.f().total_cmp(&b.f()).then(a.start.cmp(&b.start))
    }
}

/// Continue every run that is not done for one stage, in parallel, each
/// within the limits `stage` gives it; returns the evaluations spent.
fn run_all(
    pool: &mut [Run],
    problem: &KrigingProblem,
    workspaces: &WorkspacePool,
    bounds: &Bounds,
    unpack: &Unpack<'_>,
    opts: &KrigingOptions,
    stage: &(dyn Fn(&Run) -> optim::QuasiNewtonOptions + Sync),
) -> usize {
    let cancel = &opts.cancel;
    pool.par_iter_mut()
        .filter(|r| !r.done)
        .map(|r| {
            let o = stage(r);
            let mut ws = workspaces.take();
            let obj =
                |z: &[f64], g: &mut [f64]| ln_psi_grad(problem, unpack, cancel, &mut ws, z, g);
            // a run that has stopped once resumes from its known ln ψ and
            // gradient instead of evaluating its point again
            let known = r.result.as_ref().map(|last| (last.f, r.grad.as_slice()));
            let warm = (!r.hinv.is_empty()).then(|| std::mem::take(&mut r.hinv));
            let (res, h, g) = optim::quasi_newton_resume(obj, &r.x, known, warm, bounds, &o);
            workspaces.put(ws);
            r.grad = g;
            let spent = res.evals;
            r.x.clone_from(&res.x);
            r.iterations += res.iterations;
            r.evals += spent;
            r.hinv = h;
            // stopped before the stage's limits: converged (or stuck)
            r.done = res.stop != optim::StopReason::Budget
                || (res.iterations < o.max_iter && res.evals < o.max_evals);
            r.result = Some(res);
            spent
        })
        .sum()
}

/// Iterations a finalist runs between two checks for runs that have met.
/// A stage boundary does not change a run's path (it resumes with its
/// point, value, gradient and inverse Hessian), only how soon a duplicate
/// is dropped. On `likelihood_core 300` (12 three-output fits) 10 took
/// 6 845 evaluations, 5 took 6 534, 3 took 6 364, 2 took 6 248 and 1 took
/// 6 198, every one of the 36 ln ψ the same; 2 is as fast as 1 in wall time
/// (a stage is a synchronisation point of the output's finalists).
const FINAL_STAGE_ITER: usize = 2;
/// Stages of [`converge_finalists`] (of [`FINAL_STAGE_ITER`] iterations)
/// over which a finalist must gain at least the basin tolerance's `fatol`
/// (0.01 nats of log-likelihood) to go on.
const CRAWL_STAGES: usize = 10;
/// Two runs whose points differ by less than this in every coordinate
/// (log10 units: 26 % in ξ or ν) are in one basin of ln ψ.
const SAME_BASIN: f64 = 0.1;
/// Below this log10 ξ an input is inert: with normalised inputs
/// `ξ (s − s')² ≲ 0.01` over the campaign, so ln ψ is flat there and two
/// runs at, say, 10⁻⁴ and 10⁻⁶ are in one basin.
const INERT_LOG10_THETA: f64 = -3.0;

/// Run the finalists to convergence, [`FINAL_STAGE_ITER`] iterations at a
/// time, each within `full_iter` iterations and `opts.max_evals`
/// evaluations in all. After each stage a run that has come within
/// [`SAME_BASIN`] of a better one (lower ln ψ; start order breaks ties) is
/// dropped: both would converge to the same optimum, and converging such
/// duplicates was most of the multistart's cost (on the bench campaigns,
/// two to four of the four finalists reached the same ln ψ). A run in a
/// worse basin is not dropped for its ln ψ: on UR10 series B (ey) a
/// finalist whose quasi-Newton model predicted a decrease of 4e-6, 0.06
/// behind the best, went on to win by 0.02.
///
/// A run that crawls stops: when its last [`CRAWL_STAGES`] stages (20
/// iterations) together lowered ln ψ by less than the [`basin_tolerance`]
/// lets a single iteration stop at (0.01 nats of log-likelihood). On the
/// 632-pose ISO-cube campaign (`cargo bench --bench xi_choice`) the
/// kinematic-trend JS winner of ex otherwise ran to the 200-iteration
/// limit along a ridge, gaining 3.5e-9 of ln ψ per iteration from its
/// 70th; with the rule the fit took 364 evaluations instead of 916, at the
/// same ln ψ to four digits. The basin tolerance itself, which stops at
/// the first such iteration, was tried here and stopped a finalist on a
/// flat stretch 0.62 % above SMT's ψ (`tests/kriging_reference.rs`,
/// js / quadratic / ey); with this rule those nine reference fits reach
/// the same ψ as without it. A rule that also stopped a run which, at the
/// rate of its last [`CRAWL_STAGES`] stages, could not reach the best
/// run's ln ψ within its iteration limit was tried and dropped: on the
/// calibration residual of UR10 series B's first 600 rows it cut ey's
/// search from 1 263 evaluations to 358 at the same ln ψ (a finalist 0.23
/// behind crawled to its iteration limit along a valley, each step a
/// sixteenth to a thirty-second of the quasi-Newton step, 5–6 evaluations
/// an iteration, about 1 080 in all), and left
/// every default JS and EJS fit of the shipped campaigns and of B and C
/// at the same ln ψ to five digits, but it stopped the winner of ex in
/// the kinematic-trend EJS fit of all of series C (ln ψ −3.2468 against
/// −3.5746; `holdout --cv 10` on C: that model's mean 3D error 0.1902
/// against 0.1700 mm): a finalist far behind may crawl, then descend.
/// Returns the evaluations spent.
fn converge_finalists(
    pool: &mut [Run],
    problem: &KrigingProblem,
    workspaces: &WorkspacePool,
    bounds: &Bounds,
    unpack: &Unpack<'_>,
    opts: &KrigingOptions,
    full_iter: usize,
) -> usize {
    let d = problem.inputs.d;
    let crawl_tol = basin_tolerance(problem.m()).fatol;
    let stage = |r: &Run| optim::QuasiNewtonOptions {
        max_iter: FINAL_STAGE_ITER.min(full_iter.saturating_sub(r.iterations)),
        max_evals: opts.max_evals.saturating_sub(r.evals),
        ..optim::QuasiNewtonOptions::default()
    };
    let mut evals = 0;
    loop {
        // out of budget; a run that converged while screening stays done
        for r in pool.iter_mut() {
            let o = stage(r);
            r.done |= o.max_iter == 0 || o.max_evals == 0;
        }
        if pool.iter().all(|r| r.done) {
            break;
        }
        evals += run_all(pool, problem, workspaces, bounds, unpack, opts, &stage);
        let points: Vec<(usize, f64, Vec<f64>)> =
            pool.iter().map(|r| (r.start, r.f(), r.x.clone())).collect();
        for r in pool.iter_mut().filter(|r| !r.done) {
            // crawling: the last CRAWL_STAGES stages together gained less
            // than the basin tolerance of one iteration
            r.finals.push(r.f());
            let k = r.finals.len();
            if k > CRAWL_STAGES && r.finals[k - 1 - CRAWL_STAGES] - r.f() < crawl_tol {
                r.done = true;
            }
        }
        for r in pool.iter_mut().filter(|r| !r.done) {
            let (f, start) = (r.f(), r.start);
            r.done = points
                .iter()
                .any(|(s, g, x)| (*g < f || (*g == f && *s < start)) && same_basin(x, &r.x, d));
        }
    }
    evals
}

/// [`SAME_BASIN`] apart at most in every coordinate, the first `d` (log10
/// ξ) floored at [`INERT_LOG10_THETA`].
fn same_basin(a: &[f64], b: &[f64], d: usize) -> bool {
    a.iter().zip(b).enumerate().all(|(k, (x, y))| {
        let (x, y) = if k < d {
            (x.max(INERT_LOG10_THETA), y.max(INERT_LOG10_THETA))
        } else {
            (*x, *y)
        };
        (x - y).abs() < SAME_BASIN
    })
}

/// A BFGS inverse Hessian approximation.
type Hessian = Vec<Vec<f64>>;

/// Mesh size at which every GPS start stops before the first selection.
const SCREEN_MESH: f64 = 0.25;

/// Minimise ln ψ; returns the best result (evals summed over all runs) and the
/// number of starts.
///
/// GPS uses successive halving over its starts: every start runs (in
/// parallel) to a mesh of [`SCREEN_MESH`]; the better half continues to a mesh
/// four times finer, and so on until one remains, which is polished to
/// `opts.tol`. Losing starts stop early, and the choice between the last
/// candidates is made on nearly converged values. With `opts.polish` the
/// winner then gets finite-difference BFGS steps ([`optim::bfgs`]): ψ is
/// smooth there, and this reaches the last digits a pattern search would need
/// thousands of evaluations for (on the COMAU campaign ψ drops by another
/// ~1e-6 relative, to the precision of SMT's gradient-based optimiser).
pub(super) fn optimise(
    problem: &KrigingProblem,
    bounds: &Bounds,
    unpack: &Unpack<'_>,
    opts: &KrigingOptions,
) -> Search {
    let m = problem.m();
    let done = |best: OptimResult, starts: usize| Search {
        best,
        starts,
        rows: m,
        inverse_hessian: None,
    };
    let run = |x0: &[f64], initial_mesh: f64, tol: f64| {
        let obj = ln_psi_objective(problem, unpack, &opts.cancel);
        match opts.optimizer {
            OptimizerKind::Gps => optim::gps(
                obj,
                x0,
                bounds,
                &GpsOptions {
                    initial_mesh,
                    mesh_tol: tol,
                    max_evals: opts.max_evals,
                    ..GpsOptions::default()
                },
            ),
            // Bfgs returned before `run` is used
            OptimizerKind::HookeJeeves | OptimizerKind::Bfgs => optim::hooke_jeeves(
                obj,
                x0,
                bounds,
                &HjOptions {
                    max_evals: opts.max_evals,
                    ..HjOptions::default()
                },
            ),
        }
    };
    match opts.optimizer {
        OptimizerKind::HookeJeeves => return done(run(&bounds.center(), 0.5, opts.tol), 1),
        OptimizerKind::Bfgs => return optimise_bfgs(problem, bounds, unpack, opts),
        OptimizerKind::Gps => {}
    }
    let starts = optim::lhs_starts(bounds, opts.starts, opts.seed);
    let mut mesh = SCREEN_MESH.max(opts.tol);
    let (_, mut pool) = optim::multistart(&starts, |x0| run(x0, 0.5, mesh));
    let mut evals: usize = pool.iter().map(|r| r.evals).sum();
    loop {
        // stable sort: ties keep start order, so the result is deterministic
        pool.sort_by(|a, b| a.f.total_cmp(&b.f));
        pool.truncate(pool.len().div_ceil(2));
        if (pool.len() == 1 && mesh <= opts.tol) || opts.cancel.is_cancelled() {
            break;
        }
        let next = if pool.len() == 1 {
            opts.tol
        } else {
            (mesh / 4.0).max(opts.tol)
        };
        let (_, refined) = optim::multistart(
            &pool.iter().map(|r| r.x.clone()).collect::<Vec<_>>(),
            |x0| run(x0, mesh, next),
        );
        evals += refined.iter().map(|r| r.evals).sum::<usize>();
        // a refinement never returns a worse point than it started from
        pool = refined;
        mesh = next;
    }
    let mut best = pool.swap_remove(0);
    if !opts.polish || opts.cancel.is_cancelled() {
        best.evals = evals;
        return done(best, starts.len());
    }
    let obj = ln_psi_objective(problem, unpack, &opts.cancel);
    let mut polished = optim::bfgs(obj, &best.x, bounds, &optim::BfgsOptions::default());
    polished.evals += evals;
    done(polished, starts.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// One basin: every coordinate within [`SAME_BASIN`], ξ below
    /// [`INERT_LOG10_THETA`] counted as equal; the nugget (after the `d`
    /// ξ coordinates) is not floored.
    #[test]
    fn same_basin_floors_inert_inputs_only() {
        assert!(same_basin(&[-1.0, -4.0, -2.0], &[-1.05, -6.0, -2.05], 2));
        assert!(!same_basin(&[-1.0, -2.5, -2.0], &[-1.0, -6.0, -2.0], 2));
        assert!(!same_basin(&[-1.0, -4.0, -4.0], &[-1.0, -4.0, -6.0], 2));
        assert!(!same_basin(&[-1.0, -4.0, -2.0], &[-0.8, -4.0, -2.0], 2));
    }
}
