//! Measuring a stream over a network link: one client asks for every frame
//! at one size and format (full size while moving, one sample per pixel),
//! orbits the camera, acknowledges each frame, and reports frames per
//! second, bytes per frame, the bit rate and input-to-frame latency
//! percentiles — the figures by which remote rendering to a handheld over
//! 802.11g was judged (the remote-rendering paper after Purcell et al. 2002).

use crate::load::{percentile, run_load, LoadOptions};
use crate::protocol::{FrameFormat, SettingsJson, Stage};
use crate::stats::median;
use anyhow::{bail, Result};
use serde::Serialize;
use std::time::Duration;

/// What to measure.
#[derive(Clone, Debug)]
pub struct LinkOptions {
    /// `ws://host:port/ws[?token=T]`.
    pub url: String,
    /// Frame size asked for.
    pub size: (u32, u32),
    /// Payload format asked for.
    pub format: FrameFormat,
    /// JPEG quality to ask for (`None`: the server's default).
    pub quality: Option<u8>,
    /// Seconds the camera moves; frames are counted after `warmup`.
    pub seconds: f64,
    /// Seconds at the start that are not counted (the settings take effect,
    /// TCP's window opens).
    pub warmup: f64,
    /// Orbit inputs per second (more than the frame rate keeps every frame
    /// a new view).
    pub input_hz: f64,
}

/// What one link measurement found, over the counted window.
#[derive(Clone, Debug, Serialize)]
pub struct LinkReport {
    /// Server address.
    pub url: String,
    /// Frame width.
    pub width: u32,
    /// Frame height.
    pub height: u32,
    /// Payload format.
    pub format: FrameFormat,
    /// Counted window, seconds.
    pub seconds: f64,
    /// Frames of the asked size and format in the window.
    pub frames: usize,
    /// Frames per second.
    pub fps: f64,
    /// Mean payload bytes per frame.
    pub payload_bytes_per_frame: f64,
    /// Mean message bytes per frame (payload and header).
    pub message_bytes_per_frame: f64,
    /// Message bits per second, in millions (without WebSocket, TCP and IP
    /// framing).
    pub mbit_per_second: f64,
    /// Input-to-frame latency, median, ms.
    pub latency_p50_ms: Option<f64>,
    /// Input-to-frame latency, 95th percentile, ms.
    pub latency_p95_ms: Option<f64>,
    /// Input-to-frame latency, 99th percentile, ms.
    pub latency_p99_ms: Option<f64>,
    /// Server render time per frame, median, ms.
    pub render_ms_median: Option<f64>,
    /// Frames in the window of another size or format (the server ignored
    /// the settings if this is not 0).
    pub other_frames: usize,
    /// Error messages and failures.
    pub errors: Vec<String>,
}

impl LinkOptions {
    /// Why the options cannot be measured, if they cannot.
    pub fn problem(&self) -> Option<String> {
        if !(self.seconds.is_finite() && self.seconds > 0.0 && self.seconds <= 3600.0) {
            return Some(format!("seconds {} outside (0, 3600]", self.seconds));
        }
        if !(self.warmup.is_finite() && self.warmup >= 0.0 && self.warmup < self.seconds) {
            return Some(format!(
                "warm-up {} s must be at least 0 and shorter than the {} s run",
                self.warmup, self.seconds
            ));
        }
        if !(self.input_hz.is_finite() && self.input_hz > 0.0 && self.input_hz <= 1000.0) {
            return Some(format!("input rate {} outside (0, 1000] Hz", self.input_hz));
        }
        if self.size.0 == 0 || self.size.1 == 0 {
            return Some(format!("size {}x{} is empty", self.size.0, self.size.1));
        }
        None
    }
}

/// Connect one client to `opts.url`, ask for full-size frames of one
/// sample in `opts.format`, orbit for `opts.seconds`, and report the window
/// after the warm-up.
pub async fn measure_link(opts: &LinkOptions) -> Result<LinkReport> {
    if let Some(p) = opts.problem() {
        bail!("{p}");
    }
    let settings = SettingsJson {
        width: Some(opts.size.0),
        height: Some(opts.size.1),
        quality: opts.quality,
        spp: Some(1),
        format: Some(opts.format),
        previews: Some(false),
    };
    let reports = run_load(&LoadOptions {
        url: opts.url.clone(),
        clients: 1,
        moving: Duration::from_secs_f64(opts.seconds),
        still: Duration::ZERO,
        input_hz: opts.input_hz,
        settings: Some(settings),
    })
    .await?;
    let r = &reports[0];
    let (from, to) = (opts.warmup, opts.seconds);
    let in_window: Vec<_> = r
        .frames
        .iter()
        .filter(|f| f.at_s >= from && f.at_s < to)
        .collect();
    let (asked, other): (Vec<_>, Vec<_>) = in_window.into_iter().partition(|f| {
        (f.width, f.height, f.format) == (opts.size.0, opts.size.1, opts.format)
            && f.stage == Stage::Full
    });
    let window = to - from;
    let n = asked.len();
    let mean_of = |total: usize| if n == 0 { 0.0 } else { total as f64 / n as f64 };
    let payload: usize = asked.iter().map(|f| f.bytes).sum();
    let message: usize = asked.iter().map(|f| f.message_bytes).sum();
    let latencies: Vec<f64> = r
        .latencies_ms
        .iter()
        .zip(&r.latencies_at_s)
        .filter(|&(_, &at)| at >= from && at < to)
        .map(|(&l, _)| l)
        .collect();
    Ok(LinkReport {
        url: opts.url.clone(),
        width: opts.size.0,
        height: opts.size.1,
        format: opts.format,
        seconds: window,
        frames: n,
        fps: n as f64 / window,
        payload_bytes_per_frame: mean_of(payload),
        message_bytes_per_frame: mean_of(message),
        mbit_per_second: message as f64 * 8.0 / window / 1e6,
        latency_p50_ms: percentile(&latencies, 50.0),
        latency_p95_ms: percentile(&latencies, 95.0),
        latency_p99_ms: percentile(&latencies, 99.0),
        render_ms_median: median(asked.iter().map(|f| f.render_ms).collect()),
        other_frames: other.len(),
        errors: r.errors.clone(),
    })
}
