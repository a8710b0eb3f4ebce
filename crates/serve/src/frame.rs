//! Rendering one frame and encoding it as JPEG or sending its raw RGB.

use crate::protocol::FrameFormat;
use crate::world::World;
use jpeg_encoder::{ColorType, Encoder};
use raykit_core::Camera;
use raykit_render::{render, RenderOptions};
use std::time::Instant;

/// A rendered, encoded frame.
pub struct EncodedFrame {
    /// Baseline JPEG bytes, or raw RGB rows.
    pub payload: Vec<u8>,
    /// Render time, ms.
    pub render_ms: f64,
    /// Encoding time, ms.
    pub encode_ms: f64,
}

/// Render `world` through `camera` at `width` × `height` with `spp`
/// samples (the renderer of `raykit render`: Blinn-Phong, shadow rays) on
/// the rayon pool, then JPEG-encode at `quality` or keep the RGB as it is
/// ([`FrameFormat`]). Blocking: call it from a blocking task.
pub fn render_frame(
    world: &World,
    camera: &Camera,
    (width, height): (u32, u32),
    spp: u32,
    format: FrameFormat,
    quality: u8,
) -> EncodedFrame {
    let start = Instant::now();
    let opts = RenderOptions {
        width,
        height,
        samples_per_pixel: spp,
        ..RenderOptions::default()
    };
    let g = &world.geometry;
    let image = render(
        &g.scene.mesh,
        &world.lights,
        g.accel.as_ref(),
        camera,
        &opts,
        &|_| {},
    );
    let rendered = Instant::now();
    let payload = match format {
        FrameFormat::Jpeg => encode_jpeg(&image.rgb, width, height, quality),
        FrameFormat::Raw => image.rgb,
    };
    EncodedFrame {
        payload,
        render_ms: (rendered - start).as_secs_f64() * 1e3,
        encode_ms: rendered.elapsed().as_secs_f64() * 1e3,
    }
}

type Job = Box<dyn FnOnce() + Send>;

/// Frames waiting to be rendered, first come first served, by a few
/// dedicated threads (each render still spreads its tiles over the rayon
/// pool). A fixed queue keeps clients fair (no render steals another's
/// turn), does not oversubscribe the cores, and keeps every frame
/// allocation on a few threads, so the allocator's per-thread arenas (and
/// the server's memory) do not grow with the number of clients.
pub struct RenderQueue {
    jobs: std::sync::mpsc::Sender<Job>,
}

impl RenderQueue {
    /// A queue served by `threads` threads (at least 1); they end when the
    /// queue is dropped.
    pub fn new(threads: usize) -> Self {
        let (jobs, rx) = std::sync::mpsc::channel::<Job>();
        let rx = std::sync::Arc::new(std::sync::Mutex::new(rx));
        for i in 0..threads.max(1) {
            let rx = rx.clone();
            std::thread::Builder::new()
                .name(format!("raykit-render-{i}"))
                .spawn(move || loop {
                    let job = match rx.lock().unwrap_or_else(|e| e.into_inner()).recv() {
                        Ok(job) => job,
                        Err(_) => return,
                    };
                    job();
                })
                .expect("cannot start a render thread");
        }
        RenderQueue { jobs }
    }

    /// [`render_frame`] in turn, awaited without blocking an async worker;
    /// `None` if the render panicked (the thread survives it). Dropping the
    /// future before the turn comes cancels the render.
    pub async fn render(
        &self,
        world: std::sync::Arc<World>,
        camera: Camera,
        size: (u32, u32),
        spp: u32,
        format: FrameFormat,
        quality: u8,
    ) -> Option<EncodedFrame> {
        let (tx, rx) = tokio::sync::oneshot::channel();
        let job: Job = Box::new(move || {
            // Whoever asked has gone (session ended, stream dropped): skip.
            if tx.is_closed() {
                return;
            }
            let frame = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
                render_frame(&world, &camera, size, spp, format, quality)
            }));
            if let Ok(frame) = frame {
                let _ = tx.send(frame);
            }
        });
        self.jobs.send(job).ok()?;
        rx.await.ok()
    }
}

/// Baseline JPEG of 8-bit RGB rows (sizes up to 65535, which the server's
/// limits keep below).
pub fn encode_jpeg(rgb: &[u8], width: u32, height: u32, quality: u8) -> Vec<u8> {
    let mut out = Vec::with_capacity(rgb.len() / 8);
    Encoder::new(&mut out, quality.clamp(1, 100))
        .encode(rgb, width as u16, height as u16, ColorType::Rgb)
        .expect("in-memory JPEG encoding of a size within limits");
    out
}
