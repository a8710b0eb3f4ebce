//! `GET /mjpeg`: a `multipart/x-mixed-replace` JPEG stream for clients
//! without JavaScript. Each part is rendered only when the connection can
//! take it, so a slow reader gets the latest view and no backlog.

use crate::api::{error, query_u32};
use crate::app::{AppState, ClientGuard};
use crate::frame::FrameRequest;
use crate::protocol::FrameFormat;
use crate::sync::lock;
use axum::body::{Body, Bytes};
use axum::extract::{Query, State};
use axum::http::{header, StatusCode};
use axum::response::Response;
use std::collections::HashMap;
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Boundary between the parts.
pub const BOUNDARY: &str = "raykitframe";

/// The last part is repeated at least this often (without rendering again),
/// so proxies keep the stream open.
pub const KEEPALIVE: Duration = Duration::from_secs(2);

struct Stream {
    state: Arc<AppState>,
    guard: ClientGuard,
    size: Option<(u32, u32)>,
    quality: u8,
    spp: u32,
    last_version: Option<u64>,
    last_sent: Instant,
    last_part: Option<Bytes>,
}

/// `GET /mjpeg?width=W&height=H&quality=Q&spp=S`.
pub async fn handler(
    State(state): State<Arc<AppState>>,
    Query(q): Query<HashMap<String, String>>,
) -> Response {
    let parsed = (|| -> Result<_, String> {
        let w = query_u32(&q, "width")?;
        let h = query_u32(&q, "height")?;
        let size = match (w, h) {
            (Some(w), Some(h)) => Some((w, h)),
            (None, None) => None,
            _ => return Err("give both width and height, or neither".into()),
        };
        if let Some((w, h)) = size {
            if let Some(p) = state.config.size_problem(w, h) {
                return Err(p);
            }
        }
        let quality = query_u32(&q, "quality")?.unwrap_or(state.config.quality as u32);
        if !(1..=100).contains(&quality) {
            return Err(format!("quality {quality} outside 1..=100"));
        }
        let spp = query_u32(&q, "spp")?.unwrap_or(1);
        if !(1..=state.config.max_spp).contains(&spp) {
            return Err(format!("spp {spp} outside 1..={}", state.config.max_spp));
        }
        Ok((size, quality as u8, spp))
    })();
    let (size, quality, spp) = match parsed {
        Ok(p) => p,
        Err(e) => return error(StatusCode::BAD_REQUEST, e),
    };
    let Some(guard) = state.register("mjpeg") else {
        return error(
            StatusCode::SERVICE_UNAVAILABLE,
            format!("client limit of {} reached", state.config.max_clients),
        );
    };
    let stream = Stream {
        state,
        guard,
        size,
        quality,
        spp,
        last_version: None,
        last_sent: Instant::now(),
        last_part: None,
    };
    let body = futures_util::stream::unfold(stream, next_part);
    Response::builder()
        .header(
            header::CONTENT_TYPE,
            format!("multipart/x-mixed-replace; boundary={BOUNDARY}"),
        )
        .header(header::CACHE_CONTROL, "no-cache")
        .body(Body::from_stream(body))
        .expect("static headers are valid")
}

/// The next part: waits for a change of the world (or the keep-alive time),
/// renders the default camera and frames it as a multipart part. Ends the
/// stream on shutdown.
async fn next_part(mut s: Stream) -> Option<(Result<Bytes, std::io::Error>, Stream)> {
    let mut world_rx = s.state.watch_world();
    let mut shutdown = s.state.watch_shutdown();
    if *shutdown.borrow() {
        return None;
    }
    if s.last_version.is_some_and(|v| v == s.state.world().version) {
        let due = s.last_sent + KEEPALIVE;
        tokio::select! {
            _ = world_rx.changed() => {}
            _ = shutdown.wait_for(|s| *s) => return None,
            _ = tokio::time::sleep_until(due.into()) => {
                // Nothing changed: repeat the last part instead of rendering.
                if let Some(part) = &s.last_part {
                    s.last_sent = Instant::now();
                    return Some((Ok(part.clone()), s));
                }
            }
        }
    }
    let world = s.state.world();
    let size = s.size.unwrap_or(world.full);
    let (quality, spp) = (s.quality, s.spp);
    let encoded = s
        .state
        .renderer
        .render(FrameRequest {
            camera: world.camera,
            world: world.clone(),
            size,
            spp,
            format: FrameFormat::Jpeg,
            quality,
        })
        .await?;
    let now = Instant::now();
    let client = &s.guard.client;
    lock(&client.stats).frame_sent(now, encoded.payload.len(), &[]);
    s.state.count_frame(
        encoded.payload.len(),
        (encoded.render_ms + encoded.encode_ms) * 1e-3,
    );
    s.last_version = Some(world.version);
    s.last_sent = now;
    let mut part = format!(
        "--{BOUNDARY}\r\nContent-Type: image/jpeg\r\nContent-Length: {}\r\n\r\n",
        encoded.payload.len()
    )
    .into_bytes();
    part.extend_from_slice(&encoded.payload);
    part.extend_from_slice(b"\r\n");
    let part = Bytes::from(part);
    s.last_part = Some(part.clone());
    Some((Ok(part), s))
}
