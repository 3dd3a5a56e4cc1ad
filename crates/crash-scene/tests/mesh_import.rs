//! Scenes with imported Gmsh meshes: the path is relative to the scene file, errors in
//! the mesh name the mesh file's own line, and the geometry checks reach into the file.

mod common;

use common::*;
use crash_core::Vec3;
use crash_scene::ErrorKind;
use std::path::PathBuf;

/// Two triangles (tags 7, 8) and a quad (tag 9) over the rectangle [0, 2] x [0, 1].
const MSH: &str = "$MeshFormat
4.1 0 8
$EndMeshFormat
$Nodes
1 6 1 6
2 1 0 6
1
2
3
4
5
6
0 0 0
1 0 0
1 1 0
0 1 0
2 0 0
2 1 0
$EndNodes
$Elements
2 3 7 9
2 1 2 2
7 1 2 3
8 1 3 4
2 1 3 1
9 2 5 6 3
$EndElements
";

const SCENE: &str = r#"end_time = 1.0e-3

[materials.steel]
density = 7800.0
young = 200.0e9
poisson = 0.3

[[bodies]]
name = "part"
material = "steel"
thickness = 0.01
mesh = { file = "meshes/part.msh", scale = 0.5 }
"#;

/// Write the scene and its mesh into a fresh directory; returns the scene path.
fn files(test: &str, scene: &str, msh: &str) -> PathBuf {
    let dir = temp_dir(test);
    std::fs::create_dir_all(dir.join("meshes")).expect("mkdir");
    std::fs::write(dir.join("meshes/part.msh"), msh).expect("write msh");
    let p = dir.join("scene.toml");
    std::fs::write(&p, scene).expect("write scene");
    p
}

fn load_error(p: &std::path::Path) -> crash_scene::SceneError {
    match crash_scene::load(p).and_then(|s| s.build()) {
        Ok(_) => panic!("accepted"),
        Err(e) => e,
    }
}

#[test]
fn imported_mesh_is_found_relative_to_the_scene_and_scaled() {
    let p = files("ok", SCENE, MSH);
    let b = crash_scene::load(&p)
        .expect("valid")
        .build()
        .expect("builds");
    let body = &b.bodies[0];
    assert_eq!(
        (body.def.tris.len(), body.def.quads.len(), body.node_count()),
        (2, 1, 6)
    );
    // scale 0.5: the rectangle becomes 1 x 0.5 m, mass = rho t A
    assert!((body.total_mass() - 7800.0 * 0.01 * 0.5).abs() < 1e-9);
    assert_eq!(body.def.x0[4], Vec3::new(1.0, 0.0, 0.0));
}

#[test]
fn element_tri_splits_imported_quads() {
    let p = files(
        "split",
        &SCENE.replace("thickness = 0.01", "thickness = 0.01\nelement = \"tri\""),
        MSH,
    );
    let b = crash_scene::load(&p)
        .expect("valid")
        .build()
        .expect("builds");
    assert_eq!(
        (b.bodies[0].def.tris.len(), b.bodies[0].def.quads.len()),
        (4, 0)
    );
    assert!((b.bodies[0].total_mass() - 7800.0 * 0.01 * 0.5).abs() < 1e-9);
}

#[test]
fn element_quad_with_imported_triangles_is_refused() {
    let p = files(
        "quad",
        &SCENE.replace("thickness = 0.01", "thickness = 0.01\nelement = \"quad\""),
        MSH,
    );
    let e = load_error(&p);
    check(
        &e,
        ErrorKind::Invalid,
        12,
        11,
        "bodies[0].element",
        &["cannot become quads"],
    );
}

#[test]
fn missing_mesh_file_is_a_read_error_at_the_file_key() {
    let p = files(
        "missing",
        &SCENE.replace("meshes/part.msh", "meshes/nothere.msh"),
        MSH,
    );
    let e = load_error(&p);
    check(
        &e,
        ErrorKind::Read,
        12,
        17,
        "bodies[0].mesh.file",
        &["nothere.msh", "cannot read"],
    );
}

#[test]
fn malformed_mesh_file_names_its_own_line() {
    let p = files("bad", SCENE, &MSH.replace("9 2 5 6 3", "9 2 5 6 42"));
    let e = load_error(&p);
    check(
        &e,
        ErrorKind::MeshFile,
        12,
        17,
        "bodies[0].mesh.file",
        &["meshes/part.msh:26: element 9 refers to node 42", "node 42"],
    );
}

#[test]
fn degenerate_element_in_mesh_file_names_its_tag_and_line() {
    // element 8 becomes (1, 3, 3): zero area
    let p = files("degenerate", SCENE, &MSH.replace("8 1 3 4", "8 1 3 3"));
    let e = load_error(&p);
    check(
        &e,
        ErrorKind::Geometry,
        12,
        17,
        "bodies[0].mesh.file",
        &["meshes/part.msh:24: element tag 8", "degenerate"],
    );
}

#[test]
fn warped_quad_in_mesh_file_is_refused_with_its_tag() {
    // lift node 6 (a corner of quad 9) out of the plane by 0.3 m
    let p = files(
        "warped",
        SCENE,
        &MSH.replace("2 1 0\n$EndNodes", "2 1 0.3\n$EndNodes"),
    );
    let e = load_error(&p);
    check(
        &e,
        ErrorKind::Geometry,
        12,
        17,
        "bodies[0].mesh.file",
        &["element tag 9", "warped", "split it into triangles"],
    );
}

#[test]
fn scene_hash_covers_the_mesh_file() {
    let a = crash_scene::load(&files("hash-a", SCENE, MSH))
        .expect("v")
        .build()
        .expect("b");
    let moved = MSH.replace("2 1 0\n$EndNodes", "2 1.01 0\n$EndNodes");
    let b = crash_scene::load(&files("hash-b", SCENE, &moved))
        .expect("v")
        .build()
        .expect("b");
    assert_ne!(a.scene_hash, b.scene_hash);
    let mut h = crash_core::hash::Fnv::default();
    h.bytes(SCENE.as_bytes());
    h.bytes(MSH.as_bytes());
    assert_eq!(a.scene_hash, h.finish());
}
