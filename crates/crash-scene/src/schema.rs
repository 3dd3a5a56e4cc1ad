//! The scene file as written (serde, unknown keys rejected). Values are checked and
//! turned into core objects by `build`; defaults live there, next to their checks.
//! Fixed-length arrays (vectors, sizes, cell counts, curve points) are read by
//! `exact`, which refuses any other length.

use crate::exact;
use serde::Deserialize;
use std::collections::BTreeMap;

pub type V3 = [f64; 3];

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SceneFile {
    /// Run name (default: the file stem).
    pub name: Option<String>,
    /// Simulated time [s].
    pub end_time: f64,
    /// Fraction of the critical time step used (default 0.9).
    pub dt_safety: Option<f64>,
    /// Gravity acceleration [m/s^2] (default zero).
    #[serde(default, deserialize_with = "exact::option")]
    pub gravity: Option<V3>,
    /// Time between output frames [s] (default end_time / 100).
    pub output_interval: Option<f64>,
    /// The run's energy-balance limit (default 0.05): a warning at once, a stop (exit 3)
    /// more than 3 steps past it.
    pub energy_limit: Option<f64>,
    #[serde(default)]
    pub contact: ContactSpec,
    #[serde(default)]
    pub materials: BTreeMap<String, MaterialSpec>,
    #[serde(default)]
    pub bodies: Vec<BodySpec>,
    /// Load curves by name: time/value tables for prescribed motion and loads.
    #[serde(default)]
    pub curves: BTreeMap<String, CurveSpec>,
    /// Requested result intervals beyond the frames (parsed and checked; written by the
    /// run once the outputs exist, see docs/scene-format.md).
    #[serde(default)]
    pub outputs: OutputsSpec,
}

/// A load curve: points (time [s], value) with increasing times, linear between
/// points, the first value before the first point and the last value after the last.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CurveSpec {
    #[serde(deserialize_with = "exact::rows")]
    pub points: Vec<[f64; 2]>,
}

/// Result intervals [s] named after the LS-DYNA files they correspond to.
#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct OutputsSpec {
    /// Global statistics (energies of the whole scene).
    pub glstat: Option<f64>,
    /// Energies per body.
    pub matsum: Option<f64>,
    /// Contact forces per interface / body pair.
    pub rcforc: Option<f64>,
    /// Histories of the nodes in `history`.
    pub nodout: Option<f64>,
    /// Reaction forces at supports.
    pub spcforc: Option<f64>,
    /// Nodes whose histories are requested, by body and mesh node id.
    #[serde(default)]
    pub history: Vec<HistorySpec>,
    /// Float arrays of the frames: "f64" (default) or "f32".
    pub precision: Option<String>,
    /// Frame data compression: "zlib" (default) or "none".
    pub compression: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct HistorySpec {
    pub body: String,
    /// Node ids of the body's mesh file.
    pub nodes: Vec<i64>,
}

#[derive(Debug, Clone, Default, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ContactSpec {
    pub enabled: Option<bool>,
    /// Search margin [m] (default: derived, see `margin`).
    pub margin: Option<f64>,
    pub penalty_scale: Option<f64>,
    /// "soft" or "element".
    pub penalty: Option<String>,
    pub damping_ratio: Option<f64>,
    /// "limit_dt" (default) or "stop".
    pub speed_rule: Option<String>,
    /// "nodes" (default) or "segments".
    pub pass: Option<String>,
    /// The segment pass's sides: "auto" (default), "finer" or "both".
    pub sides: Option<String>,
}

/// Either (young, poisson) or the seed's Lamé pair (lambda1, lambda2).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MaterialSpec {
    /// [kg/m^3]
    pub density: f64,
    /// Young's modulus [Pa].
    pub young: Option<f64>,
    /// Poisson's ratio [-].
    pub poisson: Option<f64>,
    /// Lamé constants of the seed's energy density [Pa].
    pub lambda1: Option<f64>,
    pub lambda2: Option<f64>,
    /// Kelvin damping time alpha [s] (default 0).
    pub kelvin: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BodySpec {
    pub name: String,
    pub material: String,
    /// Shell thickness [m].
    pub thickness: f64,
    /// "tri" or "quad" (default depends on the shape).
    pub element: Option<String>,
    /// Transverse shear correction factor (default 5/6).
    pub shear_factor: Option<f64>,
    /// Translation [m] applied after the rotation.
    #[serde(default, deserialize_with = "exact::option")]
    pub position: Option<V3>,
    pub rotation: Option<RotationSpec>,
    /// Initial velocity of the centre of mass (of `angular_velocity_centre` when given)
    /// [m/s].
    #[serde(default, deserialize_with = "exact::option")]
    pub velocity: Option<V3>,
    /// Initial angular velocity [rad/s] about the centre of mass (or about
    /// `angular_velocity_centre`).
    #[serde(default, deserialize_with = "exact::option")]
    pub angular_velocity: Option<V3>,
    /// The point [m, global] the initial rigid motion is given at (default: the centre
    /// of mass).
    #[serde(default, deserialize_with = "exact::option")]
    pub angular_velocity_centre: Option<V3>,
    /// Mass-proportional damping c [1/s].
    pub mass_damping: Option<f64>,
    /// Takes part in contact (default true).
    pub contact: Option<bool>,
    pub self_contact: Option<bool>,
    // exactly one shape
    pub plate: Option<PlateSpec>,
    pub sphere: Option<SphereSpec>,
    pub cylinder: Option<CylinderSpec>,
    #[serde(rename = "box")]
    pub cuboid: Option<BoxSpec>,
    pub mesh: Option<MeshSpec>,
    #[serde(default)]
    pub fix: Vec<FixSpec>,
    #[serde(default)]
    pub prescribe: Vec<PrescribeSpec>,
    #[serde(default)]
    pub load: Vec<LoadSpec>,
    #[serde(default)]
    pub pressure: Vec<PressureSpec>,
}

/// Right-handed rotation by `angle` degrees about `axis` (any length > 0).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RotationSpec {
    #[serde(deserialize_with = "exact::array")]
    pub axis: V3,
    pub angle: f64,
}

/// Counts are read as signed integers so that a negative one gets a clear message.
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PlateSpec {
    /// [lx, ly] in m.
    #[serde(deserialize_with = "exact::array")]
    pub size: [f64; 2],
    /// [nx, ny] cells.
    #[serde(default, deserialize_with = "exact::option")]
    pub cells: Option<[i64; 2]>,
    /// Target cell size [m] (instead of cells).
    pub element_size: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SphereSpec {
    pub radius: f64,
    /// Icosphere subdivision level: 20 * 4^level triangles.
    pub level: Option<i64>,
    /// Cubed sphere instead of an icosphere: cells per cube-face edge (6 n^2 quads,
    /// or 12 n^2 triangles with `element = "tri"`).
    pub cubed: Option<i64>,
    /// Target edge length [m] (instead of level).
    pub element_size: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CylinderSpec {
    pub radius: f64,
    pub length: f64,
    /// [around, along] cells.
    #[serde(default, deserialize_with = "exact::option")]
    pub cells: Option<[i64; 2]>,
    pub element_size: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BoxSpec {
    /// [lx, ly, lz] in m.
    #[serde(deserialize_with = "exact::array")]
    pub size: V3,
    /// Cells along the longest side.
    pub cells: Option<i64>,
    pub element_size: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct MeshSpec {
    /// Gmsh .msh (4.1 ASCII), relative to the scene file.
    pub file: String,
    /// Factor applied to the file's coordinates (e.g. 0.001 for mm), default 1.
    pub scale: Option<f64>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FixSpec {
    /// "all", "x-", "x+", "y-", "y+", "z-", "z+" or { min = [..], max = [..] }.
    pub select: toml::Value,
    /// "all" (default), "translations", "rotations" or a list of "x","y","z","rx","ry","rz".
    pub dofs: Option<toml::Value>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PrescribeSpec {
    pub select: toml::Value,
    /// Prescribed velocity [m/s] (this or `displacement`).
    #[serde(default, deserialize_with = "exact::option")]
    pub velocity: Option<V3>,
    /// Prescribed displacement [m] scaled by `curve` (or `ramp`): the nodes are at
    /// x0 + displacement * f(t) at every step (LS-DYNA VAD = 2).
    #[serde(default, deserialize_with = "exact::option")]
    pub displacement: Option<V3>,
    /// Prescribed angular velocity [rad/s] of each selected node (default: rotations
    /// held).
    #[serde(default, deserialize_with = "exact::option")]
    pub angular_velocity: Option<V3>,
    /// Ramp time from zero [s] (default 0: moving from the start).
    pub ramp: Option<f64>,
    /// A curve of `curves` that scales velocity and angular_velocity over time
    /// (instead of ramp).
    pub curve: Option<String>,
}

#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LoadSpec {
    pub select: toml::Value,
    /// Total force [N], split equally over the selected nodes.
    #[serde(default, deserialize_with = "exact::option")]
    pub force: Option<V3>,
    /// Total moment [N m], split equally over the selected nodes.
    #[serde(default, deserialize_with = "exact::option")]
    pub moment: Option<V3>,
    /// Time the load starts to rise [s] (default 0).
    pub start: Option<f64>,
    /// Rise time to full value [s] (default 0: a step).
    pub ramp: Option<f64>,
    /// A curve of `curves` that scales force and moment over time (instead of start
    /// and ramp).
    pub curve: Option<String>,
}

/// A pressure on the elements of a body (all, or `elements`), along their reference normals
/// (a dead load: direction and area of the initial configuration).
#[derive(Debug, Clone, PartialEq, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PressureSpec {
    /// Pressure [Pa]; positive pushes against the element normal (n = (x2-x1) x (x3-x1)
    /// for a triangle, the diagonals' cross product for a quad).
    pub value: f64,
    /// A curve of `curves` that scales the pressure over time (default: constant).
    pub curve: Option<String>,
    /// The elements loaded, by their ids in the body's mesh file (Gmsh element tags;
    /// a generated shape numbers its elements 1, 2, ... triangles first); default: all.
    pub elements: Option<Vec<u64>>,
}
