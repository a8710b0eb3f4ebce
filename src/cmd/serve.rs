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
Ctrl-C (SIGINT) or SIGTERM (what systemd, docker and kubernetes send to stop) shuts down\n\
gracefully: WebSocket clients get close code 1001, MJPEG streams end, and the exit status is 0.\n\n\
Frames are rendered by the quick one-bounce renderer (Blinn-Phong, shadow rays), not the\n\
Whitted tracer of `raykit render`: mirrors and glass show no reflection or refraction.\n\
Each frame renders in bands of at most 131072 samples (pixels x spp) per thread (--threads);\n\
clients' frames take turns a band at a time, so a client asking for --max-width x --max-height\n\
at --max-spp slows the others in proportion to the clients rendering, not by its whole frame.\n\n\
The wire protocol and every endpoint are described in crates/serve/PROTOCOL.md.\n\
Behind a reverse proxy, forward /ws as a WebSocket upgrade; the page uses relative URLs."
)]
pub struct ServeArgs {
    /// Scene: builtin:NAME[:key=value,...] (`raykit info scenes`) or a mesh file.
    #[arg(long, default_value = "builtin:cornell")]
    scene: String,
    /// Address to listen on: IP:PORT (0.0.0.0:PORT for the LAN) or HOST:PORT, resolved to
    /// the host's first IPv4 address (its first address if it has none).
    #[arg(long, default_value = "127.0.0.1:8080", value_parser = parse_addr)]
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
    /// Stop by itself after this many seconds (for scripts); otherwise run until Ctrl-C or SIGTERM.
    #[arg(long)]
    seconds: Option<f64>,
}

/// An `--addr` value: `IP:PORT`, or `HOST:PORT` resolved to the host's first
/// IPv4 address (its first address if it has none).
fn parse_addr(s: &str) -> Result<SocketAddr, String> {
    use std::net::ToSocketAddrs;
    if let Ok(addr) = s.parse() {
        return Ok(addr);
    }
    let help = "give IP:PORT (such as 127.0.0.1:8080) or HOST:PORT (such as localhost:8080)";
    if s.rsplit_once(':')
        .is_none_or(|(_, port)| port.parse::<u16>().is_err())
    {
        return Err(format!("no port: {help}"));
    }
    let addrs: Vec<SocketAddr> = s
        .to_socket_addrs()
        .map_err(|e| format!("cannot resolve the host ({e}): {help}"))?
        .collect();
    addrs
        .iter()
        .find(|a| a.is_ipv4())
        .or(addrs.first())
        .copied()
        .ok_or_else(|| format!("the host has no address: {help}"))
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

/// Serve until Ctrl-C or SIGTERM (or `--seconds`), then shut down
/// gracefully ([`raykit_serve::Server::shutdown`]) and exit with status 0.
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
        // Listening for the signals before loading the scene: a stop
        // request while it loads ends the command without serving.
        let stop = stop_requested()?;
        tokio::pin!(stop);
        let server = tokio::select! {
            server = start(config, loader(), &args.scene) => server?,
            signal = &mut stop => {
                eprintln!("raykit serve: {}: stopped before serving", signal?);
                return Ok(ExitCode::SUCCESS);
            }
        };
        let state = server.state();
        let world = state.world();
        eprintln!(
            "raykit serve: {} ({} triangles) on http://{}/{}  (Ctrl-C or SIGTERM stops)",
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
            Some(s) => tokio::select! {
                _ = tokio::time::sleep(Duration::from_secs_f64(s)) => {}
                signal = &mut stop => { eprintln!("raykit serve: {}", signal?); }
            },
            None => {
                let signal = stop.await?;
                eprintln!("raykit serve: {signal}");
            }
        }
        eprintln!("raykit serve: shutting down");
        server.shutdown().await?;
        Ok(ExitCode::SUCCESS)
    })
}

/// A future that ends with the signal's name at Ctrl-C (SIGINT) or SIGTERM.
/// The handlers are installed when this is called (inside the runtime), so
/// a signal that arrives before the future is polled is not lost.
#[cfg(unix)]
fn stop_requested() -> Result<impl std::future::Future<Output = Result<&'static str>>> {
    use tokio::signal::unix::{signal, SignalKind};
    let mut interrupt = signal(SignalKind::interrupt()).context("cannot handle Ctrl-C")?;
    let mut terminate = signal(SignalKind::terminate()).context("cannot handle SIGTERM")?;
    Ok(async move {
        tokio::select! {
            _ = interrupt.recv() => Ok("Ctrl-C"),
            _ = terminate.recv() => Ok("SIGTERM"),
        }
    })
}

/// A future that ends with the signal's name at Ctrl-C.
#[cfg(not(unix))]
fn stop_requested() -> Result<impl std::future::Future<Output = Result<&'static str>>> {
    Ok(async {
        tokio::signal::ctrl_c()
            .await
            .context("waiting for Ctrl-C")?;
        Ok("Ctrl-C")
    })
}
