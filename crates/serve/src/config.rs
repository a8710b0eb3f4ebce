//! Server settings and the limits a client may ask up to.

use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;

/// Samples (pixels × samples per pixel) of one slice of a frame per thread
/// of the rayon pool: about a tenth of a second of tracing `builtin:cornell`
/// on one core.
const SLICE_SAMPLES_PER_THREAD: u64 = 1 << 17;

/// How the server runs and what it allows.
#[derive(Clone, Debug)]
pub struct ServeConfig {
    /// Address to listen on.
    pub addr: SocketAddr,
    /// When set, every request needs `?token=` or `Authorization: Bearer`;
    /// an empty token is refused.
    pub token: Option<String>,
    /// Most clients (WebSocket and MJPEG together).
    pub max_clients: usize,
    /// Default full resolution of new clients.
    pub full: (u32, u32),
    /// Largest width and height a client may ask for.
    pub max_size: (u32, u32),
    /// Default samples per pixel of the refined stage.
    pub spp: u32,
    /// Largest samples per pixel a client may ask for.
    pub max_spp: u32,
    /// Default JPEG quality (1..=100).
    pub quality: u8,
    /// How long the camera must stay still before full resolution.
    pub settle: Duration,
    /// Largest WebSocket message or HTTP body a client may send, bytes.
    pub max_message_bytes: usize,
    /// Inputs per second a client may send; more are dropped with an error.
    pub max_inputs_per_second: u32,
    /// How often each WebSocket client is pinged.
    pub ping_every: Duration,
    /// A WebSocket client silent this long (no message, no pong) is
    /// disconnected.
    pub idle_timeout: Duration,
    /// Largest scene `POST /api/scene` may load, triangles.
    pub max_scene_triangles: usize,
    /// Directory scene files may be loaded from through the API (`None`:
    /// built-in scenes only); it must be readable when the server starts.
    pub scene_dir: Option<PathBuf>,
    /// Time a client has to send a request's headers before its connection
    /// is closed, and again its body (408), so that connections that never
    /// finish a request (a slow-loris client) cannot use up the server's
    /// sockets.
    pub header_timeout: Duration,
    /// Most samples (pixels × samples per pixel) rendered in one slice of a
    /// frame, per thread of the rayon pool. Frames render in horizontal
    /// bands of at most this many samples times the pool's threads, and
    /// clients' frames take turns a band at a time, so that no client's
    /// frame, however large, holds the others' up for more than a band.
    pub slice_samples_per_thread: u64,
}

impl Default for ServeConfig {
    /// 127.0.0.1:8080, no token, 16 clients, 1280×720 refined with 4
    /// samples, 3840×2160 and 16 samples at most, quality 80, 150 ms settle,
    /// 16 KiB messages, 240 inputs/s, scenes up to 20M triangles, a ping every
    /// 20 s and 65 s of silence allowed, 10 s to send a request's headers,
    /// slices of 131,072 samples per thread.
    fn default() -> Self {
        ServeConfig {
            addr: SocketAddr::from(([127, 0, 0, 1], 8080)),
            token: None,
            max_clients: 16,
            full: (1280, 720),
            max_size: (3840, 2160),
            spp: 4,
            max_spp: 16,
            quality: 80,
            settle: Duration::from_millis(150),
            max_message_bytes: 16 * 1024,
            max_inputs_per_second: 240,
            max_scene_triangles: 20_000_000,
            ping_every: Duration::from_secs(20),
            idle_timeout: Duration::from_secs(65),
            scene_dir: None,
            header_timeout: Duration::from_secs(10),
            slice_samples_per_thread: SLICE_SAMPLES_PER_THREAD,
        }
    }
}

impl ServeConfig {
    /// Why a requested full resolution is not allowed, if it is not.
    pub fn size_problem(&self, width: u32, height: u32) -> Option<String> {
        let (mw, mh) = self.max_size;
        (!(16..=mw).contains(&width) || !(16..=mh).contains(&height))
            .then(|| format!("resolution {width}x{height} outside 16x16..={mw}x{mh}"))
    }

    /// Why the settings themselves are unusable, if they are. Each reason
    /// names the setting, with the `raykit serve` flag that sets it.
    pub fn problem(&self) -> Option<String> {
        if let Some(p) = self.size_problem(self.full.0, self.full.1) {
            return Some(format!("full (--width, --height): default {p}"));
        }
        if self.max_size.0 > 16384 || self.max_size.1 > 16384 {
            return Some(format!(
                "max_size (--max-width, --max-height) {}x{} is over 16384x16384",
                self.max_size.0, self.max_size.1
            ));
        }
        if !(1..=4096).contains(&self.max_spp) {
            return Some(format!(
                "max_spp (--max-spp) {} outside 1..=4096",
                self.max_spp
            ));
        }
        if !(1..=self.max_spp).contains(&self.spp) {
            return Some(format!(
                "spp (--spp) {} outside 1..={} (max_spp, --max-spp)",
                self.spp, self.max_spp
            ));
        }
        if !(1..=100).contains(&self.quality) {
            return Some(format!(
                "quality (--quality) {} outside 1..=100",
                self.quality
            ));
        }
        if self.max_clients == 0 {
            return Some("max_clients (--max-clients) must be at least 1".into());
        }
        if self.max_message_bytes < 256 {
            return Some(format!(
                "max_message_bytes (--max-message-bytes) {} is under 256",
                self.max_message_bytes
            ));
        }
        if self.max_inputs_per_second == 0 {
            return Some(
                "max_inputs_per_second (--max-inputs-per-second) must be at least 1".into(),
            );
        }
        if self.header_timeout.is_zero() {
            return Some("header_timeout must be positive".into());
        }
        if self.ping_every.is_zero() || self.idle_timeout <= self.ping_every {
            return Some(format!(
                "idle_timeout ({:?}) must exceed ping_every ({:?}), which must be positive",
                self.idle_timeout, self.ping_every
            ));
        }
        if self.settle > Duration::from_secs(60) {
            return Some(format!(
                "settle (--settle-ms) {} ms is over 60000 ms",
                self.settle.as_millis()
            ));
        }
        if self.slice_samples_per_thread == 0 {
            return Some("slice_samples_per_thread must be at least 1".into());
        }
        if self.token.as_deref() == Some("") {
            return Some(
                "token (--token, $RAYKIT_TOKEN) is empty: give one clients must present, or none"
                    .into(),
            );
        }
        if let Some(dir) = &self.scene_dir {
            if let Err(e) = std::fs::read_dir(dir) {
                return Some(format!(
                    "scene_dir (--scene-dir): the folder {} cannot be read: {e}",
                    dir.display()
                ));
            }
        }
        None
    }

    /// The preview size for a full resolution: half in each direction, at
    /// least 16.
    pub fn preview_size(full: (u32, u32)) -> (u32, u32) {
        ((full.0 / 2).max(16), (full.1 / 2).max(16))
    }
}
