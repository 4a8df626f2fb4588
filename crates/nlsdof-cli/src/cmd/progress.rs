//! The progress bars of the fits (one tick per start; the staged fit
//! names each stage).

use nlsdof::identification::IdentifyProgress;

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

/// One bar for the stages of the default staged fit
/// ([`nlsdof::identification::identify`]): each stage resets it to its own
/// length and names itself, e.g. `generalised: landscape [====] 12/41`.
pub fn stage_bar(what: &str) -> (indicatif::ProgressBar, impl Fn(IdentifyProgress) + Sync) {
    let pb =
        indicatif::ProgressBar::with_draw_target(Some(1), indicatif::ProgressDrawTarget::stderr());
    if let Ok(style) =
        indicatif::ProgressStyle::with_template("{msg} [{bar:30}] {pos}/{len} ({elapsed})")
    {
        pb.set_style(style);
    }
    pb.set_message(what.to_string());
    let bar = pb.clone();
    let what = what.to_string();
    let on = move |p: IdentifyProgress| match p {
        IdentifyProgress::Stage { name, steps } => {
            bar.set_length(steps as u64);
            bar.set_position(0);
            bar.set_message(format!("{what}: {name}"));
        }
        IdentifyProgress::Step => bar.inc(1),
    };
    (pb, on)
}

/// A bar of local fits labelled `what` (`fit --profile`: one profile of an
/// exponent, at most `1 + 2 × 24` fits; a side ends early when it crosses
/// the threshold), and the `progress(done, most)` callback that moves it.
pub fn fits_bar(what: &str) -> (indicatif::ProgressBar, impl Fn(usize, usize) + Sync) {
    let pb =
        indicatif::ProgressBar::with_draw_target(Some(1), indicatif::ProgressDrawTarget::stderr());
    if let Ok(style) = indicatif::ProgressStyle::with_template(
        "{msg} [{bar:30}] {pos}/{len} local fits at most ({elapsed})",
    ) {
        pb.set_style(style);
    }
    pb.set_message(what.to_string());
    let bar = pb.clone();
    let on = move |done: usize, most: usize| {
        bar.set_length(most as u64);
        bar.set_position(done as u64);
    };
    (pb, on)
}
