//! The complete example of docs/scene-format.md is a valid scene and builds as described.

use crash_core::body::dof;
use std::path::PathBuf;

fn example() -> String {
    let doc = std::fs::read_to_string(
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md"),
    )
    .expect("docs/scene-format.md");
    let after = doc.split("## Complete example").nth(1).expect("section");
    let block = after.split("```toml\n").nth(1).expect("toml block");
    block.split("```").next().expect("closed block").to_string()
}

#[test]
fn docs_complete_example_builds_as_documented() {
    let b = crash_scene::parse(&example(), "docs/scene-format.md")
        .unwrap_or_else(|e| panic!("{e}"))
        .build()
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(b.name, "example");
    assert_eq!(b.bodies.len(), 3);
    assert_eq!(b.contact.margin, 5.0e-4);
    // aluminium by its Lamé pair: E = mu (3 lambda + 2 mu) / (lambda + mu) ~ 70 GPa, nu ~ 0.33
    let al = b.bodies[0].def.section.material;
    assert!(
        (al.young - 70.0e9).abs() < 0.2e9 && (al.poisson - 0.33).abs() < 2e-3,
        "{al:?}"
    );
    // clamped short edges: 2 x 31 nodes; plus the vertically held patch
    let plate = &b.bodies[0];
    assert_eq!(
        plate.def.fixed.iter().filter(|&&f| f == dof::ALL).count(),
        62
    );
    assert!(plate.def.fixed.contains(&dof::Z));
    // the box is kinematic, starting at rest (ramp)
    assert!(b.bodies[2].def.kinematic);
    assert!(b.bodies[2].state.v.iter().all(|v| v.norm() == 0.0));
    // the pressure pulse: nodal loads on a table; they add up to -p A along z (the
    // plate lies in z = 0, its normal +z)
    let plate = &b.bodies[0].def;
    let c = plate
        .loads
        .iter()
        .find(|l| l.curve != crash_core::NO_CURVE)
        .expect("the pressure pulse")
        .curve;
    assert_eq!(plate.curves[c as usize].points.len(), 3);
    let total: f64 = plate
        .loads
        .iter()
        .filter(|l| l.curve == c)
        .map(|l| l.force.z)
        .sum();
    assert!((total + 2.0e3 * 0.5 * 0.3).abs() < 1e-9, "{total}");
}
