//! One client's view and its render loop: inputs move the camera, frames go
//! out one at a time (the next only after the client acknowledges the last,
//! and then the latest view, never a backlog), refining from a half-size
//! preview while the camera moves to full size and more samples when it
//! stops.

use crate::app::{lock, AppState};
use crate::camera_control::{camera_problem, fly, orbit, orient, pan, zoom};
use crate::config::ServeConfig;
use crate::protocol::{
    encode_frame, CameraJson, ClientMessage, FrameFormat, FrameHeader, SettingsJson, Stage,
};
use crate::stats::{ClientSample, ClientStats};
use crate::world::World;
use raykit_core::Camera;
use serde_json::json;
use std::sync::{Arc, Mutex};
use std::time::Instant;
use tokio::sync::{mpsc, Notify};

/// Most input arrival times remembered between two frames (for latency).
const MAX_PENDING_INPUTS: usize = 1024;

/// What a session sends to its connection.
#[derive(Debug)]
pub enum Outgoing {
    /// A JSON text message.
    Text(String),
    /// A frame: header and payload (see [`encode_frame`]).
    Frame(Vec<u8>),
    /// A WebSocket ping (liveness check).
    Ping,
}

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
    pub fn count_error(&self, state: &AppState) {
        lock(&self.stats).errors += 1;
        lock(&state.totals).errors += 1;
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
            ClientMessage::Reset => world.camera,
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

/// What the render loop does next.
enum Next {
    /// Render this stage now.
    Render(Stage),
    /// Sleep until woken, or until the instant.
    Wait(Option<Instant>),
}

/// Decide the next step for `v` in `world` at `now`.
fn next_step(v: &View, world: &World, settle: std::time::Duration, now: Instant) -> Next {
    if v.in_flight.is_some() {
        return Next::Wait(None);
    }
    match v.rendered {
        Some((view_version, world_version, stage))
            if view_version == v.version && world_version == world.look_version =>
        {
            match stage.next(v.spp) {
                None => Next::Wait(None),
                Some(next) => {
                    let due = v.last_input + settle;
                    if now >= due {
                        Next::Render(next)
                    } else {
                        Next::Wait(Some(due))
                    }
                }
            }
        }
        _ if v.previews => Next::Render(Stage::Preview),
        _ => Next::Render(Stage::Full),
    }
}

/// Render and send frames to one WebSocket client until `out` closes or the
/// server shuts down.
pub async fn render_loop(
    state: Arc<AppState>,
    client: Arc<ClientShared>,
    out: mpsc::Sender<Outgoing>,
) {
    let mut world_rx = state.watch_world();
    let mut shutdown = state.watch_shutdown();
    loop {
        if *shutdown.borrow() || out.is_closed() {
            return;
        }
        let world = state.world();
        // A new scene: the client's camera starts again from its default.
        let new_scene = {
            let mut v = lock(&client.view);
            (v.generation != world.geometry.generation).then(|| {
                v.generation = world.geometry.generation;
                v.camera = world.camera;
                v.version += 1;
            })
        };
        if new_scene.is_some() {
            let g = &world.geometry;
            let msg = json!({"type": "scene", "scene": g.scene.name,
                "triangles": g.scene.mesh.num_triangles(),
                "camera": CameraJson::from_camera(&world.camera)});
            if out.send(Outgoing::Text(msg.to_string())).await.is_err() {
                return;
            }
        }
        let step = next_step(
            &lock(&client.view),
            &world,
            state.config.settle,
            Instant::now(),
        );
        match step {
            Next::Wait(deadline) => {
                let sleep = async {
                    match deadline {
                        Some(d) => tokio::time::sleep_until(d.into()).await,
                        None => std::future::pending().await,
                    }
                };
                tokio::select! {
                    _ = client.wake.notified() => {}
                    _ = world_rx.changed() => {}
                    _ = shutdown.changed() => {}
                    _ = out.closed() => return,
                    _ = sleep => {}
                }
            }
            Next::Render(stage) => {
                let (snapshot, inputs) = {
                    let mut v = lock(&client.view);
                    let inputs = std::mem::take(&mut v.pending);
                    (v.clone(), inputs)
                };
                let (size, spp) = match stage {
                    Stage::Preview => (ServeConfig::preview_size(snapshot.full), 1),
                    Stage::Full => (snapshot.full, 1),
                    Stage::Refined => (snapshot.full, snapshot.spp),
                };
                let camera = snapshot.camera;
                let Some(encoded) = state
                    .renderer
                    .render(
                        world.clone(),
                        camera,
                        size,
                        spp,
                        snapshot.format,
                        snapshot.quality,
                    )
                    .await
                else {
                    return;
                };
                let now = Instant::now();
                let frame_no = {
                    let mut v = lock(&client.view);
                    v.frames += 1;
                    v.in_flight = Some(v.frames);
                    v.rendered = Some((snapshot.version, world.look_version, stage));
                    v.frames
                };
                let (fps, latency_ms, bytes_per_second) = {
                    let mut s = lock(&client.stats);
                    s.frame_sent(now, encoded.payload.len(), &inputs);
                    (s.fps(now), s.median_latency_ms(), s.bytes_per_second(now))
                };
                state.count_frame(
                    encoded.payload.len(),
                    (encoded.render_ms + encoded.encode_ms) * 1e-3,
                );
                let header = FrameHeader {
                    frame: frame_no,
                    width: size.0,
                    height: size.1,
                    spp,
                    stage,
                    input_seq: snapshot.input_seq,
                    camera: CameraJson::from_camera(&camera),
                    render_ms: encoded.render_ms,
                    format: snapshot.format,
                    encode_ms: encoded.encode_ms,
                    fps,
                    latency_ms,
                    bytes_per_second,
                };
                if out
                    .send(Outgoing::Frame(encode_frame(&header, &encoded.payload)))
                    .await
                    .is_err()
                {
                    return;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::world::Geometry;
    use std::time::Duration;

    fn world() -> World {
        let g = Arc::new(Geometry::new(raykit_scene::builtin("cornell").unwrap(), 1));
        World {
            lights: g.default_lights(),
            camera: g.default_camera(16.0 / 9.0),
            full: (64, 36),
            geometry: g,
            version: 1,
            look_version: 1,
        }
    }

    #[test]
    fn steps_follow_preview_full_refined_after_the_settle_time() {
        let w = world();
        let config = ServeConfig::default();
        let c = ClientShared::new(1, "ws", &w, &config);
        let t0 = Instant::now();
        let settle = Duration::from_millis(150);
        let mut v = lock(&c.view).clone();
        v.last_input = t0;
        assert!(matches!(
            next_step(&v, &w, settle, t0),
            Next::Render(Stage::Preview)
        ));
        v.rendered = Some((v.version, w.look_version, Stage::Preview));
        v.in_flight = Some(1);
        assert!(matches!(next_step(&v, &w, settle, t0), Next::Wait(None)));
        v.in_flight = None;
        // Still moving: wait until the settle time has passed.
        match next_step(&v, &w, settle, t0 + Duration::from_millis(50)) {
            Next::Wait(Some(due)) => assert_eq!(due, t0 + settle),
            _ => panic!("expected a timed wait"),
        }
        assert!(matches!(
            next_step(&v, &w, settle, t0 + settle),
            Next::Render(Stage::Full)
        ));
        v.rendered = Some((v.version, w.look_version, Stage::Full));
        assert!(matches!(
            next_step(&v, &w, settle, t0 + settle),
            Next::Render(Stage::Refined)
        ));
        v.rendered = Some((v.version, w.look_version, Stage::Refined));
        assert!(matches!(
            next_step(&v, &w, settle, t0 + settle),
            Next::Wait(None)
        ));
        // Any change starts again from the preview, or from full size for
        // clients that turned previews off.
        v.version += 1;
        assert!(matches!(
            next_step(&v, &w, settle, t0 + settle),
            Next::Render(Stage::Preview)
        ));
        v.previews = false;
        assert!(matches!(
            next_step(&v, &w, settle, t0),
            Next::Render(Stage::Full)
        ));
    }

    #[test]
    fn inputs_are_validated_and_acks_must_match() {
        let w = world();
        let config = ServeConfig::default();
        let c = ClientShared::new(1, "ws", &w, &config);
        let now = Instant::now();
        let before = lock(&c.view).camera;
        assert!(c
            .apply(
                Some(1),
                &ClientMessage::Zoom { factor: 0.0 },
                &w,
                &config,
                now
            )
            .is_err());
        let huge = ClientMessage::Settings(SettingsJson {
            width: Some(100_000),
            ..Default::default()
        });
        assert!(c.apply(None, &huge, &w, &config, now).is_err());
        let bad = ClientMessage::Camera(CameraJson {
            eye: Some(before.target.to_array()),
            ..Default::default()
        });
        assert!(c.apply(None, &bad, &w, &config, now).is_err());
        assert_eq!(lock(&c.view).camera, before);
        assert_eq!(lock(&c.view).version, 1);
        c.apply(
            Some(5),
            &ClientMessage::Orbit {
                yaw: 0.1,
                pitch: 0.0,
            },
            &w,
            &config,
            now,
        )
        .unwrap();
        let v = lock(&c.view).clone();
        assert_eq!((v.version, v.input_seq, v.pending.len()), (2, 5, 1));
        assert_eq!(v.camera, orbit(&before, 0.1, 0.0));
        assert!(c
            .apply(None, &ClientMessage::Ack { frame: 1 }, &w, &config, now)
            .is_err());
        lock(&c.view).in_flight = Some(1);
        c.apply(None, &ClientMessage::Ack { frame: 1 }, &w, &config, now)
            .unwrap();
        assert_eq!(lock(&c.view).in_flight, None);
    }
}
