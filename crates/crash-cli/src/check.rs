//! `crash check SCENE`: validate and print what a run would do, without running.

use anyhow::Context;
use std::path::Path;

/// Cost of one element-cycle of the whole step on one core [ns], the range measured on
/// the project's machines (docs/performance.md: 42-60 ns on the fastest host, the
/// showcase and the OpenRadioss models; 170 on the slowest, the showcase in session
/// 19); used only for the run-time estimate.
const NS_PER_ELEMENT_CYCLE: (f64, f64) = (40.0, 170.0);

pub fn check(path: &Path, deck: &crash_scene::keyword::DeckOptions) -> anyhow::Result<()> {
    let scene = crash_scene::load_input(path, deck)?;
    let built = scene.build()?;
    for n in &built.notes {
        match n.strip_prefix("warning: ") {
            Some(w) => println!("warning: {w}"),
            None => println!("note: {n}"),
        }
    }
    if let Some(p) = crash_scene::check_initial_overlap(&built.bodies, &built.contact) {
        anyhow::bail!("{}", crate::run::penetration_message(&built, &p));
    }
    let summary = built.summary();
    println!("{summary}");
    let cycles = summary.elements as f64 * summary.steps_estimate as f64;
    let (fast, slow) = NS_PER_ELEMENT_CYCLE;
    println!(
        "estimated run time on one core: {:.0} to {:.0} s ({:.2e} element-cycles at {fast:.0} to {slow:.0} ns, by CPU)",
        cycles * fast * 1e-9,
        cycles * slow * 1e-9,
        cycles
    );
    built
        .critical_dt()
        .map(|(dt, body, element)| {
            println!("critical element: body {body}, element {element} (dt {dt:.4e} s)")
        })
        .context("the first force pass failed")?;
    Ok(())
}
