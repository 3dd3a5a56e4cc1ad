//! LS-DYNA keyword decks (`.k`, `.key`, `.dyn`) read into scenes: the subset of
//! docs/keyword-input.md, everything else refused with its file, line and keyword.
//!
//! `lexer` reads the deck and its includes into blocks of cards; `cards` splits cards
//! into fields (fixed columns, long format, commas) and reads numbers; `readers` and
//! `control` turn blocks into the typed records of `deck`; `convert`, `mesh` and `bc`
//! make bodies of the parts; `emit` writes them as a scene (TOML and Gmsh meshes), with
//! the origin of every key so that the scene's own checks point at the deck's cards.
//! `crash run deck.k` parses that scene with the meshes in memory; `crash convert`
//! writes it.

pub mod bc;
pub mod boundary;
pub mod cards;
pub mod control;
pub mod convert;
pub mod deck;
pub mod emit;
pub mod lexer;
pub mod mesh;
pub mod props;
pub mod readers;

pub use emit::Converted;

use crate::shape::{MeshInput, MeshInputs};
use crate::Scene;
use std::path::{Path, PathBuf};
use thiserror::Error;

/// A deck that cannot be read or converted: `file:line:column: *KEYWORD: message`
/// (column 0 when the whole card is meant, line 0 when the whole file).
#[derive(Debug, Clone, PartialEq, Eq, Error)]
#[error("{}", self.located())]
pub struct DeckError {
    pub file: String,
    pub line: usize,
    pub column: usize,
    /// The keyword without `*` (empty when none applies).
    pub keyword: String,
    pub message: String,
}

impl DeckError {
    fn located(&self) -> String {
        let mut s = self.file.clone();
        if self.line > 0 {
            s.push_str(&format!(":{}", self.line));
            if self.column > 0 {
                s.push_str(&format!(":{}", self.column));
            }
        }
        if self.keyword.is_empty() {
            format!("{s}: {}", self.message)
        } else {
            format!("{s}: *{}: {}", self.keyword, self.message)
        }
    }
}

/// Choices the user makes about what a deck may lose.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq)]
pub struct DeckOptions {
    /// Run contacts with friction (FS, FD) frictionless, with a note, instead of
    /// refusing them.
    pub ignore_friction: bool,
}

/// A keyword deck by its extension (`.k`, `.key`, `.dyn`, any case).
pub fn is_deck(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| matches!(e.to_ascii_lowercase().as_str(), "k" | "key" | "dyn"))
}

fn stem(path: &Path) -> String {
    path.file_stem()
        .map_or_else(|| "deck".to_string(), |s| s.to_string_lossy().into_owned())
}

/// Read and convert the deck at `path`; meshes are named `{mesh_prefix}.part{PID}.msh`.
pub fn convert(path: &Path, opts: &DeckOptions, mesh_prefix: &str) -> Result<Converted, DeckError> {
    let deck = deck::read(path)?;
    let model = convert::model(&deck, opts)?;
    Ok(emit::emit(&deck, model, &stem(path), mesh_prefix))
}

/// The deck at `path` as a checked scene (meshes in memory, errors at the deck's cards).
pub fn load(path: &Path, opts: &DeckOptions) -> Result<Scene, crate::InputError> {
    let c = convert(path, opts, &stem(path))?;
    Ok(c.scene(path)?)
}

impl Converted {
    /// The scene of this conversion, errors located in the deck at `path`.
    pub fn scene(self, path: &Path) -> Result<Scene, crate::SceneError> {
        let mut inputs = MeshInputs::new();
        for (name, surface, files) in self.meshes {
            inputs.insert(
                name,
                MeshInput {
                    surface,
                    written: Some((self.files.clone(), files)),
                },
            );
        }
        let dir = path.parent().map(Path::to_path_buf).unwrap_or_default();
        let scene = crate::parse_with(
            &self.toml,
            &path.display().to_string(),
            dir,
            inputs,
            Some(self.origins),
        )?;
        Ok(scene.with_notes(self.notes))
    }

    /// Write the scene to `scene` and its meshes next to it (names as in the TOML;
    /// the directory is made if needed); returns the files written.
    pub fn write(&self, scene: &Path) -> std::io::Result<Vec<PathBuf>> {
        let dir = scene.parent().map(Path::to_path_buf).unwrap_or_default();
        if !dir.as_os_str().is_empty() {
            std::fs::create_dir_all(&dir)?;
        }
        let mut out = Vec::new();
        for (name, surface, _) in &self.meshes {
            let mut text = String::new();
            crate::msh_write::write(surface, &mut text);
            let p = dir.join(name);
            std::fs::write(&p, text)?;
            out.push(p);
        }
        std::fs::write(scene, &self.toml)?;
        out.insert(0, scene.to_path_buf());
        Ok(out)
    }
}
