//! One look for the progress bars of long jobs (campaigns, `eval-vision`
//! and its sweep, `render-dataset`, `detect` over many images): done of
//! all, rate, time left. indicatif draws on standard error only when it is
//! a terminal, so scripts, pipes and logs see none of it.

use indicatif::{ProgressBar, ProgressStyle};

/// A bar over `len` items called `what` ("trials", "images").
pub fn bar(len: usize, what: &str) -> ProgressBar {
    let template = format!(
        "{{bar:30}} {{pos}}/{{len}} {what}  {{per_sec}}, {{elapsed}} elapsed, about {{eta}} left  {{msg}}"
    );
    let style =
        ProgressStyle::with_template(&template).unwrap_or_else(|_| ProgressStyle::default_bar());
    ProgressBar::new(len as u64).with_style(style)
}
