//! Progress bars (indicatif) on stderr; hidden when stderr is not a terminal,
//! so piped and test output stays clean.

use indicatif::{ProgressBar, ProgressStyle};

/// A bar of `len` steps labelled `prefix`, with elapsed time and a message.
pub fn bar(len: u64, prefix: &str) -> ProgressBar {
    let pb = ProgressBar::new(len);
    pb.set_style(
        ProgressStyle::with_template("{prefix:>10} [{bar:30}] {pos}/{len} {elapsed:>4} {msg}")
            .expect("valid template")
            .progress_chars("=> "),
    );
    pb.set_prefix(prefix.to_string());
    pb
}

/// A spinner labelled `prefix` for steps of unknown length.
pub fn spinner(prefix: &str) -> ProgressBar {
    let pb = ProgressBar::new_spinner();
    pb.set_style(
        ProgressStyle::with_template("{prefix:>10} {spinner} {elapsed:>4} {msg}")
            .expect("valid template"),
    );
    pb.set_prefix(prefix.to_string());
    pb.enable_steady_tick(std::time::Duration::from_millis(200));
    pb
}
