//! Accepting connections with bounds on what a client can hold: at most
//! [`MAX_CONNECTIONS`] open at once (the next waits to be accepted), and a
//! request's headers must arrive within the configured `header_timeout`, so connections
//! that open and never finish a request (a slow-loris client) cannot use up
//! the server's sockets. Each connection is served by hyper with upgrades
//! (the WebSocket), and closed gracefully when the server shuts down.

use axum::Router;
use hyper_util::rt::{TokioExecutor, TokioIo, TokioTimer};
use hyper_util::server::conn::auto::Builder;
use hyper_util::service::TowerToHyperService;
use std::sync::Arc;
use std::time::Duration;
use tokio::net::TcpListener;
use tokio::sync::{watch, Semaphore};

/// Connections open at once; the rest wait in the kernel's accept queue.
/// The sessions (WebSocket, MJPEG) are bounded separately, by
/// `max_clients`.
pub const MAX_CONNECTIONS: usize = 512;

/// Serve `app` on `listener` until `stop` turns true; then stop accepting,
/// let every open connection finish its request, and return when all have
/// closed (the caller bounds that wait). Each request's headers must arrive
/// within `header_timeout`.
pub async fn serve(
    listener: TcpListener,
    app: Router,
    header_timeout: Duration,
    mut stop: watch::Receiver<bool>,
) -> std::io::Result<()> {
    let open = Arc::new(Semaphore::new(MAX_CONNECTIONS));
    let (closing, _) = watch::channel(false);
    loop {
        let permit = tokio::select! {
            p = open.clone().acquire_owned() => p.expect("the semaphore is never closed"),
            _ = stopped(&mut stop) => break,
        };
        let (tcp, _) = tokio::select! {
            accepted = listener.accept() => match accepted {
                Ok(a) => a,
                // A failed accept (the process is out of file descriptors,
                // say) concerns that connection only; pause and go on.
                Err(_) => {
                    tokio::time::sleep(Duration::from_millis(50)).await;
                    continue;
                }
            },
            _ = stopped(&mut stop) => break,
        };
        // Frames and acknowledgements go out at once (no Nagle delay): one
        // frame is in flight at a time, so a held-back tail stalls the stream.
        let _ = tcp.set_nodelay(true);
        let service = TowerToHyperService::new(app.clone());
        let mut closed = closing.subscribe();
        tokio::spawn(async move {
            let _permit = permit;
            // hyper's header timeout starts at a request's first byte: a
            // connection that sends nothing is closed here instead.
            // (A peek, not `readable`, whose readiness can be a stale one.)
            let mut first = [0u8; 1];
            if !matches!(
                tokio::time::timeout(header_timeout, tcp.peek(&mut first)).await,
                Ok(Ok(1))
            ) {
                return;
            }
            // HTTP/1 only: telling HTTP/2 apart would wait for a first byte
            // with no timer, so a connection sending nothing would be kept.
            let mut builder = Builder::new(TokioExecutor::new()).http1_only();
            builder
                .http1()
                .timer(TokioTimer::new())
                .header_read_timeout(header_timeout);
            let conn = builder.serve_connection_with_upgrades(TokioIo::new(tcp), service);
            tokio::pin!(conn);
            tokio::select! {
                _ = conn.as_mut() => return,
                _ = stopped(&mut closed) => conn.as_mut().graceful_shutdown(),
            }
            let _ = conn.await;
        });
    }
    drop(listener);
    closing.send_replace(true);
    // Every connection holds a permit until it closes.
    let _all = open.acquire_many(MAX_CONNECTIONS as u32).await;
    Ok(())
}

/// Returns when `flag` turns true (or its sender is gone).
async fn stopped(flag: &mut watch::Receiver<bool>) {
    let _ = flag.wait_for(|s| *s).await;
}
