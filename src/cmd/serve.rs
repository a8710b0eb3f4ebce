//! `raykit serve`: stream rendered frames to browsers and other clients.

use anyhow::{Context, Result};
use clap::Args;
use raykit_lab::args::scene_arg::loader;
use raykit_serve::{runtime, start, ServeConfig};
use std::net::SocketAddr;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::Duration;

/// Arguments of `raykit serve`.
#[derive(Args)]
#[command(
    after_help = "Open the printed address in a browser: drag to orbit, right-drag or shift-drag to pan,\n\
wheel or pinch to zoom, WASD/QE to fly, or tilt a phone in orientation mode.\n\n\
Examples:\n  raykit serve                                     # builtin:cornell on http://127.0.0.1:8080/\n  \
raykit serve --scene dragon.ply.gz --addr 0.0.0.0:8080 --token s3cret\n  \
curl -X POST localhost:8080/api/scene -H 'Content-Type: application/json' -d '{\"scene\":\"builtin:terrain\"}'\n  \
curl -X PUT localhost:8080/api/camera -H 'Content-Type: application/json' -d '{\"eye\":[0,1,3],\"target\":[0,0,0]}'\n  \
curl localhost:8080/metrics\n  \
ffplay http://127.0.0.1:8080/mjpeg                # no JavaScript: MJPEG\n\n\
The wire protocol and every endpoint are described in crates/serve/PROTOCOL.md.\n\
Behind a reverse proxy, forward /ws as a WebSocket upgrade; the page uses relative URLs."
)]
pub struct ServeArgs {
    /// Scene: builtin:NAME[:key=value,...] (`raykit info scenes`) or a mesh file.
    #[arg(long, default_value = "builtin:cornell")]
    scene: String,
    /// Address to listen on (0.0.0.0:PORT for the LAN).
    #[arg(long, default_value = "127.0.0.1:8080")]
    addr: SocketAddr,
    /// Require this token (`?token=` or `Authorization: Bearer`); also from $RAYKIT_TOKEN.
    /// An empty token is refused.
    #[arg(long, env = "RAYKIT_TOKEN", hide_env_values = true)]
    token: Option<String>,
    /// Most clients at once (WebSocket and MJPEG).
    #[arg(long, default_value_t = 16)]
    max_clients: usize,
    /// Full resolution (when the camera stops) of new clients; the preview while it moves is half.
    #[arg(long, default_value_t = 1280)]
    width: u32,
    /// Full resolution height.
    #[arg(long, default_value_t = 720)]
    height: u32,
    /// Samples per pixel of the last refinement step.
    #[arg(long, default_value_t = 4)]
    spp: u32,
    /// JPEG quality 1..100 (clients may change it).
    #[arg(long, default_value_t = 80)]
    quality: u8,
    /// Milliseconds the camera must stay still before full resolution.
    #[arg(long, default_value_t = 150)]
    settle_ms: u64,
    /// Largest width a client may ask for.
    #[arg(long, default_value_t = 3840)]
    max_width: u32,
    /// Largest height a client may ask for.
    #[arg(long, default_value_t = 2160)]
    max_height: u32,
    /// Largest samples per pixel a client may ask for.
    #[arg(long, default_value_t = 16)]
    max_spp: u32,
    /// Largest client message (WebSocket) or request body, bytes.
    #[arg(long, default_value_t = 16384)]
    max_message_bytes: usize,
    /// Inputs per second per client; more are dropped with an error.
    #[arg(long, default_value_t = 240)]
    max_inputs_per_second: u32,
    /// Largest scene `POST /api/scene` may load, in triangles.
    #[arg(long, default_value_t = 20_000_000)]
    max_scene_triangles: usize,
    /// Allow `POST /api/scene` to load mesh files from this directory (otherwise builtin: only);
    /// it must exist and be readable when the server starts.
    #[arg(long)]
    scene_dir: Option<PathBuf>,
    /// Render threads (0 = one per core; at most 4096).
    #[arg(long, default_value_t = 0)]
    threads: usize,
    /// Stop by itself after this many seconds (for scripts); otherwise run until Ctrl-C.
    #[arg(long)]
    seconds: Option<f64>,
}

impl ServeArgs {
    fn config(&self) -> ServeConfig {
        ServeConfig {
            addr: self.addr,
            token: self.token.clone(),
            max_clients: self.max_clients,
            full: (self.width, self.height),
            max_size: (self.max_width, self.max_height),
            spp: self.spp,
            max_spp: self.max_spp,
            quality: self.quality,
            settle: Duration::from_millis(self.settle_ms),
            max_message_bytes: self.max_message_bytes,
            max_inputs_per_second: self.max_inputs_per_second,
            max_scene_triangles: self.max_scene_triangles,
            scene_dir: self.scene_dir.clone(),
            ..ServeConfig::default()
        }
    }
}

/// Serve until Ctrl-C (or `--seconds`).
pub fn run(args: ServeArgs) -> Result<ExitCode> {
    if args.threads > 0 {
        rayon::ThreadPoolBuilder::new()
            .num_threads(raykit_lab::measure::check_threads(args.threads)?)
            .build_global()
            .context("cannot start the thread pool")?;
    }
    if let Some(s) = args.seconds {
        if !(s.is_finite() && (0.0..=1e7).contains(&s)) {
            anyhow::bail!("--seconds must be a number of seconds in 0..=1e7, got {s}");
        }
    }
    if args.token.as_deref() == Some("") {
        anyhow::bail!(
            "--token (or $RAYKIT_TOKEN) is empty: give a token clients must present, or leave \
             both unset to serve without one"
        );
    }
    if let Some(dir) = &args.scene_dir {
        std::fs::read_dir(dir)
            .with_context(|| format!("--scene-dir {} cannot be read", dir.display()))?;
    }
    let config = args.config();
    runtime()?.block_on(async move {
        let server = start(config, loader(), &args.scene).await?;
        let state = server.state();
        let world = state.world();
        eprintln!(
            "raykit serve: {} ({} triangles) on http://{}/{}  (Ctrl-C stops)",
            world.geometry.scene.name,
            world.geometry.scene.mesh.num_triangles(),
            server.addr(),
            if args.token.is_some() {
                "?token=..."
            } else {
                ""
            },
        );
        match args.seconds {
            Some(s) => tokio::time::sleep(Duration::from_secs_f64(s)).await,
            None => {
                tokio::signal::ctrl_c()
                    .await
                    .context("waiting for Ctrl-C")?;
            }
        }
        eprintln!("raykit serve: shutting down");
        server.shutdown().await?;
        Ok(ExitCode::SUCCESS)
    })
}
