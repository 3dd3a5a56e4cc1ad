//! End to end: `crash run` on the seed's first benchmark at a reduced size (the
//! sphere-on-plate-small scene, run long enough for the whole contact): the run
//! finishes, the sphere rebounds, the energy balance holds within 2%, and the pictures
//! exist and are not blank.

use std::collections::HashSet;
use std::path::Path;
use std::process::Command;

fn scene(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../scenes")
        .join(name)
}

#[test]
fn sphere_on_plate_rebounds_with_energy_balance_and_pictures() {
    let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join("e2e-sphere-on-plate");
    let _ = std::fs::remove_dir_all(&out);
    let status = Command::new(env!("CARGO_BIN_EXE_crash"))
        .arg("run")
        .arg(scene("sphere-on-plate-small.toml"))
        .args([
            "--end-time",
            "3.5e-3",
            "--output-interval",
            "2.5e-4",
            "--quiet",
            "--threads",
            "2",
            "--out",
        ])
        .arg(&out)
        .status()
        .expect("crash runs");
    assert!(status.success(), "crash run failed: {status}");

    let summary = crash_io::read_summary(out.join(crash_io::SUMMARY_JSON)).expect("summary");
    println!(
        "largest energy-balance error {:.3e}",
        summary.energy_balance_error
    );
    assert!(summary.energy_balance_error < 0.02);
    assert!(summary.fault.is_none());

    // the sphere (body 1) moves up at the end: it rebounded
    let entries = crash_io::read_pvd(&out.join(crash_io::PVD_FILE)).expect("pvd");
    let last = entries.last().expect("frames");
    let frame = crash_io::read_vtu(&out.join(&last.file)).expect("last frame");
    let sphere = frame.bodies.iter().find(|b| b.id == 1).expect("sphere");
    let vz = sphere.v.iter().map(|v| v.z).sum::<f64>() / sphere.v.len() as f64;
    println!(
        "sphere mean vertical velocity at t = {:.3e} s: {vz:.3} m/s (impact at -5 m/s)",
        last.time
    );
    assert!(vz > 1.0, "the sphere did not rebound: {vz} m/s");

    // contact history has the pair (plate, sphere) with a positive force
    let contacts =
        crash_io::read_contacts_csv(out.join(crash_io::CONTACTS_CSV)).expect("contacts.csv");
    assert!(contacts
        .iter()
        .any(|r| r.a == 0 && r.b == 1 && r.force > 0.0));

    // pictures exist and are not blank
    let pictures = out.join("pictures");
    // (the contact views and the contact-force plot exist because the sphere touched)
    let names = [
        "sheet.png",
        "energy.png",
        "energies.png",
        "contact_force.png",
        "below.png",
        "section.png",
        "frame_000000.png",
    ];
    for name in names {
        let img = crash_io::render::image::load_png(pictures.join(name)).expect(name);
        let colours: HashSet<[u8; 3]> = img.rgb.chunks(3).map(|c| [c[0], c[1], c[2]]).collect();
        println!(
            "{name}: {}x{}, {} colours",
            img.width,
            img.height,
            colours.len()
        );
        assert!(colours.len() > 20, "{name} looks blank");
    }
}
