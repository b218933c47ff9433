//! The `filigree` command-line tool: a thin layer over the library.
//! Each subcommand lives in `src/cli/cmd/<name>.rs` and only parses, calls
//! the core and prints; no algorithm lives here. `filigree bench` is
//! `src/bench/` (the `bench` feature).
use clap::{Parser, Subcommand};
use std::process::ExitCode;

// The CLI may time things and use threads; the library may not (clippy.toml).
#[allow(clippy::disallowed_methods)]
mod cmd;
// `filigree bench`: only in a binary built with the `bench` feature.
#[cfg(feature = "bench")]
#[allow(clippy::disallowed_methods)]
#[path = "../bench/mod.rs"]
mod bench;

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
    Fit(Box<cmd::fit::FitArgs>),
    /// Draw a pattern program with given parameters to PNG or SVG.
    Render(cmd::fit::RenderArgs),
    /// Texture pixel art with oriented elements in the image's own palette.
    Pixel(Box<cmd::pixel::Args>),
    /// Grow a pen-and-ink tangle from a group grammar, to SVG or PNG.
    Tangle(Box<cmd::tangle::Args>),
    /// Multiscale microstructures: sphere-trace or slice an implicit scene.
    Micro {
        #[command(subcommand)]
        which: cmd::micro::Which,
    },
    /// Texture: from an example image to a procedural model and its
    /// parameters (`--index I --image IMG [--set scale=v] --out OUT.png`),
    /// or inspect the models (render, models, sheet).
    #[command(args_conflicts_with_subcommands = true)]
    Texture {
        #[command(subcommand)]
        which: Option<cmd::texture::Which>,
        #[command(flatten)]
        query: Box<cmd::texture_index::QueryArgs>,
    },
    /// Build the Texture tool's index (dataset, scales, PCN-2, SVMs, space).
    BuildIndex(cmd::texture_index::BuildArgs),
    /// Benchmarks that print JSON.
    #[cfg(feature = "bench")]
    Bench {
        #[command(subcommand)]
        which: bench::Which,
    },
}

/// Output piped into a reader that stops early (`filigree inspect … | head`)
/// ends the program quietly, as a Unix tool killed by SIGPIPE would (status
/// 141), instead of a panic message from `println!`.
fn quiet_on_broken_pipe() {
    let default = std::panic::take_hook();
    std::panic::set_hook(Box::new(move |info| {
        let msg = info
            .payload()
            .downcast_ref::<String>()
            .map(String::as_str)
            .or_else(|| info.payload().downcast_ref::<&str>().copied())
            .unwrap_or("");
        if msg.starts_with("failed printing to stdout") && msg.contains("Broken pipe") {
            std::process::exit(141);
        }
        default(info);
    }));
}

fn main() -> ExitCode {
    quiet_on_broken_pipe();
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Inspect(a) => cmd::inspect::run(a),
        Command::Fit(a) => cmd::fit::run_fit(*a),
        Command::Render(a) => cmd::fit::run_render(a),
        Command::Pixel(a) => cmd::pixel::run(*a),
        Command::Tangle(a) => cmd::tangle::run(*a),
        Command::Micro { which } => cmd::micro::run(which),
        Command::Texture {
            which: Some(which), ..
        } => cmd::texture::run(which),
        Command::Texture { which: None, query } => cmd::texture_index::run_query(*query),
        Command::BuildIndex(a) => cmd::texture_index::run_build(a),
        #[cfg(feature = "bench")]
        Command::Bench { which } => bench::run(which),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("filigree: {e}");
            ExitCode::FAILURE
        }
    }
}
