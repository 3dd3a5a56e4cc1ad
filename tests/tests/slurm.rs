//! The Slurm recipe (deploy/slurm/crash.sbatch), without Slurm: rendered for a node
//! list (CRASH_DRY_RUN=1 prints the commands it would run), and run here with
//! stand-ins for srun and scontrol (deploy/slurm/test-local.sh).
#![allow(clippy::unwrap_used)]

use std::path::PathBuf;
use std::process::Command;

fn repo() -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("..")
}

/// The recipe's dry run for this allocation: its lines by their label.
fn render(nodelist: &str, cpus_per_task: &str, env: &[(&str, &str)]) -> Vec<(String, String)> {
    let out = Command::new("bash")
        .current_dir(repo())
        .arg("deploy/slurm/crash.sbatch")
        .args(["scenes/ten-spheres-three-plates.toml", "out/ten"])
        .env("CRASH_DRY_RUN", "1")
        .env("SLURM_JOB_ID", "42")
        .env("SLURM_JOB_NODELIST", nodelist)
        .env("SLURM_CPUS_PER_TASK", cpus_per_task)
        .env("SLURM_SUBMIT_DIR", "/shared/crash")
        .env_remove("CRASH_THREADS")
        .env_remove("CRASH_MASTER_ADDR")
        .env_remove("CRASH_PORT")
        .env_remove("CRASH_WORKER_ON_MASTER_NODE")
        .envs(env.iter().copied())
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout).into_owned();
    assert!(
        out.status.success(),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
    text.lines()
        .filter_map(|l| l.split_once(": "))
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect()
}

fn get<'a>(lines: &'a [(String, String)], key: &str) -> Vec<&'a str> {
    lines
        .iter()
        .filter(|(k, _)| k == key)
        .map(|(_, v)| v.as_str())
        .collect()
}

/// node[01-03] with 8 CPUs per task: one master on node01, one srun step of one
/// worker per node (3 tasks, 8 CPUs and 8 threads each) dialling node01, and the
/// master waiting for exactly those 3 workers.
#[test]
fn the_recipe_runs_one_master_and_one_worker_per_node_with_the_tasks_cpus_as_threads() {
    let l = render("node[01-03]", "8", &[]);
    assert_eq!(get(&l, "nodes"), ["node01 node02 node03"]);
    assert_eq!(get(&l, "worker nodes"), ["node01 node02 node03"]);
    let workers = get(&l, "workers");
    assert_eq!(workers.len(), 1, "one srun step: {l:?}");
    assert_eq!(
        workers[0],
        "srun --nodes=3 --ntasks=3 --ntasks-per-node=1 --cpus-per-task=8 --overlap \
         /shared/crash/target/release/crash-worker --master http://node01:50051 --threads 8"
    );
    assert_eq!(
        get(&l, "master"),
        [
            "/shared/crash/target/release/crash-master scenes/ten-spheres-three-plates.toml \
          --listen 0.0.0.0:50051 --workers 3 --out out/ten"
        ]
    );
}

/// Slurm's host-list forms: ranges and lists in brackets, zero padding, several
/// bracket groups, plain names; "32(x4)" CPU counts; the options that change the
/// addresses, the thread count and where workers run.
#[test]
fn the_recipe_expands_slurm_node_lists_and_follows_its_settings() {
    let l = render("gpu[8-10,012],r[1-2]-n[08-09],login", "32(x4)", &[]);
    assert_eq!(
        get(&l, "nodes"),
        ["gpu8 gpu9 gpu10 gpu012 r1-n08 r1-n09 r2-n08 r2-n09 login"]
    );
    let w = get(&l, "workers")[0];
    assert!(
        w.starts_with("srun --nodes=9 --ntasks=9 --ntasks-per-node=1 --cpus-per-task=32 "),
        "{w}"
    );
    assert!(
        w.ends_with("--master http://gpu8:50051 --threads 32"),
        "{w}"
    );
    assert!(get(&l, "master")[0].contains("--workers 9 "));

    let l = render(
        "node[01-03]",
        "8",
        &[
            ("CRASH_WORKER_ON_MASTER_NODE", "0"),
            ("CRASH_MASTER_ADDR", "node01-ib"),
            ("CRASH_PORT", "6000"),
            ("CRASH_THREADS", "6"),
            ("CRASH_END_TIME", "2e-3"),
        ],
    );
    assert_eq!(get(&l, "worker nodes"), ["node02 node03"]);
    let w = get(&l, "workers")[0];
    assert!(w.starts_with("srun --nodes=2 --ntasks=2 --ntasks-per-node=1 --cpus-per-task=8 --overlap --exclude=node01 "), "{w}");
    assert!(
        w.ends_with("--master http://node01-ib:6000 --threads 6"),
        "{w}"
    );
    let m = get(&l, "master")[0];
    assert!(
        m.contains("--listen 0.0.0.0:6000 --workers 2 --out out/ten --end-time 2e-3"),
        "{m}"
    );
}

/// The recipe run here (srun and scontrol stand-ins, 3 "nodes" on 127.0.0.1): 3
/// workers attach and the run ends with `crash run`'s final state hash.
#[test]
fn the_recipe_runs_here_with_stand_ins_and_matches_crash_run() {
    let crash = PathBuf::from(crash_tests::procs::bin("crash"));
    crash_tests::procs::master_bin();
    crash_tests::procs::worker_bin();
    let out = Command::new("bash")
        .current_dir(repo())
        .arg("deploy/slurm/test-local.sh")
        .env("CRASH_BIN", crash.parent().unwrap())
        .env_remove("CRASH_SECRET")
        .output()
        .unwrap();
    let text = String::from_utf8_lossy(&out.stdout);
    assert!(
        out.status.success() && text.contains("slurm-local: PASS"),
        "{text}{}",
        String::from_utf8_lossy(&out.stderr)
    );
}
