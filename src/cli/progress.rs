//! Progress bars (indicatif) on stderr; hidden when stderr is not a terminal,
//! so piped and test output stays clean.

use indicatif::{ProgressBar, ProgressStyle};
use robokrige::report::fit::ga_progress;

/// Run `work` with a bar of `len` steps labelled `prefix` (elapsed time and
/// a message) drawn, and clear the bar once it returns, failed or not.
pub fn with_bar<T>(len: u64, prefix: &str, work: impl FnOnce(&ProgressBar) -> T) -> T {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{prefix:>10} [{bar:30}] {pos}/{len} {elapsed:>4} {msg}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    pb.set_prefix(prefix.to_string());
    let out = work(&pb);
    pb.finish_and_clear();
    out
}

/// [`with_bar`] with a spinner, for work of unknown length.
pub fn with_spinner<T>(prefix: &str, work: impl FnOnce(&ProgressBar) -> T) -> T {
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{prefix:>10} {spinner} {elapsed:>4} {msg}")
            .expect("valid template"),
    );
    pb.set_prefix(prefix.to_string());
    pb.enable_steady_tick(std::time::Duration::from_millis(200));
    let out = work(&pb);
    pb.finish_and_clear();
    out
}

/// A library's progress `(done, total)` drawn on `pb`.
pub fn of_total(pb: &ProgressBar) -> impl Fn(usize, usize) + Sync + '_ {
    |done, total| {
        pb.set_length(total as u64);
        pb.set_position(done as u64);
    }
}

/// A library's progress `(done, what)` drawn on `pb`.
pub fn steps(pb: &ProgressBar) -> impl Fn(usize, &str) + Sync + '_ {
    |done, what| {
        pb.set_position(done as u64);
        pb.set_message(what.to_string());
    }
}

/// A library's progress `(done, total, what)` drawn on `pb`.
pub fn steps_of(pb: &ProgressBar) -> impl Fn(usize, usize, &str) + Sync + '_ {
    |done, total, what| {
        pb.set_length(total as u64);
        steps(pb)(done, what);
    }
}

/// The GA's progress `(axis, generation, best CV RMSE)` as `pb`'s message
/// ([`robokrige::report::fit::ga_progress`]).
pub fn ga(pb: &ProgressBar) -> impl Fn(usize, usize, f64) + Sync + '_ {
    |axis, generation, best| pb.set_message(ga_progress(axis, generation, best))
}
