//! `caustics`: command-line entry. Parses arguments, dispatches to the library, maps errors to exit codes
#![recursion_limit = "256"]
//! (2: bad input, 1: any other failure). The commands (src/app/) use only the library's public API.

mod app;

#[global_allocator]
static HEAP: app::heap::CountingAlloc = app::heap::CountingAlloc;

use caustics::error::Result;
use clap::{Parser, Subcommand};

const ENVIRONMENT: &str = "\
Environment:
  CAUSTICS_DEVICE      Vulkan device: cpu (lavapipe), gpu, an index into the usable devices (digits only), or a
                       device's name or a substring of exactly one device's name. Default: a GPU if there is
                       one, else lavapipe.
  CAUSTICS_VALIDATION  1: Khronos validation layers (with synchronization validation) on, and any validation
                       message fails the command; 0: off. Default: on in debug builds, off in release builds.
  CAUSTICS_CACHE_DIR   Where `bench` caches its CPU references. Default: $CARGO_TARGET_DIR/reference-cache, else
                       target/reference-cache.

Exit codes: 0 success, 2 bad input (an argument, a scene or an image; the message names it), 1 anything else.
Docs: README.md, docs/cli.md (every option, the stats keys), docs/design.md (units, metric, contracts),
docs/scenes.md (every scene key), docs/viewer.md (the viewer's controls).";

#[derive(Parser, Debug)]
#[command(
    name = "caustics",
    version,
    about = "Real-time refractive caustics: adaptive caustic maps on Vulkan",
    after_help = ENVIRONMENT
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a frame headless and write an AOV (beauty PNG, caustics or direct EXR in W/m²).
    Render(app::commands::RenderArgs),
    /// Render frames and print per-stage GPU timings (timestamp queries); takes the method options of render.
    Profile(app::commands::ProfileArgs),
    /// Exact CPU photon tracer: ground truth for orthographic cameras.
    Reference(app::reference_cmd::ReferenceArgs),
    /// Speed against error: sweep methods and levels, time them, score them against the CPU reference.
    Bench(app::bench::BenchArgs),
    /// Compare two EXR images with the project's error metric.
    Compare(app::compare::CompareArgs),
    /// Windowed viewer: orbit the camera, move the light, switch methods; live per-stage GPU timings.
    View(app::viewer::ViewArgs),
    /// Stability over time: error and flicker against the CPU reference along a light orbit.
    Temporal(app::temporal::TemporalArgs),
    /// Soak: many frames through one renderer with a moving light and changing settings (tools/soak).
    #[command(hide = true)]
    Soak(app::soak::SoakArgs),
}

fn run(cli: Cli) -> Result<()> {
    match cli.command {
        Command::Render(a) => app::commands::run_render(&a),
        Command::Profile(a) => app::commands::run_profile(&a),
        Command::Reference(a) => app::reference_cmd::run(&a),
        Command::Bench(a) => app::bench::run_bench(&a),
        Command::Compare(a) => app::compare::run_compare(&a),
        Command::View(a) => app::viewer::run(&a),
        Command::Soak(a) => app::soak::run_soak(&a),
        Command::Temporal(a) => app::temporal::run_temporal(&a),
    }
}

/// Rust ignores SIGPIPE, so printing into a closed pipe (`caustics profile | head`) would panic. Restore the
/// default action: the process ends quietly, like any Unix filter.
#[cfg(unix)]
fn restore_sigpipe() {
    // SAFETY: setting a signal disposition to its default at startup, before any thread exists.
    unsafe {
        libc::signal(libc::SIGPIPE, libc::SIG_DFL);
    }
}

fn main() {
    #[cfg(unix)]
    restore_sigpipe();
    // The library reports through `log`; the CLI prints its warnings as `warning: ...` lines on stderr (and, with
    // RUST_LOG=info or debug, the rest with their level and module).
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn"))
        .format(|buf, record| {
            use std::io::Write;
            match record.level() {
                log::Level::Error => writeln!(buf, "error: {}", record.args()),
                log::Level::Warn => writeln!(buf, "warning: {}", record.args()),
                level => writeln!(buf, "[{level} {}] {}", record.target(), record.args()),
            }
        })
        .init();
    let cli = Cli::parse();
    // Tracy's client (`--features tracy`): it sends the renderer's zones while Tracy's profiler is connected.
    #[cfg(feature = "tracy")]
    let _tracy = tracy_client::Client::start();
    if let Err(e) = run(cli) {
        eprintln!("error: {}", app::flags::message(&e));
        std::process::exit(e.exit_code());
    }
}

#[cfg(test)]
mod tests {
    use super::Cli;
    use clap::CommandFactory;

    /// The flag src/app/flags.rs gives each library field is an option of `render` or `reference`.
    #[test]
    fn every_mapped_flag_is_an_option() {
        let cli = Cli::command();
        let longs: Vec<String> = ["render", "reference"]
            .iter()
            .flat_map(|name| cli.find_subcommand(name).unwrap().get_arguments())
            .filter_map(|a| a.get_long().map(|l| format!("--{l}")))
            .collect();
        for (field, flag) in crate::app::flags::FLAGS {
            assert!(longs.iter().any(|l| l == flag), "{field}: {flag} is not an option of render or reference");
        }
    }
}
