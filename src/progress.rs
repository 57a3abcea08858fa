//! The progress bar the CLI shows on stderr while a render runs. It is fed through the render's
//! row hook ([`crate::options::Progress`]), appears only once a render has taken about a second,
//! and only when stderr is a terminal: piped or redirected stderr (tests, scripts, CI) sees
//! nothing.
//!
//! ```text
//! render_with_progress(.., &|rows| bar.rows_done(rows.count)) --> indicatif bar on stderr (tty only)
//! ```

use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};

/// How long a render runs before its bar appears.
pub const SHOW_AFTER: Duration = Duration::from_secs(1);

/// A row counter that draws a bar on stderr once [`SHOW_AFTER`] has passed, if stderr is a
/// terminal; otherwise it only counts.
pub struct RowBar {
    bar: Option<ProgressBar>,
    start: Instant,
    shown: AtomicBool,
}

impl RowBar {
    /// A bar for `rows` rows labelled `label` (drawn only when stderr is a terminal).
    pub fn new(label: &str, rows: u32) -> RowBar {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar =
                ProgressBar::with_draw_target(Some(rows as u64), ProgressDrawTarget::hidden());
            let style = ProgressStyle::with_template(
                "{msg:>9} [{bar:40.cyan/blue}] {pos}/{len} rows, {elapsed} (eta {eta})",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar())
            .progress_chars("=> ");
            bar.set_style(style);
            bar.set_message(label.to_string());
            bar
        });
        RowBar {
            bar,
            start: Instant::now(),
            shown: AtomicBool::new(false),
        }
    }

    /// Counts `rows` more finished rows; the render's [`crate::options::Progress`] hook.
    pub fn rows_done(&self, rows: u32) {
        let Some(bar) = &self.bar else {
            return;
        };
        bar.inc(rows as u64);
        if !self.shown.load(Ordering::Relaxed)
            && self.start.elapsed() >= SHOW_AFTER
            && !self.shown.swap(true, Ordering::Relaxed)
        {
            bar.set_draw_target(ProgressDrawTarget::stderr());
        }
    }

    /// Removes the bar from the terminal.
    pub fn finish(&self) {
        if let Some(bar) = &self.bar {
            bar.finish_and_clear();
        }
    }
}

impl Drop for RowBar {
    fn drop(&mut self) {
        self.finish();
    }
}
