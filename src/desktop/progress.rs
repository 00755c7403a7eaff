//! Progress on stderr, phase by phase.

use std::io::IsTerminal;

/// Progress on stderr (indicatif): one bar per phase of a pass — `photons` (chunks
/// traced), `balance` (subtrees balanced), `rows` (rows rendered) — with the pass, the
/// phase's name, the steps done and an ETA. Hidden unless enabled and stderr is a
/// terminal. Workers tick it from any thread.
#[derive(Debug)]
pub struct Progress {
    bar: indicatif::ProgressBar,
    passes: u32,
}

impl Progress {
    /// A bar over `passes` passes; draws nothing unless `enabled` and stderr is a
    /// terminal.
    pub fn new(enabled: bool, passes: u32) -> Self {
        let bar = if enabled && std::io::stderr().is_terminal() {
            indicatif::ProgressBar::with_draw_target(None, indicatif::ProgressDrawTarget::stderr())
        } else {
            indicatif::ProgressBar::hidden()
        };
        let template = "{prefix:>16} [{bar:30}] {pos}/{len} {elapsed:>4} ETA {eta}";
        if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
            bar.set_style(style.progress_chars("#>-"));
        }
        Self { bar, passes }
    }

    /// A bar that draws nothing.
    pub fn hidden() -> Self {
        Self::new(false, 1)
    }

    /// Starts phase `name` of pass `pass` (from 0) over `steps` steps.
    pub fn phase(&self, pass: u32, name: &str, steps: usize) {
        let prefix = if self.passes > 1 {
            std::format!("pass {}/{} {name}", pass + 1, self.passes)
        } else {
            name.into()
        };
        self.bar.reset();
        self.bar.set_prefix(prefix);
        self.bar.set_length(steps as u64);
    }

    /// The current phase has `steps` steps after all (once they are known).
    pub fn set_steps(&self, steps: usize) {
        self.bar.set_length(steps as u64);
    }

    /// One step done.
    pub fn tick(&self) {
        self.bar.inc(1);
    }

    /// Clears the bar.
    pub fn finish(&self) {
        self.bar.finish_and_clear();
    }
}
