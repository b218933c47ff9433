//! The `filigree` command-line tool: a thin layer over the library.
//! Each subcommand lives in `src/cmd/<name>.rs` and only parses, calls the
//! core and prints; no algorithm lives here.
use clap::{Parser, Subcommand};
use std::process::ExitCode;

// The CLI may time things and use threads; the library may not (clippy.toml).
#[allow(clippy::disallowed_methods)]
mod cmd;

#[derive(Parser)]
#[command(
    name = "filigree",
    version,
    about = "Filigree: a procedural-pattern studio (CLI of the same core the browser app runs)"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Describe an image: size, palette, colour clusters.
    Inspect(cmd::inspect::Args),
    /// Fit a pattern program's parameters to a target image.
    Fit(cmd::fit::FitArgs),
    /// Draw a pattern program with given parameters to PNG or SVG.
    Render(cmd::fit::RenderArgs),
    /// Texture pixel art with oriented elements in the image's own palette.
    Pixel(Box<cmd::pixel::Args>),
    /// Benchmarks that print JSON.
    Bench {
        #[command(subcommand)]
        which: cmd::bench::Which,
    },
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Inspect(a) => cmd::inspect::run(a),
        Command::Fit(a) => cmd::fit::run_fit(a),
        Command::Render(a) => cmd::fit::run_render(a),
        Command::Pixel(a) => cmd::pixel::run(*a),
        Command::Bench { which } => cmd::bench::run(which),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("filigree: {e}");
            ExitCode::FAILURE
        }
    }
}
