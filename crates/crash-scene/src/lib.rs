//! crash-scene: scene files (TOML) turned into ready-to-run core objects.
//!
//! `load`/`parse` read and check a scene (syntax, keys, types, globals, materials,
//! references); `Scene::build` generates or imports the meshes and returns the bodies
//! and run parameters (`Built`). Every error is a `SceneError` that names the file,
//! line, column and key and says what is valid. The format: docs/scene-format.md.

pub mod build;
pub mod context;
pub mod error;
pub mod globals;
pub mod margin;
pub mod msh;
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

use context::Ctx;
use crash_core::hash::Fnv;
use crash_core::Material;
use globals::Globals;
use schema::SceneFile;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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
}

/// Read and check a scene file.
pub fn load(path: &Path) -> Result<Scene, SceneError> {
    let file = path.display().to_string();
    let text = std::fs::read_to_string(path).map_err(|e| SceneError {
        kind: ErrorKind::Read,
        file: file.clone(),
        line: 0,
        column: 0,
        key: String::new(),
        message: format!("cannot read the scene file: {e}"),
    })?;
    parse(&text, &file)
}

/// Check a scene given as text; `file` names it in errors and locates imported meshes
/// (relative to its directory).
pub fn parse(text: &str, file: &str) -> Result<Scene, SceneError> {
    let ctx = Ctx::new(file, text);
    let spec: SceneFile = toml::from_str(text).map_err(|e| ctx.from_toml(&e))?;
    let end_time = globals::check_end_time(&ctx, spec.end_time, false)?;
    let g = globals::globals(&ctx, &spec, end_time, None)?;
    let materials = globals::materials(&ctx, &spec)?;
    globals::references(&ctx, &spec, &materials)?;
    let path = Path::new(file);
    let name = spec.name.clone().unwrap_or_else(|| {
        path.file_stem()
            .map_or_else(|| "scene".to_string(), |s| s.to_string_lossy().into_owned())
    });
    let mut hash = Fnv::default();
    hash.bytes(text.as_bytes());
    Ok(Scene {
        spec,
        name,
        dir: path.parent().map(Path::to_path_buf).unwrap_or_default(),
        globals: g,
        materials,
        overrides: Overrides::default(),
        ctx,
        hash,
    })
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
        build::build(self, &self.ctx, self.hash)
    }
}
