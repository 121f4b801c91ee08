//! `caustics`: command-line entry. Parses arguments, dispatches to the library, maps errors to exit codes
//! (2: bad input, 1: any other failure).

use caustics::error::AppResult;
use clap::{Parser, Subcommand};

#[derive(Parser, Debug)]
#[command(name = "caustics", version, about = "Real-time refractive caustics: adaptive caustic maps on Vulkan")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Render a frame headless and write an AOV (beauty PNG, caustics or direct EXR in W/m²).
    Render(caustics::commands::RenderArgs),
    /// Render frames and print per-stage GPU timings (timestamp queries).
    Profile(caustics::commands::ProfileArgs),
    /// Exact CPU photon tracer: ground truth for orthographic cameras.
    Reference(caustics::reference::ReferenceArgs),
    /// Speed against error: sweep methods and levels, time them, score them against the CPU reference.
    Bench(caustics::bench::BenchArgs),
    /// Compare two EXR images with the project's error metric.
    Compare(caustics::metrics::CompareArgs),
    /// Windowed viewer: orbit the camera, move the light, switch methods; live per-stage GPU timings.
    View(caustics::viewer::ViewArgs),
    /// Stability over time: error and flicker against the CPU reference along a light orbit.
    Temporal(caustics::temporal::TemporalArgs),
    /// Soak: many frames through one renderer with a moving light and changing settings (tools/soak).
    #[command(hide = true)]
    Soak(caustics::soak::SoakArgs),
}

fn run(cli: Cli) -> AppResult<()> {
    match cli.command {
        Command::Render(a) => caustics::commands::run_render(&a),
        Command::Profile(a) => caustics::commands::run_profile(&a),
        Command::Reference(a) => caustics::reference::run(&a),
        Command::Bench(a) => caustics::bench::run_bench(&a),
        Command::Compare(a) => caustics::metrics::run_compare(&a),
        Command::View(a) => caustics::viewer::run(&a),
        Command::Soak(a) => caustics::soak::run_soak(&a),
        Command::Temporal(a) => caustics::temporal::run_temporal(&a),
    }
}

/// Rust ignores SIGPIPE, so printing into a closed pipe (`caustics profile | head`) would panic. Restore the
/// default action: the process ends quietly, like any Unix filter.
#[cfg(unix)]
fn restore_sigpipe() {
    extern "C" {
        fn signal(signum: i32, handler: usize) -> usize;
    }
    const SIGPIPE: i32 = 13;
    const SIG_DFL: usize = 0;
    // SAFETY: setting a signal disposition to its default at startup, before any thread exists.
    unsafe {
        signal(SIGPIPE, SIG_DFL);
    }
}

fn main() {
    #[cfg(unix)]
    restore_sigpipe();
    env_logger::Builder::from_env(env_logger::Env::default().default_filter_or("warn")).format_timestamp(None).init();
    let cli = Cli::parse();
    if let Err(e) = run(cli) {
        eprintln!("error: {e}");
        std::process::exit(e.exit_code());
    }
}
