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
use std::time::{Duration, Instant};
use tokio::sync::mpsc;

/// Close code for a message over the size limit (RFC 6455 §7.4.1).
pub const CLOSE_TOO_BIG: u16 = 1009;
/// Close code when the server shuts down or the client went silent.
pub const CLOSE_GOING_AWAY: u16 = 1001;
/// Close code when the server cannot render.
pub const CLOSE_INTERNAL: u16 = 1011;
/// Close code for a frame that breaks the WebSocket protocol: unmasked,
/// with a reserved opcode or reserved bits, a continuation with nothing to
/// continue, a control frame over 125 bytes or fragmented (RFC 6455 §7.4.1).
pub const CLOSE_PROTOCOL: u16 = 1002;
/// Close code for a text message that is not UTF-8 (RFC 6455 §7.4.1).
pub const CLOSE_INVALID_DATA: u16 = 1007;

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

/// When to ping a client and when to give up on it: a ping every
/// `ping_every`, and a close once nothing (message or pong) has been heard
/// for `idle_timeout`, at that moment rather than at the next ping.
struct Liveness {
    ping_every: Duration,
    idle_timeout: Duration,
    last_heard: Instant,
    next_ping: Instant,
}

/// What [`Liveness`] says is due.
#[derive(Debug, PartialEq, Eq)]
enum Due {
    /// Nothing yet.
    Nothing,
    /// Send a ping.
    Ping,
    /// Silent too long: close.
    Close,
}

impl Liveness {
    fn new(ping_every: Duration, idle_timeout: Duration, now: Instant) -> Self {
        Liveness {
            ping_every,
            idle_timeout,
            last_heard: now,
            next_ping: now + ping_every,
        }
    }

    /// Something came from the client at `now`.
    fn heard(&mut self, now: Instant) {
        self.last_heard = now;
    }

    /// The next instant something may be due.
    fn wake(&self) -> Instant {
        self.next_ping.min(self.last_heard + self.idle_timeout)
    }

    /// What is due at `now` (a ping counts as sent).
    fn due(&mut self, now: Instant) -> Due {
        if now.saturating_duration_since(self.last_heard) >= self.idle_timeout {
            Due::Close
        } else if now >= self.next_ping {
            self.next_ping = now + self.ping_every;
            Due::Ping
        } else {
            Due::Nothing
        }
    }
}

/// The close code and reason for an error reading the socket, or `None`
/// when the connection itself failed (nothing can be sent).
fn close_for(error: axum::Error) -> Option<(u16, String)> {
    use tokio_tungstenite::tungstenite::error::{Error, ProtocolError};
    let error = error.into_inner().downcast::<Error>().ok()?;
    match *error {
        Error::Capacity(_) => Some((CLOSE_TOO_BIG, "message over the size limit".into())),
        Error::Utf8(_) => Some((CLOSE_INVALID_DATA, "text message is not UTF-8".into())),
        Error::Protocol(ProtocolError::ResetWithoutClosingHandshake) => None,
        Error::Protocol(p) => {
            // A close reason has at most 123 bytes.
            let mut reason = format!("protocol error: {p}");
            while reason.len() > 123 {
                reason.pop();
            }
            Some((CLOSE_PROTOCOL, reason))
        }
        _ => None,
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
    let mut close: Option<(u16, String)> = None;
    let going_away = |reason: &str| Some((CLOSE_GOING_AWAY, reason.to_string()));
    let c = &state.config;
    let mut live = Liveness::new(c.ping_every, c.idle_timeout, Instant::now());
    loop {
        let wake = tokio::time::Instant::from_std(live.wake());
        let msg = tokio::select! {
            m = stream.next() => m,
            _ = shutdown.wait_for(|s| *s) => { close = going_away("server shutting down"); break; }
            // The render loop ends only when the server cannot render.
            _ = &mut renderer => {
                close = if *state.watch_shutdown().borrow() {
                    going_away("server shutting down")
                } else {
                    Some((CLOSE_INTERNAL, "rendering failed".into()))
                };
                break;
            }
            _ = tokio::time::sleep_until(wake) => {
                match live.due(Instant::now()) {
                    Due::Close => {
                        close = going_away("no message or pong for too long");
                        break;
                    }
                    Due::Ping => { let _ = tx.try_send(Outgoing::Ping); }
                    Due::Nothing => {}
                }
                continue;
            }
        };
        live.heard(Instant::now());
        let text = match msg {
            None => break,
            Some(Err(e)) => {
                // A broken frame or an over-long message ends the connection
                // (tungstenite cannot skip it); say why if the socket still
                // works.
                close = close_for(e);
                if close.is_some() {
                    client.count_error(&state.totals);
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
        match result {
            Ok(()) => {}
            // Acks take no token, so a wrong one is answered at most once
            // a second, as dropped messages are; the rest are counted.
            Err(_) if is_ack && !limit.report(now) => client.count_error(&state.totals),
            Err(e) => reply_error(&tx, &client, &state, &e),
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn silence_closes_at_the_idle_timeout_not_at_the_next_ping() {
        let (every, idle) = (Duration::from_secs(20), Duration::from_secs(65));
        let t0 = Instant::now();
        let at = |s: u64| t0 + Duration::from_secs(s);
        let mut live = Liveness::new(every, idle, t0);
        assert_eq!(live.due(at(1)), Due::Nothing);
        for ping in [20, 40, 60] {
            assert_eq!(live.wake(), at(ping));
            assert_eq!(live.due(at(ping)), Due::Ping);
        }
        // The next ping would be at 80 s: the close is due at 65 s.
        assert_eq!(live.wake(), at(65));
        assert_eq!(live.due(at(64)), Due::Nothing);
        assert_eq!(live.due(at(65)), Due::Close);
        // Hearing from the client moves the close.
        let mut live = Liveness::new(every, idle, t0);
        assert_eq!(live.due(at(20)), Due::Ping);
        live.heard(at(30));
        for ping in [40, 60] {
            assert_eq!(live.due(at(ping)), Due::Ping);
        }
        assert_eq!(live.due(at(65)), Due::Nothing);
        assert_eq!(live.wake(), at(80));
        assert_eq!(live.due(at(80)), Due::Ping);
        assert_eq!(live.wake(), at(95));
        assert_eq!(live.due(at(95)), Due::Close);
    }
}
