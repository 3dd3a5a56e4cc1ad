//! Barrier overhead of one step over gRPC on loopback: the master sends Step to every
//! worker and waits for every report, the workers hold one trivial body each (2
//! triangles), so the time is the protocol's: encode, loopback TCP, decode, compute-pool
//! hand-over, and back. Workers run as threads of this process, each with its own
//! current-thread runtime and a 1-thread compute pool, exactly as a worker process.
#![allow(clippy::unwrap_used)]

use crash_core::shapes::{plate, ElementKind};
use crash_core::{Body, Clock, Material, Section, Stabilization, Vec3};
use crash_link::{BodyLoad, Command, Reply, Setup, WorkerLink};
use crash_master::{Cluster, RemoteOptions};
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use std::time::{Duration, Instant};

fn body(id: u32) -> Body {
    let s = Section::new(Material::steel(), 0.001);
    Body::new(
        id,
        "b",
        &plate(0.01, 0.01, 1, 1, ElementKind::Tri),
        s,
        Stabilization::default(),
    )
    .unwrap()
}

fn heavy(id: u32) -> Body {
    let s = Section::new(Material::steel(), 0.001);
    Body::new(
        id,
        "h",
        &plate(0.3, 0.3, 60, 60, ElementKind::Quad),
        s,
        Stabilization::default(),
    )
    .unwrap()
}

fn cluster(n: usize) -> Cluster {
    cluster_with(n, body)
}

fn cluster_with(n: usize, make: fn(u32) -> Body) -> Cluster {
    let mut c = Cluster::bind("127.0.0.1:0".parse().unwrap(), n, RemoteOptions::default()).unwrap();
    let url = format!("http://{}", c.local_addr());
    for _ in 0..n {
        let opts = crash_worker::WorkerOptions::new(&url, 1);
        std::thread::spawn(move || {
            let _ = crash_worker::run(&opts);
        });
    }
    c.accept().unwrap();
    let setup = Setup {
        gravity: Vec3::zeros(),
        contact: Default::default(),
        reactions: false,
        probes: Default::default(),
    };
    for (i, l) in c.links_mut().iter_mut().enumerate() {
        for cmd in [
            Command::Setup(setup.clone()),
            Command::Load {
                at: Clock::default(),
                bodies: vec![BodyLoad::whole(make(i as u32))],
            },
            Command::regroup(vec![vec![i as u32]]),
            Command::Start,
        ] {
            l.send(cmd).unwrap();
            assert!(!matches!(l.recv().unwrap(), Reply::Error(_)));
        }
    }
    c
}

/// Calibration: a worker that answers every command at once with an empty report on
/// its communication thread (no decode of the command, no compute-pool hand-over): the
/// bare bidirectional-stream round trip through the same master code.
fn echo_worker(url: String) {
    use crash_proto::pb;
    use crash_proto::pb::coordinator_client::CoordinatorClient;
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .unwrap();
    rt.block_on(async move {
        let Ok(mut client) = CoordinatorClient::connect(url).await else {
            return;
        };
        let (tx, rx) = tokio::sync::mpsc::unbounded_channel();
        let Ok(resp) = client
            .attach(tokio_stream::wrappers::UnboundedReceiverStream::new(rx))
            .await
        else {
            return;
        };
        let mut inbound = resp.into_inner();
        // no secret: the Challenge's nonce is not used
        let _challenge = inbound.message().await;
        tx.send(pb::WorkerMessage {
            reply: Some(pb::worker_message::Reply::Hello(pb::Hello {
                protocol_version: crash_link::PROTOCOL_VERSION,
                threads: 1,
                host: "echo".into(),
                pid: 0,
                proof: Vec::new(),
                peer_port: 0,
                peer_host: String::new(),
            })),
        })
        .unwrap();
        let _welcome = inbound.message().await;
        let report = pb::WorkerMessage {
            reply: Some(pb::worker_message::Reply::Report(pb::Report {
                bodies: Some(pb::BodyReports::default()),
                ..Default::default()
            })),
        };
        while let Ok(Some(_)) = inbound.message().await {
            if tx.send(report.clone()).is_err() {
                break;
            }
        }
    });
}

fn echo(c: &mut Criterion) {
    let mut cl =
        Cluster::bind("127.0.0.1:0".parse().unwrap(), 1, RemoteOptions::default()).unwrap();
    let url = format!("http://{}", cl.local_addr());
    std::thread::spawn(move || echo_worker(url));
    cl.accept().unwrap();
    c.bench_function("stream_round_trip", |b| {
        b.iter(|| {
            let l = &mut cl.links_mut()[0];
            l.send(Command::Step {
                at: Clock::default(),
                dt: 1e-9,
                kin_nodes: false,
                due: crash_core::Due::ALL,
                contact: Default::default(),
                direct: false,
            })
            .unwrap();
            let Reply::Report(_) = l.recv().unwrap() else {
                panic!("not a report")
            };
        })
    });
}

fn barrier(c: &mut Criterion) {
    let mut g = c.benchmark_group("barrier_step");
    g.measurement_time(Duration::from_secs(5));
    for n in [1usize, 2, 4] {
        let mut cl = cluster(n);
        let mut clock = Clock::default();
        g.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter_custom(|iters| {
                let t = Instant::now();
                for _ in 0..iters {
                    let links = cl.links_mut();
                    for l in links.iter_mut() {
                        l.send(Command::Step {
                            at: clock,
                            dt: 1e-9,
                            kin_nodes: false,
                            due: crash_core::Due::ALL,
                            contact: Default::default(),
                            direct: false,
                        })
                        .unwrap();
                    }
                    for l in links.iter_mut() {
                        let Reply::Report(_) = l.recv().unwrap() else {
                            panic!("not a report")
                        };
                    }
                    clock = clock.after(1e-9);
                }
                t.elapsed()
            })
        });
        for l in cl.links_mut() {
            l.close("bench done");
        }
    }
    g.finish();
}

/// One worker holding a 3 600-quad plate: the step time minus the worker's own
/// compute time is the overhead when compute separates the messages.
fn loaded(c: &mut Criterion) {
    let mut cl = cluster_with(1, heavy);
    let mut clock = Clock::default();
    let mut compute = 0u64;
    let mut n = 0u64;
    c.bench_function("barrier_step_3600_quads/1", |b| {
        b.iter(|| {
            let l = &mut cl.links_mut()[0];
            l.send(Command::Step {
                at: clock,
                dt: 1e-8,
                kin_nodes: false,
                due: crash_core::Due::ALL,
                contact: Default::default(),
                direct: false,
            })
            .unwrap();
            let Reply::Report(r) = l.recv().unwrap() else {
                panic!("not a report")
            };
            compute += r.compute_ns;
            n += 1;
            clock = clock.after(1e-8);
        })
    });
    println!(
        "worker compute per step: {:.1} us",
        compute as f64 / n.max(1) as f64 * 1e-3
    );
}

criterion_group!(benches, echo, barrier, loaded);
criterion_main!(benches);
