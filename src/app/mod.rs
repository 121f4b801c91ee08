//! The command-line applications on the library's public API: `render` and `profile` (commands/), `reference`,
//! `compare`, `bench` (with its report), `view` (the windowed viewer), `temporal` and the hidden `soak`.

pub mod bench;
pub mod bench_report;
pub mod commands;
pub mod compare;
pub mod flags;
pub mod heap;
pub mod profiler;
pub mod reference_cmd;
pub mod soak;
pub mod temporal;
pub mod viewer;

/// A progress bar on stderr: the bar `make` makes, styled by `template`, where stderr is a terminal; else a hidden
/// one.
pub fn stderr_bar(make: impl FnOnce() -> indicatif::ProgressBar, template: &str) -> indicatif::ProgressBar {
    use std::io::IsTerminal;
    if !std::io::stderr().is_terminal() {
        return indicatif::ProgressBar::hidden();
    }
    let bar = make();
    if let Ok(style) = indicatif::ProgressStyle::with_template(template) {
        bar.set_style(style);
    }
    bar
}
