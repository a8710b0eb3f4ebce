//! Rendering frames (in bands, taking turns between clients) and encoding
//! them as JPEG or sending their raw RGB.

use crate::protocol::FrameFormat;
use crate::world::World;
use jpeg_encoder::{ColorType, Encoder};
use raykit_core::Camera;
use raykit_render::{render, RenderOptions, Tile};
use std::collections::VecDeque;
use std::sync::{Arc, Condvar, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::oneshot;

/// A rendered, encoded frame.
pub struct EncodedFrame {
    /// Baseline JPEG bytes, or raw RGB rows.
    pub payload: Vec<u8>,
    /// Render time, ms.
    pub render_ms: f64,
    /// Encoding time, ms.
    pub encode_ms: f64,
}

/// What a frame is: the world and camera it shows, its size, samples per
/// pixel and payload format. Frames are rendered by `raykit_render::render`,
/// the quick one-bounce renderer (Blinn-Phong direct light with shadow rays,
/// the sky behind), not `raykit render`'s Whitted tracer: mirrors and glass
/// get their Blinn-Phong terms only, without reflection or refraction (in
/// `builtin:whitted` the mirror box is black but for highlights, the glass
/// sphere opaque white).
#[derive(Clone)]
pub struct FrameRequest {
    /// The scene, lights and BVH to render.
    pub world: Arc<World>,
    /// The camera to render through.
    pub camera: Camera,
    /// Width and height in pixels.
    pub size: (u32, u32),
    /// Samples per pixel.
    pub spp: u32,
    /// JPEG or raw RGB.
    pub format: FrameFormat,
    /// JPEG quality, 1..=100.
    pub quality: u8,
}

impl FrameRequest {
    /// The renderer's options for the rows of `window` (the whole frame
    /// when `None`).
    fn options(&self, window: Option<Tile>) -> RenderOptions {
        RenderOptions {
            width: self.size.0,
            height: self.size.1,
            samples_per_pixel: self.spp,
            window,
            ..RenderOptions::default()
        }
    }

    /// The RGB rows of `window` (the whole frame when `None`).
    fn render_rgb(&self, window: Option<Tile>) -> Vec<u8> {
        let g = &self.world.geometry;
        render(
            &g.scene.mesh,
            &self.world.lights,
            g.accel.as_ref(),
            &self.camera,
            &self.options(window),
            &|_| {},
        )
        .rgb
    }

    /// The payload of the whole frame's RGB rows: JPEG-encoded at the
    /// request's quality, or the rows as they are ([`FrameFormat`]).
    fn payload(&self, rgb: Vec<u8>) -> Vec<u8> {
        match self.format {
            FrameFormat::Jpeg => encode_jpeg(&rgb, self.size.0, self.size.1, self.quality),
            FrameFormat::Raw => rgb,
        }
    }

    /// Samples the frame takes: pixels × samples per pixel.
    pub fn samples(&self) -> u64 {
        self.size.0 as u64 * self.size.1 as u64 * self.spp.max(1) as u64
    }

    /// How many horizontal bands ([`Tile::band`]) the frame is rendered in
    /// so that none takes more than `slice_samples` samples (but for a
    /// single row that takes more): the fewest such bands, at least one.
    pub fn bands(&self, slice_samples: u64) -> u32 {
        let row = self.size.0 as u64 * self.spp.max(1) as u64;
        let rows = (slice_samples / row.max(1)).max(1);
        (self.size.1 as u64).div_ceil(rows).max(1) as u32
    }
}

/// A frame being rendered band by band.
struct Job {
    request: FrameRequest,
    /// Bands in all, and the next to render.
    bands: u32,
    next: u32,
    /// The rows rendered so far, top to bottom.
    rgb: Vec<u8>,
    /// Time spent rendering its bands.
    render: Duration,
    reply: oneshot::Sender<EncodedFrame>,
}

/// The frames waiting for a render thread, in turn.
#[derive(Default)]
struct Queue {
    jobs: VecDeque<Job>,
    closed: bool,
}

/// Frames are rendered by a few dedicated threads in slices: horizontal
/// bands of at most a slice's samples each (pixels × samples per pixel),
/// which assemble bit for bit into the whole frame (`RenderOptions::window`).
/// Frames take turns a band at a time (round robin): a thread renders the
/// next band of the frame at the front of the queue and puts the frame back
/// at the end if it has more. A frame is never in two threads at once, and
/// each client has at most one frame rendering, so a client's frame waits
/// for at most one band of every other client's frame per band of its own:
/// one client asking for the largest size and samples slows the others'
/// frames in proportion to the number of clients rendering, instead of
/// making them wait for its whole frame. Each band spreads its tiles over
/// the rayon pool; a fixed set of threads does not oversubscribe the cores
/// and keeps every frame allocation on a few threads, so the allocator's
/// per-thread arenas (and the server's memory) do not grow with the number
/// of clients.
pub struct RenderQueue {
    queue: Arc<(Mutex<Queue>, Condvar)>,
    slice_samples: u64,
}

impl RenderQueue {
    /// A queue served by `threads` threads (at least 1), rendering slices
    /// of at most `slice_samples` samples; the threads end when the queue
    /// is dropped.
    pub fn new(threads: usize, slice_samples: u64) -> Self {
        let queue = Arc::new((Mutex::new(Queue::default()), Condvar::new()));
        for i in 0..threads.max(1) {
            let queue = queue.clone();
            std::thread::Builder::new()
                .name(format!("raykit-render-{i}"))
                .spawn(move || work(&queue))
                .expect("cannot start a render thread");
        }
        RenderQueue {
            queue,
            slice_samples: slice_samples.max(1),
        }
    }

    /// Most samples one slice renders.
    pub fn slice_samples(&self) -> u64 {
        self.slice_samples
    }

    /// The frame `request` asks for, rendered in turn with every other
    /// frame (see [`RenderQueue`]) and awaited without blocking an async
    /// worker; `None` if a band's render panicked (the thread survives it).
    /// Dropping the future cancels the rest of the render.
    pub async fn render(&self, request: FrameRequest) -> Option<EncodedFrame> {
        let (reply, rx) = oneshot::channel();
        let bands = request.bands(self.slice_samples);
        let rgb = Vec::with_capacity(3 * request.size.0 as usize * request.size.1 as usize);
        let job = Job {
            request,
            bands,
            next: 0,
            rgb,
            render: Duration::ZERO,
            reply,
        };
        let (lock, ready) = &*self.queue;
        {
            let mut q = lock.lock().unwrap_or_else(|e| e.into_inner());
            if q.closed {
                return None;
            }
            q.jobs.push_back(job);
        }
        ready.notify_one();
        rx.await.ok()
    }
}

impl Drop for RenderQueue {
    fn drop(&mut self) {
        let (lock, ready) = &*self.queue;
        let mut q = lock.lock().unwrap_or_else(|e| e.into_inner());
        q.closed = true;
        q.jobs.clear();
        drop(q);
        ready.notify_all();
    }
}

/// A render thread: the next band of the frame at the front, until the
/// queue closes.
fn work(queue: &(Mutex<Queue>, Condvar)) {
    let (lock, ready) = queue;
    loop {
        let mut job = {
            let mut q = lock.lock().unwrap_or_else(|e| e.into_inner());
            loop {
                if q.closed {
                    return;
                }
                if let Some(job) = q.jobs.pop_front() {
                    break job;
                }
                q = ready.wait(q).unwrap_or_else(|e| e.into_inner());
            }
        };
        // Whoever asked has gone (session ended, stream dropped): skip.
        if job.reply.is_closed() {
            continue;
        }
        let (w, h) = job.request.size;
        let band = Tile::band(job.next, job.bands, w, h);
        let start = Instant::now();
        let rows = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
            job.request.render_rgb(band)
        }));
        // A panic drops the job, and with it the reply: the caller gets None.
        let Ok(rows) = rows else { continue };
        job.render += start.elapsed();
        job.rgb.extend_from_slice(&rows);
        job.next += 1;
        if job.next < job.bands {
            let mut q = lock.lock().unwrap_or_else(|e| e.into_inner());
            if !q.closed {
                q.jobs.push_back(job);
                drop(q);
                ready.notify_one();
            }
            continue;
        }
        let Job {
            request,
            rgb,
            render,
            reply,
            ..
        } = job;
        let encoding = Instant::now();
        let payload =
            std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| request.payload(rgb)));
        if let Ok(payload) = payload {
            let _ = reply.send(EncodedFrame {
                payload,
                render_ms: render.as_secs_f64() * 1e3,
                encode_ms: encoding.elapsed().as_secs_f64() * 1e3,
            });
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn world() -> Arc<World> {
        Arc::new(crate::world::cornell_world((97, 61)))
    }

    fn request(size: (u32, u32), spp: u32) -> FrameRequest {
        let world = world();
        FrameRequest {
            camera: world.camera,
            world,
            size,
            spp,
            format: FrameFormat::Raw,
            quality: 90,
        }
    }

    /// The whole frame from the renderer, called directly.
    fn whole(r: &FrameRequest) -> Vec<u8> {
        let g = &r.world.geometry;
        let opts = RenderOptions {
            width: r.size.0,
            height: r.size.1,
            samples_per_pixel: r.spp,
            ..RenderOptions::default()
        };
        render(
            &g.scene.mesh,
            &r.world.lights,
            g.accel.as_ref(),
            &r.camera,
            &opts,
            &|_| {},
        )
        .rgb
    }

    #[test]
    fn bands_keep_each_slice_within_its_samples() {
        let r = request((97, 61), 3);
        assert_eq!(r.samples(), 97 * 61 * 3);
        assert_eq!(r.bands(u64::MAX), 1);
        assert_eq!(r.bands(r.samples()), 1);
        assert_eq!(r.bands(r.samples() - 1), 2);
        // One row a band when a row takes more than a slice.
        assert_eq!(r.bands(1), 61);
        for slice in [291, 300, 1000, 5000, 17000] {
            let n = r.bands(slice);
            for i in 0..n {
                let band = Tile::band(i, n, 97, 61).unwrap();
                assert!(band.pixels() * 3 <= slice, "{slice}: band {i} {band:?}");
            }
            // The fewest: one band fewer would need one over the slice.
            if n > 1 {
                let largest = (0..n - 1)
                    .map(|i| Tile::band(i, n - 1, 97, 61).unwrap().pixels())
                    .max()
                    .unwrap();
                assert!(largest * 3 > slice, "{slice}: {n} bands");
            }
        }
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn frames_rendered_in_bands_equal_the_whole_frame() {
        let queue = RenderQueue::new(2, 1000);
        for (size, spp) in [((97, 61), 1), ((97, 61), 3), ((16, 16), 1)] {
            let r = request(size, spp);
            let frame = queue.render(r.clone()).await.expect("rendered");
            assert!(r.bands(1000) > 1 || size == (16, 16));
            assert!(frame.payload == whole(&r), "{size:?} spp {spp}");
        }
        // JPEG frames are the encoding of the same pixels.
        let r = FrameRequest {
            format: FrameFormat::Jpeg,
            ..request((97, 61), 2)
        };
        let frame = queue.render(r.clone()).await.expect("rendered");
        assert_eq!(frame.payload, encode_jpeg(&whole(&r), 97, 61, 90));
    }

    #[tokio::test(flavor = "multi_thread", worker_threads = 2)]
    async fn a_small_frame_does_not_wait_for_a_large_one_asked_for_first() {
        // One render thread, and a large frame of hundreds of bands asked
        // for just before a small one: the small one takes its turn after
        // a band or two of the large one, not after all of them.
        let queue = RenderQueue::new(1, 4096);
        let large = request((512, 512), 16);
        assert!(large.bands(4096) >= 500);
        let large = queue.render(large);
        tokio::pin!(large);
        // The first poll puts it in the queue.
        assert!(futures_util::poll!(&mut large).is_pending());
        let small = request((32, 32), 1);
        let expected = whole(&small);
        let frame = tokio::select! {
            biased;
            small = queue.render(small) => small.expect("rendered"),
            _ = &mut large => panic!("the large frame was finished first"),
        };
        assert!(frame.payload == expected);
    }
}
