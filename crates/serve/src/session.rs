//! One client's view and its render loop: inputs move the camera, frames go
//! out one at a time (the next only after the client acknowledges the last,
//! and then the latest view, never a backlog), refining from a half-size
//! preview while the camera moves to full size and more samples when it
//! stops.

use crate::app::AppState;
use crate::client::{ClientShared, View};
use crate::config::ServeConfig;
use crate::frame::FrameRequest;
use crate::protocol::{encode_frame, CameraJson, FrameHeader, Stage};
use crate::sync::lock;
use crate::world::World;
use serde_json::json;
use std::sync::Arc;
use std::time::Instant;
use tokio::sync::mpsc;

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
                    .render(FrameRequest {
                        world: world.clone(),
                        camera,
                        size,
                        spp,
                        format: snapshot.format,
                        quality: snapshot.quality,
                    })
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
    use crate::camera_control::orbit;
    use crate::protocol::{ClientMessage, SettingsJson};
    use std::time::Duration;

    fn world() -> World {
        crate::world::cornell_world((64, 36))
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
