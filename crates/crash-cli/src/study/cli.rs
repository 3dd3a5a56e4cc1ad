//! The `crash study` command line.

use super::cases::CASES;
use super::matrix::run_matrix;
use super::outcome::Outcome;
use super::report::{self, RunNote};
use super::stability_report;
use super::verify::{run_suite, Selection};
use std::path::PathBuf;
use std::process::ExitCode;

/// Which suite `crash study` runs.
#[derive(clap::ValueEnum, Debug, Clone, Copy, PartialEq, Eq)]
pub enum Suite {
    /// Refinement ladders against references: docs/verification.md.
    Verification,
    /// Stiff and extreme cases: docs/stability.md.
    Stability,
    /// Both.
    All,
}

#[derive(clap::Args, Debug)]
pub struct StudyArgs {
    /// What to run.
    #[arg(value_enum, default_value_t = Suite::Verification)]
    pub suite: Suite,
    /// Small ladders and a representative slice of the stability matrix (a few minutes).
    #[arg(long)]
    pub quick: bool,
    /// Run only these verification cases (ids as listed in docs/verification.md).
    #[arg(long, value_delimiter = ',')]
    pub only: Vec<String>,
    /// Where the reports go (figures in DOCS/figures) [default: docs; with --quick
    /// nothing is written unless DOCS is given, so a quick run never replaces the full
    /// reports].
    #[arg(long)]
    pub docs: Option<PathBuf>,
    /// Do not write the reports, only check.
    #[arg(long)]
    pub no_write: bool,
    /// Threads for the element loops (wall times in the report are for this count).
    #[arg(long, default_value_t = 1)]
    pub threads: usize,
}

/// Exit code when a case misses its tolerance or order, or a stability cell blows up
/// silently.
pub const EXIT_STUDY_FAILED: u8 = 4;

pub fn study(args: &StudyArgs) -> anyhow::Result<ExitCode> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(args.threads.max(1))
        .build()?;
    let docs = match (&args.docs, args.quick || args.no_write) {
        (Some(d), _) if !args.no_write => Some(d.clone()),
        (None, false) => Some(PathBuf::from("docs")),
        _ => None,
    };
    if let Some(bad) = args
        .only
        .iter()
        .find(|o| !CASES.iter().any(|c| c.id == o.as_str()))
    {
        anyhow::bail!(
            "unknown verification case '{bad}'; the cases are: {}",
            CASES.iter().map(|c| c.id).collect::<Vec<_>>().join(", ")
        );
    }
    pool.install(|| {
        let sel = Selection {
            quick: args.quick,
            only: args.only.clone(),
        };
        let mut failed = false;
        if matches!(args.suite, Suite::Verification | Suite::All) {
            let start = std::time::Instant::now();
            let res = run_suite(&sel, |l| eprintln!("{l}"));
            if let Some(docs) = &docs {
                let note = RunNote {
                    quick: args.quick,
                    threads: args.threads.max(1),
                    total_wall_s: start.elapsed().as_secs_f64(),
                };
                for f in report::write(docs, &res, &note)? {
                    println!("{}", f.display());
                }
            }
            for r in &res {
                for p in r.problems() {
                    eprintln!("crash study: FAIL {p}");
                    failed = true;
                }
            }
        }
        if matches!(args.suite, Suite::Stability | Suite::All) {
            let res = run_matrix(args.quick, |r| {
                eprintln!(
                    "{} = {}: {} ({:.2} s){}",
                    r.cell.axis,
                    r.cell.value,
                    r.outcome.short(),
                    r.wall_s,
                    match &r.outcome {
                        Outcome::Stable {
                            max_error,
                            max_penetration,
                            ..
                        } => format!(
                            ", energy error {max_error:.2e}, penetration/t {max_penetration:.3}"
                        ),
                        Outcome::Stopped { message, .. } => format!(": {message}"),
                        Outcome::SilentBlowUp { reason } => format!(": {reason}"),
                    }
                )
            });
            if let Some(docs) = &docs {
                std::fs::create_dir_all(docs)?;
                let path = docs.join("stability.md");
                std::fs::write(
                    &path,
                    stability_report::markdown(&res, args.quick, args.threads.max(1)),
                )?;
                println!("{}", path.display());
            }
            for r in res.iter().filter(|r| !r.as_expected()) {
                eprintln!(
                    "crash study: FAIL {} = {}: {} (expected {:?})",
                    r.cell.axis,
                    r.cell.value,
                    r.outcome.short(),
                    r.cell.expect
                );
                failed = true;
            }
        }
        Ok(if failed {
            ExitCode::from(EXIT_STUDY_FAILED)
        } else {
            ExitCode::SUCCESS
        })
    })
}
