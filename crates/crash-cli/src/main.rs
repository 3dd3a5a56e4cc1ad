//! The `crash` command.

use anyhow::Context;
use clap::{Parser, Subcommand};
use crash_scene::keyword::DeckOptions;
use std::path::{Path, PathBuf};
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
        /// The scene file (TOML) or an LS-DYNA keyword deck (.k, .key, .dyn).
        scene: PathBuf,
        /// Keyword decks: run contacts with friction frictionless instead of refusing them.
        #[arg(long)]
        ignore_friction: bool,
    },
    /// Convert an LS-DYNA keyword deck into a scene (TOML) and its meshes (Gmsh .msh,
    /// one per part, next to the scene): docs/keyword-input.md.
    Convert {
        /// The keyword deck (.k, .key, .dyn).
        deck: PathBuf,
        /// The scene file to write; meshes are written as SCENE_STEM.partPID.msh beside it.
        scene: PathBuf,
        /// Convert contacts with friction as frictionless instead of refusing them.
        #[arg(long)]
        ignore_friction: bool,
    },
    /// Verification ladders (error against wall time) and the stability matrix.
    Study(crash_cli::study::cli::StudyArgs),
    /// Pictures of a finished run: snapshots, a contact sheet at the key moments with the
    /// contact zone (from below, section cut), contact-force and energy plots.
    Render {
        /// The run directory (written by `crash run`).
        out: PathBuf,
    },
}

/// `crash convert DECK SCENE`: write the scene and its meshes, print the files; warn
/// when the scene would not run yet (e.g. a load curve the core cannot run).
fn convert(deck: &Path, scene: &Path, opts: &DeckOptions) -> anyhow::Result<ExitCode> {
    let prefix = scene
        .file_stem()
        .map_or_else(|| "scene".into(), |s| s.to_string_lossy().into_owned());
    let c = crash_scene::keyword::convert(deck, opts, &prefix)?;
    for n in &c.notes {
        match n.strip_prefix("warning: ") {
            Some(w) => eprintln!("crash: warning: {w}"),
            None => eprintln!("crash: note: {n}"),
        }
    }
    let files = c
        .write(scene)
        .with_context(|| format!("cannot write {}", scene.display()))?;
    for f in &files {
        println!("{}", f.display());
    }
    if let Err(e) = crash_scene::load(scene).and_then(|s| s.build()) {
        eprintln!("crash: warning: the scene is written but does not run yet: {e}");
    }
    Ok(ExitCode::SUCCESS)
}

fn main() -> ExitCode {
    tracing_subscriber::fmt()
        .with_env_filter(
            tracing_subscriber::EnvFilter::try_from_default_env()
                .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("warn")),
        )
        .with_writer(std::io::stderr)
        // colour codes only on a terminal: logs kept in files stay plain text
        .with_ansi(std::io::IsTerminal::is_terminal(&std::io::stderr()))
        .init();
    let result = match Cli::parse().command {
        Command::Run(args) => {
            // SIGINT, SIGTERM: finish the step, last frame, restart file, summary.json
            // (interrupted), exit 130; a second one quits at once
            if let Err(e) = crash_master::stop::install_handlers() {
                eprintln!("crash: warning: cannot handle SIGINT/SIGTERM: {e}");
            }
            crash_cli::run::run(&args)
        }
        Command::Study(args) => crash_cli::study::cli::study(&args),
        Command::Check {
            scene,
            ignore_friction,
        } => crash_cli::check::check(&scene, &DeckOptions { ignore_friction })
            .map(|()| ExitCode::SUCCESS),
        Command::Convert {
            deck,
            scene,
            ignore_friction,
        } => convert(&deck, &scene, &DeckOptions { ignore_friction }),
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
