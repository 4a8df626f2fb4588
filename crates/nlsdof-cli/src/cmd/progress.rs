//! The progress bar of the fits (one tick per start).

/// A bar of `len` starts labelled `what`, drawn on stderr.
pub fn progress_bar(len: usize, what: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::with_draw_target(
        Some(len as u64),
        indicatif::ProgressDrawTarget::stderr(),
    );
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} starts ({elapsed})")
    {
        pb.set_style(style);
    }
    pb.set_message(what.to_string());
    pb
}
