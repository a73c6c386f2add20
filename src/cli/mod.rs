//! One module per subcommand. Each parses its flags (with units in their names) and calls the
//! library; no physics lives here.

pub mod calibrate;
pub mod contact;
pub mod contact_normal;
pub mod contact_tangential;
pub mod decay;
pub mod diagnose;
pub mod elements;
pub mod film;
pub mod identify;
pub mod merge;
pub mod modes;
pub mod progress;
pub mod response;
pub mod surface;

use asperity::{Error, Grid2, Result};

/// `"nx × ny points, spacing dx × dy m, periodic"` (or `non-periodic (zero-padded kernels)`).
pub fn surface_summary(surface: &Grid2) -> String {
    asperity::core::grid::describe(surface)
}

/// Declare topography files read by a command as inputs of its output set, each with its
/// `.npy.json` sidecar where it has one: no output may be either.
pub fn surface_inputs(
    out: &mut asperity::core::output::OutputSet,
    files: &[std::path::PathBuf],
    role: &str,
) -> Result<()> {
    asperity::surface::io::declare_inputs(out, files, role)
}

/// Name the CLI flag in a parameter error raised by the library.
pub fn rename_param(e: Error, flag: &str) -> Error {
    e.renamed_param(flag)
}

/// A progress bar on stderr for `len` units of work, labelled `label` (with the current step in
/// its message), showing elapsed time and the estimate of what remains. When stderr is not a
/// terminal (output redirected to a log), it prints plain log lines instead (see
/// [`progress::LogLines`]).
pub fn progress_bar(label: &str, len: u64) -> indicatif::ProgressBar {
    let bar = indicatif::ProgressBar::with_draw_target(Some(len), progress::draw_target());
    let template = if progress::is_terminal() {
        format!("{label} {{msg:>16}} {{bar:30}} {{pos}}/{{len}} [{{elapsed_precise}} < {{eta}}]")
    } else {
        format!("{label}: {{msg}} {{pos}}/{{len}}, elapsed {{elapsed_precise}}, about {{eta}} left")
    };
    bar.set_style(indicatif::ProgressStyle::with_template(&template).expect("valid template"));
    bar
}

/// A spinner on stderr for work of unknown length (log lines when stderr is not a terminal).
pub fn spinner(msg: &str) -> indicatif::ProgressBar {
    let pb = indicatif::ProgressBar::with_draw_target(None, progress::draw_target());
    if !progress::is_terminal() {
        pb.set_style(
            indicatif::ProgressStyle::with_template("{msg}, elapsed {elapsed_precise}")
                .expect("valid template"),
        );
    }
    pb.set_message(msg.to_string());
    pb.enable_steady_tick(std::time::Duration::from_millis(120));
    pb
}
