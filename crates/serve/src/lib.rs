//! raykit remote rendering server: the arrangement of the Purcell-style stream tracer (render on
//! a PC, stream the frames to a tracked handheld) for today's clients.
//!
//! [`start`] binds an axum server that renders the loaded scene with
//! [`raykit_render`] for every client through its own camera, sharing the
//! scene and its BVH. Browsers get a small web client (orbit, pan, zoom, WASD
//! fly, phone orientation); frames go over a WebSocket as JPEG (or raw RGB
//! for a client that asks, as a display without a decoder would), one
//! unacknowledged frame per client at most (so a slow client builds no
//! backlog and costs the others nothing), from a half-size preview while the
//! camera moves to full size and more samples once it stops. `GET /mjpeg`
//! serves clients without JavaScript, `/api/*` loads scenes and sets
//! cameras, lights and resolution, `/metrics` reports per-client fps,
//! input-to-frame latency and bytes/s; [`link`] measures one stream over a
//! network link. See `PROTOCOL.md` for the wire format.
//!
//! ```no_run
//! # async fn run() -> anyhow::Result<()> {
//! use raykit_serve::{start, ServeConfig};
//! use std::sync::Arc;
//!
//! let loader = Arc::new(|spec: &str| {
//!     let name = spec.strip_prefix("builtin:").unwrap_or(spec);
//!     Ok(raykit_scene::builtin(name)?)
//! });
//! let server = start(ServeConfig::default(), loader, "builtin:cornell").await?;
//! println!("open http://{}/", server.addr());
//! server.shutdown().await?;
//! # Ok(()) }
//! ```

#![forbid(unsafe_code)]
#![warn(missing_docs)]

mod api;
mod app;
mod auth;
pub mod camera_control;
mod client;
mod config;
mod connections;
mod frame;
pub mod link;
pub mod load;
mod mjpeg;
pub mod protocol;
mod query;
mod runtime;
mod session;
pub mod stats;
mod sync;
mod world;
mod ws;

pub use app::{AppState, SceneLoader};
pub use config::ServeConfig;
pub use frame::encode_jpeg;
pub use mjpeg::BOUNDARY;
pub use runtime::runtime;
pub use ws::{CLOSE_GOING_AWAY, CLOSE_INVALID_DATA, CLOSE_PROTOCOL, CLOSE_TOO_BIG};

use anyhow::{bail, Context, Result};
use axum::extract::DefaultBodyLimit;
use axum::routing::{get, post};
use axum::Router;
use std::net::SocketAddr;
use std::sync::Arc;
use tokio::task::JoinHandle;

/// The routes over `state`. The page and its script are public (they hold
/// no data; the page forwards its `?token=` to the WebSocket); everything
/// else is behind the token check, takes only the query parameters its path
/// has, and API writes must be JSON.
pub fn router(state: Arc<AppState>) -> Router {
    let protected = Router::new()
        .route("/ws", get(ws::handler))
        .route("/mjpeg", get(mjpeg::handler))
        .route("/api/status", get(api::status))
        .route("/api/scene", post(api::load_scene))
        .route("/api/camera", get(api::get_camera).put(api::put_camera))
        .route("/api/lights", axum::routing::put(api::put_lights))
        .route("/api/resolution", axum::routing::put(api::put_resolution))
        .route("/metrics", get(api::metrics))
        .layer(DefaultBodyLimit::max(state.config.max_message_bytes))
        .layer(axum::middleware::from_fn(api::require_json))
        .layer(axum::middleware::from_fn_with_state(
            state.clone(),
            api::body_in_time,
        ))
        .layer(axum::middleware::from_fn(query::refuse_unknown))
        .layer(axum::middleware::from_fn_with_state(
            state.clone(),
            auth::require_token,
        ));
    Router::new()
        .route("/", get(api::index))
        .route("/client.js", get(api::client_js))
        .merge(protected)
        .fallback(|| async { api::error(axum::http::StatusCode::NOT_FOUND, "no such path") })
        .layer(axum::middleware::from_fn(api::json_errors))
        .with_state(state)
}

/// Longest [`Server::shutdown`] waits for sessions to close.
pub const SHUTDOWN_GRACE: std::time::Duration = std::time::Duration::from_secs(5);

/// A running server.
pub struct Server {
    addr: SocketAddr,
    state: Arc<AppState>,
    task: JoinHandle<std::io::Result<()>>,
}

impl Server {
    /// The address it listens on (the real port when 0 was asked for).
    pub fn addr(&self) -> SocketAddr {
        self.addr
    }

    /// The shared state (scene, clients, totals).
    pub fn state(&self) -> &Arc<AppState> {
        &self.state
    }

    /// Close every session (WebSocket clients get close code 1001, MJPEG
    /// streams end), stop accepting, and wait for the sessions and open
    /// requests to end — at most [`SHUTDOWN_GRACE`], after which the rest
    /// (say, a stream whose client stopped reading) are dropped.
    pub async fn shutdown(self) -> Result<()> {
        self.state.begin_shutdown();
        let deadline = tokio::time::Instant::now() + SHUTDOWN_GRACE;
        // WebSocket sessions are not requests any more: wait for them here.
        while !self.state.clients().is_empty() && tokio::time::Instant::now() < deadline {
            tokio::time::sleep(std::time::Duration::from_millis(10)).await;
        }
        let abort = self.task.abort_handle();
        match tokio::time::timeout_at(deadline, self.task).await {
            Ok(joined) => joined.context("server task")?.context("server"),
            Err(_) => {
                abort.abort();
                Ok(())
            }
        }
    }
}

/// Load `scene` with `loader`, build its BVH, bind `config.addr` and serve
/// until [`Server::shutdown`].
pub async fn start(config: ServeConfig, loader: SceneLoader, scene: &str) -> Result<Server> {
    if let Some(p) = config.problem() {
        bail!("server settings: {p}");
    }
    let l = loader.clone();
    let spec = scene.to_string();
    let scene = tokio::task::spawn_blocking(move || l(&spec))
        .await
        .context("loading the scene")??;
    let addr = config.addr;
    let header_timeout = config.header_timeout;
    let state = AppState::new(config, loader, scene);
    let listener = tokio::net::TcpListener::bind(addr)
        .await
        .with_context(|| format!("cannot listen on {addr}"))?;
    let addr = listener.local_addr()?;
    let app = router(state.clone());
    let stop = state.watch_shutdown();
    let task = tokio::spawn(connections::serve(listener, app, header_timeout, stop));
    Ok(Server { addr, state, task })
}
