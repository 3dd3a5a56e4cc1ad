//! Health of a master for orchestrators (docker compose healthcheck, Kubernetes): the
//! master serves the standard gRPC health service `grpc.health.v1.Health` and reports
//! SERVING for `crash.v1.Coordinator` while it runs; `crash-worker --probe URL` asks
//! it without attaching as a worker.
//!
//! The master's server runs on its loop's thread, driven while the master waits on the
//! network (for workers to attach, for step replies); while it writes a frame or a
//! checkpoint the answer waits, so a probe needs a timeout of a few seconds.

use std::time::Duration;
use tonic_health::pb::health_check_response::ServingStatus;
use tonic_health::pb::health_client::HealthClient;
use tonic_health::pb::HealthCheckRequest;

/// The service whose health the master reports.
pub const SERVICE: &str = crash_link::HEALTH_SERVICE;

/// Ask the master at `url` whether it serves `crash.v1.Coordinator`. Ok when it
/// answers SERVING within `timeout`; otherwise the reason (unreachable, no answer,
/// another status).
pub fn probe(url: &str, timeout: Duration) -> Result<(), String> {
    probe_tls(url, timeout, None)
}

/// As `probe`, for a master that serves TLS (`tls_ca`: the certificate that signed
/// its own; the URL is then https://).
pub fn probe_tls(url: &str, timeout: Duration, tls_ca: Option<&[u8]>) -> Result<(), String> {
    let rt = tokio::runtime::Builder::new_current_thread()
        .enable_all()
        .build()
        .map_err(|e| format!("tokio runtime: {e}"))?;
    let check = async {
        let endpoint = crate::client::endpoint(url, tls_ca).map_err(|e| e.to_string())?;
        let channel = endpoint
            .connect()
            .await
            .map_err(|e| format!("cannot reach the master at {url}: {e}"))?;
        let reply = HealthClient::new(channel)
            .check(HealthCheckRequest {
                service: SERVICE.to_string(),
            })
            .await
            .map_err(|s| {
                format!(
                    "the master at {url} answered the health check with an error: {}",
                    s.message()
                )
            })?;
        match ServingStatus::try_from(reply.into_inner().status) {
            Ok(ServingStatus::Serving) => Ok(()),
            Ok(s) => Err(format!(
                "the master at {url} reports {SERVICE} as {}",
                s.as_str_name()
            )),
            Err(e) => Err(format!("the master at {url} sent an unknown status: {e}")),
        }
    };
    rt.block_on(async {
        tokio::time::timeout(timeout, check).await.map_err(|_| {
            format!(
                "the master at {url} did not answer the health check within {:.1} s",
                timeout.as_secs_f64()
            )
        })?
    })
}
