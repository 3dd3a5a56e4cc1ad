//! The `crash` command.

use clap::{Parser, Subcommand};
use std::path::PathBuf;
use std::process::ExitCode;

#[derive(Parser, Debug)]
#[command(
    name = "crash",
    version,
    about = "Explicit finite elements for impacts between thin elastic shells"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Run a scene in this process (in-process workers; no network).
    Run(crash_cli::run::RunArgs),
    /// Validate a scene and print its bodies, the stable time step and the cost, without running.
    Check {
        /// The scene file (TOML).
        scene: PathBuf,
    },
    /// Verification ladders (error against wall time) and the stability matrix.
    Study(crash_cli::study::cli::StudyArgs),
    /// Pictures of a finished run: snapshots, a contact sheet and the energy plot.
    Render {
        /// The run directory (written by `crash run`).
        out: PathBuf,
    },
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        .init();
    let result = match Cli::parse().command {
        Command::Run(args) => crash_cli::run::run(&args),
        Command::Study(args) => crash_cli::study::cli::study(&args),
        Command::Check { scene } => crash_cli::check::check(&scene).map(|()| ExitCode::SUCCESS),
        Command::Render { out } => crash_io::render_run(&out)
            .map(|files| {
                for f in files {
                    println!("{}", f.display());
                }
                ExitCode::SUCCESS
            })
            .map_err(anyhow::Error::from),
    };
    match result {
        Ok(code) => code,
        Err(e) => {
            eprintln!("crash: error: {e:#}");
            ExitCode::from(2)
        }
    }
}
