//! The demo's progress on stderr: one bar per stage and its time.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use nlsdof::demo::DemoProgress;
use std::sync::Mutex;

/// A progress bar for a stage of `len` steps labelled `stage`.
pub fn stage_bar(len: u64, stage: &str) -> ProgressBar {
    let pb = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    if let Ok(style) =
        ProgressStyle::with_template("{prefix:>11} {wide_msg} [{bar:20}] {pos}/{len} {elapsed:>4}")
    {
        pb.set_style(style.progress_chars("=> "));
    }
    pb.set_prefix(stage.to_string());
    pb
}

/// The bars of the computing stages.
#[derive(Default)]
pub struct Bars {
    bar: Mutex<Option<ProgressBar>>,
    /// The stage timing lines, printed by [`Bars::print_stages`] once the
    /// report is written: a failing run prints only its one error line.
    stages: Mutex<Vec<String>>,
}

impl Bars {
    /// Prints the stage timings (stderr), after success.
    pub fn print_stages(&self) {
        for line in self.stages.lock().expect("no panic while locked").iter() {
            eprintln!("{line}");
        }
    }

    fn with(&self, f: impl FnOnce(&ProgressBar)) {
        if let Some(pb) = self.bar.lock().expect("no panic while locked").as_ref() {
            f(pb);
        }
    }
}

impl DemoProgress for Bars {
    fn stage(&self, label: &str, steps: u64) {
        *self.bar.lock().expect("no panic while locked") = Some(stage_bar(steps, label));
    }
    fn message(&self, message: &str) {
        self.with(|pb| pb.set_message(message.to_string()));
    }
    fn step(&self) {
        self.with(|pb| pb.inc(1));
    }
    fn done(&self, name: &str, seconds: f64) {
        self.with(|pb| pb.finish_and_clear());
        self.stages
            .lock()
            .expect("no panic while locked")
            .push(format!("nlsdof demo: {name:<22} {seconds:>6.2} s"));
    }
}
