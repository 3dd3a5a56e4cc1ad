//! crash-scene: scene files (TOML) turned into ready-to-run core objects.
//!
//! `load`/`parse` read and check a scene (syntax, keys, types, globals, materials,
//! curves, references, the files it names); `Scene::build` estimates the memory the
//! meshes need, generates or imports them and returns the bodies and run parameters
//! (`Built`). Every error is a `SceneError` that names the file, line, column and key
//! and says what is valid. The format: docs/scene-format.md. `keyword` reads LS-DYNA
//! keyword decks into the same scenes (docs/keyword-input.md); `load_input` loads
//! either.

pub mod build;
pub mod context;
pub mod curves;
pub mod error;
pub mod exact;
pub mod files;
pub mod globals;
pub mod keyword;
pub mod margin;
pub mod memory;
pub mod motion;
pub mod msh;
pub mod msh_write;
pub mod outputs;
pub mod overlap;
pub mod plan;
pub mod schema;
pub mod select;
pub mod shape;
pub mod spans;
pub mod summary;

pub use build::{BodyInfo, Built};
pub use error::{ErrorKind, SceneError};
pub use overlap::{check_initial_overlap, Penetration};
pub use plan::Plan;
pub use summary::{BodySummary, Summary};

use context::{Ctx, Origins};
use crash_core::hash::Fnv;
use crash_core::Material;
use globals::Globals;
use schema::SceneFile;
use shape::MeshInputs;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// A scene or keyword deck that cannot be loaded.
#[derive(Debug, Clone, PartialEq, Eq, thiserror::Error)]
pub enum InputError {
    #[error(transparent)]
    Scene(#[from] SceneError),
    #[error(transparent)]
    Deck(#[from] keyword::DeckError),
}

/// Load a scene file (TOML) or an LS-DYNA keyword deck (`.k`, `.key`, `.dyn`): the one
/// entry point of `crash run` and `crash check`.
pub fn load_input(path: &Path, deck: &keyword::DeckOptions) -> Result<Scene, InputError> {
    if keyword::is_deck(path) {
        keyword::load(path, deck)
    } else {
        Ok(load(path)?)
    }
}

/// Values given on the command line that replace the file's.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Overrides {
    /// Replaces `end_time` [s].
    pub end_time: Option<f64>,
    /// Replaces `output_interval` [s].
    pub output_interval: Option<f64>,
}

/// A parsed and checked scene file (meshes not yet generated).
#[derive(Debug, Clone)]
pub struct Scene {
    /// The file as written (after serde).
    pub spec: SceneFile,
    /// Run name: `name` or the file stem.
    pub name: String,
    /// Imported meshes are found relative to this directory.
    pub dir: PathBuf,
    pub globals: Globals,
    pub materials: BTreeMap<String, Material>,
    overrides: Overrides,
    ctx: Ctx,
    /// FNV-1a state after the scene file's bytes.
    hash: Fnv,
    /// Mesh files given in memory (a converted keyword deck's parts), by name.
    inputs: MeshInputs,
    /// Memory the build may assume available [bytes] (None: MemAvailable).
    memory_limit: Option<u64>,
    /// Notes from the conversion of a keyword deck, passed on to `Built::notes`.
    notes: Vec<String>,
}

/// Read and check a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    let whole = |kind, message| SceneError {
        kind,
        file: file.clone(),
        line: 0,
        column: 0,
        key: String::new(),
        message,
    };
    // a scene file is small: the cap only keeps /dev/zero and the like out
    let bytes = files::read(path, files::MAX_FILE_BYTES).map_err(|p| {
        let msg = match &p {
            files::FileProblem::Unreadable(e) => format!("cannot read the scene file: {e}"),
            other => format!(
                "cannot read the scene file: {}",
                other.describe(path, files::MAX_FILE_BYTES)
            ),
        };
        whole(ErrorKind::Read, msg)
    })?;
    let text = String::from_utf8(bytes).map_err(|_| {
        whole(
            ErrorKind::Read,
            "cannot read the scene file: not UTF-8 text".into(),
        )
    })?;
    parse(&text, &file)
}

/// Check a scene given as text; `file` names it in errors and locates imported meshes
/// (relative to its directory).
pub fn parse(text: &str, file: &str) -> Result<Scene, SceneError> {
    let dir = Path::new(file)
        .parent()
        .map(Path::to_path_buf)
        .unwrap_or_default();
    parse_with(text, file, dir, MeshInputs::new(), None)
}

/// `parse` with mesh files given in memory and, for a converted keyword deck, the
/// deck cards its keys came from (errors then point at the deck).
pub fn parse_with(
    text: &str,
    file: &str,
    dir: PathBuf,
    inputs: MeshInputs,
    origins: Option<Origins>,
) -> Result<Scene, SceneError> {
    let mut ctx = Ctx::new(file, text);
    ctx.origins = origins;
    let spec: SceneFile = toml::from_str(text).map_err(|e| ctx.from_toml(&e))?;
    let end_time = globals::check_end_time(&ctx, spec.end_time, false)?;
    globals::check_name(&ctx, spec.name.as_deref())?;
    let g = globals::globals(&ctx, &spec, end_time, None)?;
    let materials = globals::materials(&ctx, &spec)?;
    globals::references(&ctx, &spec, &materials)?;
    let curves = curves::curves(&ctx, &spec)?;
    globals::curve_references(&ctx, &spec, &curves)?;
    outputs::check(&ctx, &spec)?;
    check_files(&ctx, &spec, &dir, &inputs)?;
    // the file stem is one path component; `.`/`..` (a file named "..." or "...toml")
    // would still leave the output root
    let name = spec.name.clone().unwrap_or_else(|| {
        Path::new(file)
            .file_stem()
            .map(|s| s.to_string_lossy().into_owned())
            .filter(|s| !matches!(s.as_str(), "" | "." | ".."))
            .unwrap_or_else(|| "scene".to_string())
    });
    let mut hash = Fnv::default();
    hash.bytes(text.as_bytes());
    Ok(Scene {
        spec,
        name,
        dir,
        globals: g,
        materials,
        overrides: Overrides::default(),
        ctx,
        hash,
        inputs,
        memory_limit: None,
        notes: Vec::new(),
    })
}

/// Every mesh file the scene names exists, is a regular file, is within the size cap and
/// can be read in the memory available: checked before anything is built, and
/// reported at the `file` key that names it.
fn check_files(
    ctx: &Ctx,
    spec: &SceneFile,
    dir: &Path,
    inputs: &MeshInputs,
) -> Result<(), SceneError> {
    for (i, b) in spec.bodies.iter().enumerate() {
        let Some(m) = &b.mesh else { continue };
        if inputs.contains_key(&m.file) {
            continue;
        }
        let key = format!("bodies[{i}].mesh.file");
        let path = dir.join(&m.file);
        let len = files::check(&path, files::MAX_FILE_BYTES).map_err(|p| {
            let kind = match p {
                files::FileProblem::TooLarge(_) => ErrorKind::TooLarge,
                _ => ErrorKind::Read,
            };
            ctx.value_error(kind, &key, p.describe(&path, files::MAX_FILE_BYTES))
        })?;
        let need = len.saturating_mul(shape::MSH_READ_FACTOR);
        if let Some(avail) = memory::available().filter(|&a| need > a) {
            return Err(ctx.value_error(
                ErrorKind::TooLarge,
                &key,
                format!(
                    "{} is {len} bytes: reading it needs about {}, more than the {} this machine has available",
                    path.display(),
                    memory::human(need as f64),
                    memory::human(avail as f64)
                ),
            ));
        }
    }
    Ok(())
}

impl Scene {
    /// The same scene with command-line values in place of the file's.
    pub fn with_overrides(mut self, o: Overrides) -> Result<Self, SceneError> {
        let end_time = match o.end_time {
            Some(t) => globals::check_end_time(&self.ctx, t, true)?,
            None => self.spec.end_time,
        };
        if let Some(dt) = o.output_interval {
            if !(dt.is_finite() && dt > 0.0) {
                return Err(self.ctx.key_error(
                    ErrorKind::Invalid,
                    "output_interval",
                    format!("{dt} (given on the command line): must be finite and > 0 (s)"),
                ));
            }
        }
        // the default output interval follows an overridden end time
        self.globals = globals::globals(&self.ctx, &self.spec, end_time, o.output_interval)?;
        self.overrides = o;
        Ok(self)
    }

    pub fn overrides(&self) -> Overrides {
        self.overrides
    }

    /// The scene file's name as given to `load`/`parse`.
    pub fn file(&self) -> &str {
        &self.ctx.file
    }

    /// Generate or import the meshes and build the bodies (ids 0..n in file order).
    pub fn build(&self) -> Result<Built, SceneError> {
        let mut b = build::build(self, &self.ctx, self.hash)?;
        let mut notes = self.notes.clone();
        notes.append(&mut b.notes);
        b.notes = notes;
        Ok(b)
    }

    /// Build as if the machine had `bytes` of memory available (instead of
    /// /proc/meminfo's MemAvailable): for tests and for running on another machine.
    pub fn with_memory_limit(mut self, bytes: u64) -> Self {
        self.memory_limit = Some(bytes);
        self
    }

    /// Add notes that `Built::notes` will carry (the conversion notes of a deck).
    pub fn with_notes(mut self, notes: Vec<String>) -> Self {
        self.notes.extend(notes);
        self
    }
}
