//! A load-test client: N WebSocket clients on one server, each orbiting its
//! camera at a fixed input rate and acknowledging every frame, recording
//! what arrived, when, and how long each input took to show.

use crate::protocol::{decode_frame, FrameFormat, SettingsJson, Stage};
use crate::stats::median;
use anyhow::{bail, Context, Result};
use futures_util::{SinkExt, StreamExt};
use serde::Serialize;
use std::collections::VecDeque;
use std::time::{Duration, Instant};
use tokio_tungstenite::tungstenite::protocol::WebSocketConfig;
use tokio_tungstenite::tungstenite::Message;

/// Largest frame message a load client accepts: a raw 3840×2160 frame
/// (about 25 MB) with room to spare.
pub const MAX_FRAME_MESSAGE_BYTES: usize = 64 << 20;

/// What each simulated client does.
#[derive(Clone, Debug)]
pub struct LoadOptions {
    /// `ws://host:port/ws[?token=T]`.
    pub url: String,
    /// Number of clients.
    pub clients: usize,
    /// How long each client sends inputs (the camera moves).
    pub moving: Duration,
    /// How long each client then stays connected without input.
    pub still: Duration,
    /// Inputs per second while moving (orbit steps of 0.02 rad).
    pub input_hz: f64,
    /// Settings sent once after connecting (size, format, previews), if
    /// any.
    pub settings: Option<SettingsJson>,
}

/// One frame as a client saw it.
#[derive(Clone, Debug, Serialize)]
pub struct FrameRecord {
    /// Seconds since the client connected.
    pub at_s: f64,
    /// Refinement stage.
    pub stage: Stage,
    /// Size.
    pub width: u32,
    /// Size.
    pub height: u32,
    /// Payload format.
    pub format: FrameFormat,
    /// Payload bytes.
    pub bytes: usize,
    /// Whole message bytes (header included).
    pub message_bytes: usize,
    /// Server render time, ms.
    pub render_ms: f64,
}

/// What one client got.
#[derive(Clone, Debug, Default, Serialize)]
pub struct ClientReport {
    /// Frames in arrival order.
    pub frames: Vec<FrameRecord>,
    /// Input-to-frame latencies measured by the client, ms.
    pub latencies_ms: Vec<f64>,
    /// When the frame showing each input of `latencies_ms` arrived, seconds
    /// since the client connected.
    pub latencies_at_s: Vec<f64>,
    /// Inputs sent.
    pub inputs: u64,
    /// Error messages and failures.
    pub errors: Vec<String>,
}

impl ClientReport {
    /// Frames per second over `[from, to)` seconds.
    pub fn fps_between(&self, from: f64, to: f64) -> f64 {
        let n = self
            .frames
            .iter()
            .filter(|f| f.at_s >= from && f.at_s < to)
            .count();
        n as f64 / (to - from).max(1e-9)
    }

    /// Seconds from `after` to the first frame of `stage` arriving later.
    pub fn first_after(&self, after: f64, stage: Stage) -> Option<f64> {
        self.frames
            .iter()
            .find(|f| f.at_s >= after && f.stage == stage)
            .map(|f| f.at_s - after)
    }
}

/// The `p`-th percentile (0..=100, nearest rank) of `values`.
pub fn percentile(values: &[f64], p: f64) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    let mut v = values.to_vec();
    v.sort_by(f64::total_cmp);
    let rank = ((p / 100.0) * v.len() as f64).ceil().max(1.0) as usize;
    Some(v[rank.min(v.len()) - 1])
}

/// Median of the client's latencies.
pub fn median_latency(report: &ClientReport) -> Option<f64> {
    median(report.latencies_ms.clone())
}

/// Run `opts.clients` clients at once and collect their reports.
pub async fn run_load(opts: &LoadOptions) -> Result<Vec<ClientReport>> {
    let tasks: Vec<_> = (0..opts.clients)
        .map(|i| {
            let o = opts.clone();
            tokio::spawn(async move { one_client(&o, i).await })
        })
        .collect();
    let mut out = Vec::new();
    for t in tasks {
        out.push(t.await.context("load client task")?);
    }
    Ok(out)
}

async fn one_client(opts: &LoadOptions, index: usize) -> ClientReport {
    let mut report = ClientReport::default();
    if let Err(e) = drive(opts, index, &mut report).await {
        report.errors.push(causes_once(&e));
    }
    report
}

/// `e` and its causes joined by ": ", each said once: a cause whose text the
/// line already holds (a WebSocket error that writes its I/O error into its
/// own message and also keeps it as its source) is left out.
fn causes_once(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let text = cause.to_string();
        if line.contains(&text) {
            continue;
        }
        if !line.is_empty() {
            line.push_str(": ");
        }
        line.push_str(&text);
    }
    line
}

async fn drive(opts: &LoadOptions, index: usize, report: &mut ClientReport) -> Result<()> {
    let config = WebSocketConfig::default()
        .max_message_size(Some(MAX_FRAME_MESSAGE_BYTES))
        .max_frame_size(Some(MAX_FRAME_MESSAGE_BYTES));
    let (mut ws, _) =
        tokio_tungstenite::connect_async_with_config(opts.url.as_str(), Some(config), true)
            .await
            .with_context(|| format!("connecting to {}", opts.url))?;
    if let Some(s) = &opts.settings {
        let mut msg = serde_json::to_value(s).context("settings to JSON")?;
        msg["type"] = "settings".into();
        ws.send(Message::text(msg.to_string()))
            .await
            .context("sending settings")?;
    }
    let start = Instant::now();
    let stop_moving = start + opts.moving;
    let end = stop_moving + opts.still;
    let period = Duration::from_secs_f64(1.0 / opts.input_hz.max(0.1));
    let mut tick = tokio::time::interval(period);
    let mut seq = 0u64;
    let mut sent: VecDeque<(u64, Instant)> = VecDeque::new();
    // Alternate directions between clients so their views differ.
    let yaw = if index.is_multiple_of(2) { 0.02 } else { -0.02 };
    loop {
        let deadline = tokio::time::sleep_until(end.into());
        tokio::select! {
            _ = deadline => break,
            _ = tick.tick(), if Instant::now() < stop_moving => {
                seq += 1;
                let msg = format!(r#"{{"type":"orbit","yaw":{yaw},"pitch":0,"seq":{seq}}}"#);
                ws.send(Message::text(msg)).await.context("sending input")?;
                sent.push_back((seq, Instant::now()));
                report.inputs += 1;
            }
            msg = ws.next() => {
                let Some(msg) = msg else { bail!("server closed the connection") };
                match msg.context("receiving")? {
                    Message::Binary(b) => {
                        let now = Instant::now();
                        let (h, payload) = decode_frame(&b).map_err(anyhow::Error::msg)?;
                        while sent.front().is_some_and(|&(s, _)| s <= h.input_seq) {
                            let (_, t) = sent.pop_front().expect("front exists");
                            report.latencies_ms.push((now - t).as_secs_f64() * 1e3);
                            report.latencies_at_s.push((now - start).as_secs_f64());
                        }
                        report.frames.push(FrameRecord {
                            at_s: (now - start).as_secs_f64(),
                            stage: h.stage,
                            width: h.width,
                            height: h.height,
                            format: h.format,
                            bytes: payload.len(),
                            message_bytes: b.len(),
                            render_ms: h.render_ms,
                        });
                        let ack = format!(r#"{{"type":"ack","frame":{}}}"#, h.frame);
                        ws.send(Message::text(ack)).await.context("sending ack")?;
                    }
                    Message::Text(t) if t.contains(r#""type":"error""#) => {
                        report.errors.push(t.to_string());
                    }
                    Message::Close(c) => bail!("server closed the connection: {c:?}"),
                    _ => {}
                }
            }
        }
    }
    let _ = ws.close(None).await;
    Ok(())
}

/// Resident memory of this process in KiB (Linux `/proc/self/status`), if
/// known.
pub fn rss_kib() -> Option<u64> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    status
        .lines()
        .find_map(|l| l.strip_prefix("VmRSS:"))
        .and_then(|v| v.trim().trim_end_matches("kB").trim().parse().ok())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn percentiles_by_nearest_rank() {
        let v: Vec<f64> = (1..=10).map(f64::from).collect();
        assert_eq!(percentile(&v, 50.0), Some(5.0));
        assert_eq!(percentile(&v, 90.0), Some(9.0));
        assert_eq!(percentile(&v, 99.0), Some(10.0));
        assert_eq!(percentile(&v, 0.0), Some(1.0));
        assert_eq!(percentile(&[], 50.0), None);
    }

    #[test]
    fn a_cause_written_into_its_error_is_said_once() {
        let refused = || std::io::Error::from(std::io::ErrorKind::ConnectionRefused);
        let ws = tokio_tungstenite::tungstenite::Error::Io(refused());
        let e = anyhow::Error::new(ws).context("connecting to ws://x/ws");
        let line = causes_once(&e);
        let io_text = refused().to_string();
        assert_eq!(line.matches(&io_text).count(), 1, "{line}");
        assert!(line.starts_with("connecting to ws://x/ws: "), "{line}");
        // Distinct causes all stay.
        let e = anyhow::Error::new(refused())
            .context("inner")
            .context("outer");
        assert_eq!(causes_once(&e), format!("outer: inner: {io_text}"));
    }
}
