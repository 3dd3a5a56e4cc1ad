//! The scenarios of the stability matrix. Contact scenarios are written as scene files
//! and go through the same path as `crash run` (parse, build, overlap check, master
//! loop); the free-plate scenarios build bodies directly to reach what a scene refuses
//! (a time step above the critical one) or to meet the mesh check head-on.

use super::build::body;
use super::outcome::{refused, run_and_classify, run_and_classify_guarded, Outcome, PassGuard};
use crash_core::contact::ContactConfig;
use crash_core::shapes::{plate, ElementKind};
use crash_core::{Material, RunConfig, Vec3};
use crash_master::RunInput;

/// A steel sphere (R = 50 mm, icosphere level 3) dropped onto a clamped 0.2 m steel
/// plate (t = 2 mm, 10 x 10·aspect quads).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Drop {
    pub penalty: &'static str,
    pub scale: f64,
    /// R / t of the sphere.
    pub r_over_t: f64,
    pub nu: f64,
    pub speed: f64,
    /// `dt_safety` written in the scene.
    pub safety: f64,
    /// Safety factor set on the run after the scene is built (bypasses the scene check).
    pub forced_safety: Option<f64>,
    pub margin: Option<f64>,
    /// Aspect ratio of the plate's cells.
    pub aspect: u32,
}

impl Default for Drop {
    fn default() -> Self {
        Self {
            penalty: "soft",
            scale: 0.1,
            r_over_t: 50.0,
            nu: 0.3,
            speed: 2.0,
            safety: 0.9,
            forced_safety: None,
            margin: None,
            aspect: 1,
        }
    }
}

const R: f64 = 0.05;
const TP: f64 = 0.002;

impl Drop {
    /// Contact duration estimate pi sqrt(m / k) of the sphere on a rigid plane.
    fn duration(&self) -> f64 {
        let t = R / self.r_over_t;
        let m = 4.0 * std::f64::consts::PI * R * R * t * 7800.0;
        let nu = self.nu.clamp(0.0, 0.49);
        let k = 4.0 * 200e9 * t * t / (R * (3.0 * (1.0 - nu * nu)).sqrt());
        std::f64::consts::PI * (m / k).sqrt()
    }

    pub fn scene(&self) -> String {
        let t = R / self.r_over_t;
        let gap = 2e-4 * self.speed.min(1.0);
        let end = gap / self.speed + (2.0 * self.duration()).min(0.5 * R / self.speed);
        let margin = self
            .margin
            .map_or(String::new(), |m| format!("margin = {m:e}\n"));
        format!(
            r#"name = "stability-drop"
end_time = {end:e}
dt_safety = {safety}

[contact]
penalty = "{penalty}"
penalty_scale = {scale:e}
{margin}
[materials.steel]
density = 7800.0
young = 200.0e9
poisson = {nu}

[[bodies]]
name = "plate"
material = "steel"
thickness = {TP:e}
plate = {{ size = [0.2, 0.2], cells = [10, {ny}] }}

[[bodies.fix]]
select = ["x-", "x+", "y-", "y+"]
dofs = "all"

[[bodies]]
name = "sphere"
material = "steel"
thickness = {t:e}
sphere = {{ radius = {R:e}, level = 3 }}
position = [0.0, 0.0, {z:e}]
velocity = [0.0, 0.0, {v:e}]
"#,
            safety = self.safety,
            penalty = self.penalty,
            scale = self.scale,
            nu = self.nu,
            ny = 10 * self.aspect,
            z = R + 0.5 * (t + TP) + gap,
            v = -self.speed,
        )
    }

    pub fn run(&self) -> Outcome {
        run_scene(&self.scene(), self.forced_safety)
    }
}

/// Two steel spheres (R = 50 mm, t = 1 mm, level 3) head-on: the left one, `ratio` times
/// denser, at 2 m/s onto the right one at rest.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HeadOn {
    pub mass_ratio: f64,
}

impl HeadOn {
    pub fn scene(&self) -> String {
        let t = 1e-3;
        let x = R + 0.5 * t + 2.5e-4;
        format!(
            r#"name = "stability-head-on"
end_time = 1.5e-3

[materials.heavy]
density = {rho:e}
young = 200.0e9
poisson = 0.3

[materials.steel]
density = 7800.0
young = 200.0e9
poisson = 0.3

[[bodies]]
name = "heavy"
material = "heavy"
thickness = {t:e}
sphere = {{ radius = {R:e}, level = 3 }}
position = [{xl:e}, 0.0, 0.0]
velocity = [2.0, 0.0, 0.0]

[[bodies]]
name = "light"
material = "steel"
thickness = {t:e}
sphere = {{ radius = {R:e}, level = 3 }}
position = [{x:e}, 0.0, 0.0]
"#,
            rho = 7800.0 * self.mass_ratio,
            xl = -x,
        )
    }

    pub fn run(&self) -> Outcome {
        run_scene(&self.scene(), None)
    }
}

/// Parse, build and check a scene as `crash run` does, then run it.
/// A thin steel tube (R = 25 mm, length 60 mm, 32 x 12 cells, triangles or quads)
/// thrown sideways at `speed` onto a fixed steel plate (0.12 m, t = 1 mm, 24 x 24 cells
/// of the same kind, every node held), run until it has travelled 1.5 diameters (or
/// 0.3 ms at low speed): the speed x thickness x element-kind matrix of issue 12. A
/// completed run is checked for a pass-through: no tube node over the plate may end
/// below the plate's mid-surface.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Thrown {
    pub speed: f64,
    /// Tube wall thickness [m].
    pub t: f64,
    pub kind: ElementKind,
    /// Run under the segment contact pass (`contact.pass = "segments"`) instead of the
    /// node passes.
    pub segments: bool,
    /// Under the segment pass, one way whatever the meshes (`contact.sides =
    /// "finer"`) instead of the default `"auto"` (both ways here: the tube's and the
    /// plate's segments are of about one size).
    pub one_side: bool,
}

const TUBE_R: f64 = 0.025;
const THROWN_PLATE: f64 = 0.12;

impl Thrown {
    pub fn scene(&self) -> String {
        let tp = 1e-3;
        let kind = match self.kind {
            ElementKind::Tri => "tri",
            ElementKind::Quad => "quad",
        };
        let gap = 1e-4;
        let end = (gap + 3.0 * TUBE_R) / self.speed;
        let end = end.min(3e-4);
        let contact = match (self.segments, self.one_side) {
            (true, true) => "\n[contact]\npass = \"segments\"\nsides = \"finer\"\n",
            (true, false) => "\n[contact]\npass = \"segments\"\n",
            (false, _) => "",
        };
        format!(
            r#"name = "matrix-thrown"
end_time = {end:e}
output_interval = {out:e}
{contact}
[materials.steel]
density = 7800.0
young = 200.0e9
poisson = 0.3

[[bodies]]
name = "plate"
material = "steel"
thickness = {tp:e}
element = "{kind}"
plate = {{ size = [{THROWN_PLATE:e}, {THROWN_PLATE:e}], cells = [24, 24] }}

[[bodies.fix]]
select = "all"
dofs = "all"

[[bodies]]
name = "tube"
material = "steel"
thickness = {t:e}
element = "{kind}"
cylinder = {{ radius = {TUBE_R:e}, length = 0.06, cells = [32, 12] }}
rotation = {{ axis = [1.0, 0.0, 0.0], angle = 90.0 }}
position = [0.0, 0.0, {z:e}]
velocity = [0.0, 0.0, {v:e}]
"#,
            out = end / 4.0,
            t = self.t,
            z = TUBE_R + 0.5 * (self.t + tp) + gap,
            v = -self.speed,
        )
    }

    pub fn run(&self) -> Outcome {
        let built = match crash_scene::parse(&self.scene(), "matrix.toml").and_then(|s| s.build()) {
            Ok(b) => b,
            Err(e) => return refused(e),
        };
        if let Some(p) = crash_scene::check_initial_overlap(&built.bodies, &built.contact) {
            return refused(crate::run::penetration_message(&built, &p));
        }
        let limit = built.energy_limit;
        let guard = PassGuard {
            body: 1,
            half_size: 0.5 * THROWN_PLATE,
            z: 0.0,
        };
        run_and_classify_guarded(RunInput::from_built(built), limit, Some(guard))
    }
}

pub fn run_scene(text: &str, forced_safety: Option<f64>) -> Outcome {
    let built = match crash_scene::parse(text, "stability.toml").and_then(|s| s.build()) {
        Ok(b) => b,
        Err(e) => return refused(e),
    };
    if let Some(p) = crash_scene::check_initial_overlap(&built.bodies, &built.contact) {
        return refused(crate::run::penetration_message(&built, &p));
    }
    let limit = built.energy_limit;
    let mut input = RunInput::from_built(built);
    if let Some(s) = forced_safety {
        input.config.safety = s;
    }
    run_and_classify(input, limit)
}

/// A free steel plate (default 0.2 x 0.1 m, 8 x 4 quads), t = 2 mm, in free vibration
/// (a transverse velocity pattern of 0.5 m/s), whose interior nodes are slightly shuffled so
/// that no symmetry hides a mode (as in crash-core's stability tests).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FreePlate {
    pub kind: ElementKind,
    /// Plate size [m].
    pub size: (f64, f64),
    pub kelvin: f64,
    pub safety: f64,
    pub cells: (usize, usize),
    /// Lift of the centre node as a fraction of the cell size (warped quads).
    pub warp: f64,
    pub end_time: f64,
}

impl Default for FreePlate {
    fn default() -> Self {
        Self {
            kind: ElementKind::Quad,
            size: (0.2, 0.1),
            kelvin: 0.0,
            safety: 0.9,
            cells: (8, 4),
            warp: 0.0,
            end_time: 5e-3,
        }
    }
}

impl FreePlate {
    pub fn run(&self) -> Outcome {
        let (nx, ny) = self.cells;
        let (lx, ly) = self.size;
        let mut m = plate(lx, ly, nx, ny, self.kind);
        for (i, p) in m.nodes.iter_mut().enumerate() {
            let s = ((i * 7919) % 13) as f64 / 13.0 - 0.5;
            if p.x.abs() < 0.495 * lx && p.y.abs() < 0.49 * ly {
                p.x += 0.15 * s * lx / nx as f64;
                p.y -= 0.1 * s * ly / ny as f64;
            }
        }
        if self.warp > 0.0 {
            if let Some(c) =
                (0..m.nodes.len()).min_by(|&a, &b| m.nodes[a].norm().total_cmp(&m.nodes[b].norm()))
            {
                m.nodes[c].z += self.warp * lx / nx as f64;
            }
        }
        let mat = match Material::new(7800.0, 200e9, 0.3, self.kelvin) {
            Ok(m) => m,
            Err(e) => return refused(e),
        };
        let mut b = match body(0, &m, mat, 0.002) {
            Ok(b) => b,
            Err(e) => return refused(e),
        };
        for i in 0..b.state.x.len() {
            let p = b.def.x0[i];
            b.state.v[i] = Vec3::new(
                0.0,
                0.0,
                0.5 * (std::f64::consts::PI * p.x / lx).cos() * (p.y / ly),
            );
        }
        let input = RunInput {
            name: "free-plate".into(),
            briefs: vec![crash_core::BodyBrief::of(&b)],
            bodies: crash_master::BodySource::Built(vec![Some(b)]),
            gravity: Vec3::zeros(),
            contact: ContactConfig::default(),
            config: RunConfig {
                end_time: self.end_time,
                safety: self.safety,
                ..Default::default()
            },
            output_interval: self.end_time / 4.0,
            scene_hash: 0,
            results: Default::default(),
        };
        run_and_classify(input, crash_scene::globals::DEFAULT_ENERGY_LIMIT)
    }
}
