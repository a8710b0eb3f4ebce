//! The `raykit` command line: argument parsing and wiring only; the work is
//! done by the library crates.

mod cmd;
mod error_message;
mod instanced_arg;
mod paths;
mod stage;
mod stdout_errors;

use clap::{Parser, Subcommand};
use std::io::Write;
use std::process::ExitCode;

/// raykit: ray casting and spatial queries on triangle meshes.
///
/// Meshes are read from OBJ, PLY (.ply, .ply.gz), STL, glTF/GLB and OFF files,
/// or generated: `builtin:NAME` picks a built-in scene (`raykit info scenes`).
#[derive(Parser)]
#[command(name = "raykit", version)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Render a scene with the Whitted ray tracer: mirrors, glass, lights, shadows, HDR environments.
    Render(cmd::render::RenderArgs),
    /// Assemble the PNG parts of `raykit render --tile I/N` into the whole image.
    MergeTiles(cmd::merge_tiles::MergeTilesArgs),
    /// Generate a standard ray set (primary, shadow, incoherent) as a binary ray file.
    Rays(cmd::rays::RaysArgs),
    /// Trace a ray file against a mesh and write hits (or occlusion) to a file.
    Trace(cmd::trace::TraceArgs),
    /// Point and ray queries on a mesh's surface: closest point, distance, signed distance, inside, hit counts, all hits.
    Query(cmd::query::QueryArgs),
    /// Measure build time, memory and Mrays/s of bvh8 (the default) or of every structure × triangle test.
    Bench(raykit_lab::bench::BenchArgs),
    /// Find and remove T-junctions (vertices inside other triangles' edges).
    Tjunctions(cmd::tjunctions::TJunctionsArgs),
    /// Remove the hidden interior of a model: triangles or parts no outside viewpoint sees.
    Cull(cmd::cull::CullArgs),
    /// DEMs: height-field ray casting (per-frame quadtree boxes) and shadow masks (Min 2008).
    Terrain(cmd::terrain::TerrainArgs),
    /// Stream rendered frames to browsers over WebSocket (JPEG) or MJPEG, with interactive cameras.
    Serve(cmd::serve::ServeArgs),
    /// Reproduce published tables and figures on this machine (CSV, Markdown, SVG).
    Experiment(raykit_lab::experiment::ExperimentArgs),
    /// Write a scene (built-in or file) as glTF with its materials, camera and lights.
    Export(cmd::export::ExportArgs),
    /// List the names accepted by --accel, --test and --scene.
    Info(cmd::info::InfoArgs),
}

fn main() -> ExitCode {
    stdout_errors::install();
    let cli = Cli::parse();
    if !matches!(cli.command, Command::Serve(_)) {
        remove_unfinished_outputs_on_stop();
    }
    let result = match cli.command {
        Command::Render(a) => cmd::render::run(a),
        Command::MergeTiles(a) => cmd::merge_tiles::run(a),
        Command::Rays(a) => cmd::rays::run(a),
        Command::Trace(a) => cmd::trace::run(a),
        Command::Query(a) => cmd::query::run(a),
        Command::Bench(a) => raykit_lab::bench::run(a),
        Command::Tjunctions(a) => cmd::tjunctions::run(a),
        Command::Cull(a) => cmd::cull::run(a),
        Command::Serve(a) => cmd::serve::run(a),
        Command::Terrain(a) => cmd::terrain::run(a),
        Command::Experiment(a) => raykit_lab::experiment::run(a),
        Command::Export(a) => cmd::export::run(a),
        Command::Info(a) => cmd::info::run(a),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("raykit: error: {}", error_message::error_message(&e));
            ExitCode::FAILURE
        }
    }
}

/// On Ctrl-C, SIGTERM or SIGHUP, remove the temporary files of the outputs
/// being written, leave their destinations as they were, and end with the
/// status a shell gives a program stopped by that signal (128 + its number:
/// 130 for Ctrl-C, 143 for SIGTERM). `serve` handles Ctrl-C and SIGTERM
/// itself, as a graceful shutdown that exits with status 0.
fn remove_unfinished_outputs_on_stop() {
    let installed = stop_handler(|status| {
        let _writes_stopped = raykit_io::remove_unfinished_outputs();
        // Not eprintln!: with stderr closed it would panic and never exit.
        let _ = writeln!(
            std::io::stderr(),
            "raykit: stopped; unfinished outputs removed"
        );
        std::process::exit(status);
    });
    if let Err(e) = installed {
        eprintln!(
            "raykit: warning: cannot handle Ctrl-C ({e}); a stopped run may leave temporary files"
        );
    }
}

/// Run `stop(128 + signal)` on a thread of its own when SIGINT, SIGTERM or
/// SIGHUP arrives; SIGHUP only where the process was not started ignoring
/// it, so that a command under `nohup` outlives its terminal.
#[cfg(unix)]
fn stop_handler(stop: impl Fn(i32) + Send + 'static) -> std::io::Result<()> {
    use signal_hook::consts::{SIGHUP, SIGINT, SIGTERM};
    let mut wanted = vec![SIGINT, SIGTERM];
    if !ignored(SIGHUP) {
        wanted.push(SIGHUP);
    }
    let mut signals = signal_hook::iterator::Signals::new(wanted)?;
    std::thread::Builder::new()
        .name("stop".into())
        .spawn(move || {
            if let Some(signal) = signals.forever().next() {
                stop(128 + signal);
            }
        })?;
    Ok(())
}

/// Whether `signal` is ignored (`SIG_IGN`), as `nohup` leaves SIGHUP.
#[cfg(unix)]
fn ignored(signal: i32) -> bool {
    // SAFETY: a query only (no new action), into a zeroed `sigaction`,
    // which is a valid value of that plain C struct.
    unsafe {
        let mut old: libc::sigaction = std::mem::zeroed();
        libc::sigaction(signal, std::ptr::null(), &mut old) == 0
            && old.sa_sigaction == libc::SIG_IGN
    }
}

/// Run `stop(130)` on Ctrl-C or a termination request.
#[cfg(not(unix))]
fn stop_handler(stop: impl Fn(i32) + Send + 'static) -> Result<(), ctrlc::Error> {
    ctrlc::set_handler(move || stop(130))
}
