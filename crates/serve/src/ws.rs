//! The WebSocket endpoint: hello, then frames from the session's render loop
//! one way and validated, rate-limited client messages the other.

use crate::app::{AppState, ClientGuard};
use crate::protocol::{CameraJson, ClientMessage, Envelope};
use crate::session::{render_loop, Outgoing};
use crate::sync::lock;
use axum::extract::ws::{CloseFrame, Message, WebSocket, WebSocketUpgrade};
use axum::extract::State;
use axum::response::{IntoResponse, Response};
use futures_util::{SinkExt, StreamExt};
use serde_json::json;
use std::sync::Arc;
use std::time::Instant;
use tokio::sync::mpsc;

/// Close code for a message over the size limit (RFC 6455 §7.4.1).
pub const CLOSE_TOO_BIG: u16 = 1009;
/// Close code when the server shuts down or the client went silent.
pub const CLOSE_GOING_AWAY: u16 = 1001;
/// Close code when the server cannot render.
pub const CLOSE_INTERNAL: u16 = 1011;

/// `GET /ws`: upgrade unless the client limit is reached (503).
pub async fn handler(State(state): State<Arc<AppState>>, upgrade: WebSocketUpgrade) -> Response {
    let Some(guard) = state.register("ws") else {
        return crate::api::error(
            axum::http::StatusCode::SERVICE_UNAVAILABLE,
            format!("client limit of {} reached", state.config.max_clients),
        );
    };
    let max = state.config.max_message_bytes;
    // What may wait to be sent: the largest frame (raw RGB at the largest
    // size) and a little more. A client that sends pings and never reads
    // their pongs fills it, and its session ends, instead of growing the
    // server's memory without bound.
    let (w, h) = state.config.max_size;
    let unsent = (w as usize * h as usize * 3).saturating_add(1 << 20);
    upgrade
        .max_message_size(max)
        .max_frame_size(max)
        .max_write_buffer_size(unsent)
        .on_upgrade(move |socket| session(socket, state, guard))
        .into_response()
}

/// A token bucket: `rate` messages a second, bursts up to one second's worth.
struct RateLimit {
    rate: f64,
    tokens: f64,
    last: Instant,
    last_error: Option<Instant>,
}

impl RateLimit {
    fn new(rate: u32) -> Self {
        RateLimit {
            rate: rate as f64,
            tokens: rate as f64,
            last: Instant::now(),
            last_error: None,
        }
    }

    /// Take a token at `now`; false when none is left.
    fn allow(&mut self, now: Instant) -> bool {
        let dt = now.saturating_duration_since(self.last).as_secs_f64();
        self.last = now;
        self.tokens = (self.tokens + dt * self.rate).min(self.rate);
        if self.tokens >= 1.0 {
            self.tokens -= 1.0;
            true
        } else {
            false
        }
    }

    /// Whether to report a dropped message now: at most once a second.
    fn report(&mut self, now: Instant) -> bool {
        let due = self
            .last_error
            .is_none_or(|t| now.saturating_duration_since(t).as_secs_f64() >= 1.0);
        if due {
            self.last_error = Some(now);
        }
        due
    }
}

async fn session(socket: WebSocket, state: Arc<AppState>, guard: ClientGuard) {
    let client = guard.client.clone();
    let (mut sink, mut stream) = socket.split();
    // Small: at most one frame is unacknowledged, so the queue holds little
    // more than replies; errors are dropped when it is full.
    let (tx, mut rx) = mpsc::channel::<Outgoing>(4);
    let mut shutdown = state.watch_shutdown();

    let world = state.world();
    let (full, quality, spp, format, previews) = {
        let v = lock(&client.view);
        (v.full, v.quality, v.spp, v.format, v.previews)
    };
    let c = &state.config;
    let hello = json!({
        "type": "hello", "client": client.id,
        "scene": world.geometry.scene.name,
        "triangles": world.geometry.scene.mesh.num_triangles(),
        "camera": CameraJson::from_camera(&world.camera),
        "full": [full.0, full.1],
        "preview": crate::config::ServeConfig::preview_size(full),
        "quality": quality, "spp": spp, "format": format, "previews": previews,
        "limits": {"max_width": c.max_size.0, "max_height": c.max_size.1, "max_spp": c.max_spp,
            "max_message_bytes": c.max_message_bytes,
            "max_inputs_per_second": c.max_inputs_per_second},
    });
    if sink
        .send(Message::Text(hello.to_string().into()))
        .await
        .is_err()
    {
        return;
    }

    // Writer: everything the session sends goes through one queue.
    let writer = tokio::spawn(async move {
        while let Some(out) = rx.recv().await {
            let msg = match out {
                Outgoing::Text(s) => Message::Text(s.into()),
                Outgoing::Frame(b) => Message::Binary(b.into()),
                Outgoing::Ping => Message::Ping(Vec::new().into()),
            };
            if sink.send(msg).await.is_err() {
                return None;
            }
        }
        Some(sink)
    });
    let mut renderer = tokio::spawn(render_loop(state.clone(), client.clone(), tx.clone()));

    let mut limit = RateLimit::new(state.config.max_inputs_per_second);
    let mut close: Option<(u16, &str)> = None;
    // The first ping after one period, not at once (interval's first tick
    // is immediate).
    let every = state.config.ping_every;
    let mut ping = tokio::time::interval_at(tokio::time::Instant::now() + every, every);
    let mut last_heard = Instant::now();
    loop {
        let msg = tokio::select! {
            m = stream.next() => m,
            _ = shutdown.wait_for(|s| *s) => { close = Some((CLOSE_GOING_AWAY, "server shutting down")); break; }
            // The render loop ends only when the server cannot render.
            _ = &mut renderer => {
                close = Some(if *state.watch_shutdown().borrow() {
                    (CLOSE_GOING_AWAY, "server shutting down")
                } else {
                    (CLOSE_INTERNAL, "rendering failed")
                });
                break;
            }
            _ = ping.tick() => {
                if last_heard.elapsed() > state.config.idle_timeout {
                    close = Some((CLOSE_GOING_AWAY, "no message or pong for too long"));
                    break;
                }
                let _ = tx.try_send(Outgoing::Ping);
                continue;
            }
        };
        last_heard = Instant::now();
        let text = match msg {
            None => break,
            Some(Err(e)) => {
                // Over-long messages end the connection (tungstenite cannot
                // skip them); say why if the socket still works.
                if e.to_string().contains("too long") || e.to_string().contains("too big") {
                    client.count_error(&state.totals);
                    close = Some((CLOSE_TOO_BIG, "message over the size limit"));
                }
                break;
            }
            Some(Ok(Message::Text(t))) => t,
            Some(Ok(Message::Close(_))) => break,
            Some(Ok(Message::Ping(_) | Message::Pong(_))) => continue,
            Some(Ok(Message::Binary(_))) => {
                // Answered within the rate limit, as any other input.
                if limit.allow(Instant::now()) {
                    reply_error(
                        &tx,
                        &client,
                        &state,
                        "binary messages are not accepted; send JSON text",
                    );
                } else {
                    client.count_error(&state.totals);
                }
                continue;
            }
        };
        let now = Instant::now();
        let parsed = serde_json::from_str::<Envelope>(text.as_str());
        // Acknowledgements are never dropped: a lost ack would stop the
        // stream for good.
        let is_ack = matches!(&parsed, Ok(e) if matches!(e.message, ClientMessage::Ack { .. }));
        if !is_ack && !limit.allow(now) {
            if limit.report(now) {
                let m = format!(
                    "more than {} messages per second: some were dropped",
                    state.config.max_inputs_per_second
                );
                reply_error(&tx, &client, &state, &m);
            } else {
                client.count_error(&state.totals);
            }
            continue;
        }
        let result = parsed
            .map_err(|e| format!("bad message ({e}); see PROTOCOL.md"))
            .and_then(|env| {
                client.apply(env.seq, &env.message, &state.world(), &state.config, now)
            });
        if let Err(e) = result {
            reply_error(&tx, &client, &state, &e);
        }
    }
    renderer.abort();
    drop(tx);
    // A client that stopped reading cannot hold the session open.
    let abort = writer.abort_handle();
    let flushed = tokio::time::timeout(std::time::Duration::from_secs(2), writer).await;
    abort.abort();
    if let Ok(Ok(Some(mut sink))) = flushed {
        if let Some((code, reason)) = close {
            let frame = CloseFrame {
                code,
                reason: reason.into(),
            };
            let _ = sink.send(Message::Close(Some(frame))).await;
        }
        let _ = sink.close().await;
    }
    drop(guard);
}

/// Send an error message without waiting: when the queue is full (a client
/// that does not read), the message is dropped but still counted.
fn reply_error(
    tx: &mpsc::Sender<Outgoing>,
    client: &crate::client::ClientShared,
    state: &AppState,
    message: &str,
) {
    client.count_error(&state.totals);
    let msg = json!({"type": "error", "message": message}).to_string();
    let _ = tx.try_send(Outgoing::Text(msg));
}
