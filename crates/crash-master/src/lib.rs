//! crash-master: the global time loop of a distributed run.
//!
//! The master holds the MEIM (bodies and their possible contacts, a petgraph
//! StableGraph), groups bodies into its connected components, places groups on workers
//! (balanced, sticky), drives the step barrier, chooses the global time step exactly as
//! the single-process driver does, migrates bodies between workers and merges the
//! workers' data into one view for output.
//!
//! The same loop drives in-process workers ([`run_local`], no network, no
//! serialization) and worker processes over gRPC ([`remote::Cluster`], [`run_remote`]).
//! Architecture: docs/architecture-cluster.md.

pub mod assign;
pub mod error;
pub mod file_sink;
pub mod input;
pub mod link;
mod master;
pub mod meim;
pub mod pairs;
pub mod remote;
pub mod sink;
pub mod stats;

pub use error::MasterError;
pub use file_sink::FileSink;
pub use input::{CostModel, RunInput, RunOptions};
pub use link::{LinkError, LocalWorker, WorkerLink};
pub use remote::{Cluster, RemoteOptions, RemoteWorker};
pub use sink::{EnergyRecord, RecordSink, Sink, SinkError};
pub use stats::{Migration, RunStats, StageTimes};

use master::Master;
use std::time::Instant;

/// Run a scene on the given workers (any `WorkerLink`): start, step to the end time,
/// final frame. On any error the workers are told to stop, the sink is told why (the
/// frames already written are the last complete ones), and the error is returned.
pub fn run_with<L: WorkerLink>(
    input: RunInput,
    links: &mut [L],
    sink: &mut dyn Sink,
    opts: &RunOptions,
) -> Result<RunStats, MasterError> {
    let wall = Instant::now();
    let mut m = match Master::new(links, &input, *opts) {
        Ok(m) => m,
        Err(e) => {
            let _ = sink.finish(&RunStats::default(), Some(&e));
            return Err(e);
        }
    };
    let RunInput {
        bodies, gravity, ..
    } = input;
    let result = (|| {
        m.start(bodies, gravity, sink)?;
        while !m.finished() {
            m.step(sink)?;
        }
        m.finish(sink)
    })();
    m.stats.wall_s = wall.elapsed().as_secs_f64();
    match result {
        Ok(()) => {
            m.shutdown("the run is complete");
            sink.finish(&m.stats, None)
                .map_err(|e| MasterError::Sink(e.to_string()))?;
            Ok(m.stats.clone())
        }
        Err(e) => {
            tracing::error!("run stopped: {e}");
            m.shutdown(&format!("the run stopped: {e}"));
            m.stats.final_hash = 0;
            let _ = sink.finish(&m.stats, Some(&e));
            Err(e)
        }
    }
}

/// Local mode: the same master loop over `workers` in-process workers.
pub fn run_local(
    input: RunInput,
    workers: usize,
    sink: &mut dyn Sink,
    opts: &RunOptions,
) -> Result<RunStats, MasterError> {
    let mut links: Vec<LocalWorker> = (0..workers.max(1)).map(LocalWorker::new).collect();
    run_with(input, &mut links, sink, opts)
}

/// Remote mode: the master loop over the worker processes attached to `cluster`.
pub fn run_remote(
    input: RunInput,
    cluster: &mut Cluster,
    sink: &mut dyn Sink,
    opts: &RunOptions,
) -> Result<RunStats, MasterError> {
    run_with(input, cluster.links_mut(), sink, opts)
}
