//! One client's shared state: its camera, settings and delivery state, which
//! the render loop, the WebSocket handler and the HTTP API read and change.

use crate::camera_control::{camera_problem, fly, orbit, orient, pan, zoom};
use crate::config::ServeConfig;
use crate::protocol::{CameraJson, ClientMessage, FrameFormat, SettingsJson, Stage};
use crate::stats::{ClientSample, ClientStats, Totals};
use crate::sync::lock;
use crate::world::World;
use raykit_core::Camera;
use std::sync::Mutex;
use std::time::Instant;
use tokio::sync::Notify;

/// Most input arrival times remembered between two frames (for latency).
const MAX_PENDING_INPUTS: usize = 1024;

/// A client's camera and settings and what was last sent.
#[derive(Clone, Debug)]
pub struct View {
    /// Current camera.
    pub camera: Camera,
    /// Full resolution.
    pub full: (u32, u32),
    /// Samples per pixel of the refined stage.
    pub spp: u32,
    /// JPEG quality.
    pub quality: u8,
    /// Payload format of the frames.
    pub format: FrameFormat,
    /// Whether frames rendered while the camera moves are half-size
    /// previews; otherwise every frame starts at full size.
    pub previews: bool,
    /// Incremented on every change of camera or settings.
    pub version: u64,
    /// Largest input `seq` applied.
    pub input_seq: u64,
    /// When the camera last changed by input.
    pub last_input: Instant,
    /// Arrival times of inputs no frame has shown yet.
    pub pending: Vec<Instant>,
    /// The sent frame not yet acknowledged.
    pub in_flight: Option<u64>,
    /// (view version, world look version, stage) of the last frame sent.
    pub rendered: Option<(u64, u64, Stage)>,
    /// Scene generation the camera belongs to.
    pub generation: u64,
    /// Frames sent.
    pub frames: u64,
}

/// A client as the registry and the HTTP API see it.
pub struct ClientShared {
    /// Client id, unique while the server runs.
    pub id: u64,
    /// `ws` or `mjpeg`.
    pub kind: &'static str,
    /// Camera, settings, delivery state.
    pub view: Mutex<View>,
    /// Delivery statistics.
    pub stats: Mutex<ClientStats>,
    /// Wakes the render loop after input, an acknowledgement or a change.
    pub wake: Notify,
}

impl ClientShared {
    /// A client starting from the world's default camera and resolution.
    pub fn new(id: u64, kind: &'static str, world: &World, config: &ServeConfig) -> Self {
        let now = Instant::now();
        ClientShared {
            id,
            kind,
            view: Mutex::new(View {
                camera: world.camera,
                full: world.full,
                spp: config.spp,
                quality: config.quality,
                format: FrameFormat::Jpeg,
                previews: true,
                version: 1,
                input_seq: 0,
                last_input: now,
                pending: Vec::new(),
                in_flight: None,
                rendered: None,
                generation: world.geometry.generation,
                frames: 0,
            }),
            stats: Mutex::new(ClientStats::new(now)),
            wake: Notify::new(),
        }
    }

    /// Stats for the metrics and the status page.
    pub fn sample(&self, now: Instant) -> ClientSample {
        let mut s = lock(&self.stats);
        ClientSample {
            id: self.id,
            kind: self.kind,
            fps: s.fps(now),
            latency_ms: s.median_latency_ms(),
            bytes_per_second: s.bytes_per_second(now),
            frames: s.frames,
            inputs: s.inputs,
            errors: s.errors,
        }
    }

    /// Count a message answered with an error.
    pub fn count_error(&self, totals: &Mutex<Totals>) {
        lock(&self.stats).errors += 1;
        lock(totals).errors += 1;
    }

    /// Set the camera from the HTTP API (fields optional).
    pub fn set_camera(&self, json: &CameraJson) -> Result<Camera, String> {
        let mut v = lock(&self.view);
        let camera = json.apply(&v.camera);
        if let Some(p) = camera_problem(&camera) {
            return Err(p.to_string());
        }
        v.camera = camera;
        v.version += 1;
        v.last_input = Instant::now();
        drop(v);
        self.wake.notify_one();
        Ok(camera)
    }

    /// Set the full resolution from the HTTP API.
    pub fn set_full(&self, full: (u32, u32)) {
        let mut v = lock(&self.view);
        v.full = full;
        v.version += 1;
        drop(v);
        self.wake.notify_one();
    }

    /// Apply a client message received at `now`. Acknowledgements clear the
    /// frame in flight; inputs change the camera or settings, validated
    /// against the limits (an invalid one changes nothing).
    pub fn apply(
        &self,
        seq: Option<u64>,
        message: &ClientMessage,
        world: &World,
        config: &ServeConfig,
        now: Instant,
    ) -> Result<(), String> {
        let mut v = lock(&self.view);
        if let ClientMessage::Ack { frame } = *message {
            if v.in_flight != Some(frame) {
                return Err(format!(
                    "ack for frame {frame}, but the frame awaiting an ack is {}",
                    v.in_flight.map_or("none".to_string(), |f| f.to_string())
                ));
            }
            v.in_flight = None;
            drop(v);
            self.wake.notify_one();
            return Ok(());
        }
        let finite = |xs: &[f32], bound: f32| {
            if xs.iter().all(|x| x.is_finite() && x.abs() <= bound) {
                Ok(())
            } else {
                Err(format!("numbers must be finite and within ±{bound}"))
            }
        };
        let c = v.camera;
        let mut settings_changed = false;
        let camera = match *message {
            ClientMessage::Ack { .. } => unreachable!("handled above"),
            ClientMessage::Orbit { yaw, pitch } => {
                finite(&[yaw, pitch], 100.0)?;
                orbit(&c, yaw, pitch)
            }
            ClientMessage::Pan { x, y } => {
                finite(&[x, y], 10.0)?;
                pan(&c, x, y)
            }
            ClientMessage::Zoom { factor } => {
                if !(0.01..=100.0).contains(&factor) {
                    return Err(format!("zoom factor {factor} outside 0.01..=100"));
                }
                zoom(&c, factor, world.geometry.scale() * 1e-4)
            }
            ClientMessage::Fly { forward, right, up } => {
                finite(&[forward, right, up], 10.0)?;
                fly(&c, forward, right, up, world.geometry.scale())
            }
            ClientMessage::Orient { alpha, beta, gamma } => {
                finite(&[alpha, beta, gamma], 720.0)?;
                orient(&c, alpha, beta, gamma)
            }
            ClientMessage::Camera(json) => json.apply(&c),
            ClientMessage::Reset {} => world.camera,
            ClientMessage::Settings(s) => {
                apply_settings(&mut v, &s, config)?;
                settings_changed = true;
                c
            }
        };
        if let Some(p) = camera_problem(&camera) {
            return Err(format!("{p} (the camera was left unchanged)"));
        }
        v.camera = camera;
        v.version += 1;
        if !settings_changed {
            v.last_input = now;
        }
        if let Some(s) = seq {
            v.input_seq = v.input_seq.max(s);
        }
        if v.pending.len() < MAX_PENDING_INPUTS {
            v.pending.push(now);
        }
        drop(v);
        lock(&self.stats).inputs += 1;
        self.wake.notify_one();
        Ok(())
    }
}

fn apply_settings(v: &mut View, s: &SettingsJson, config: &ServeConfig) -> Result<(), String> {
    let full = (s.width.unwrap_or(v.full.0), s.height.unwrap_or(v.full.1));
    if let Some(p) = config.size_problem(full.0, full.1) {
        return Err(p);
    }
    let quality = s.quality.unwrap_or(v.quality);
    if !(1..=100).contains(&quality) {
        return Err(format!("quality {quality} outside 1..=100"));
    }
    let spp = s.spp.unwrap_or(v.spp);
    if !(1..=config.max_spp).contains(&spp) {
        return Err(format!("spp {spp} outside 1..={}", config.max_spp));
    }
    (v.full, v.quality, v.spp) = (full, quality, spp);
    v.format = s.format.unwrap_or(v.format);
    v.previews = s.previews.unwrap_or(v.previews);
    Ok(())
}
