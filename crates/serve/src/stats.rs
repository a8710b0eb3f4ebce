//! Per-client statistics (fps, input-to-frame latency, bytes/s) and the
//! Prometheus text exposition of them.

use std::collections::VecDeque;
use std::fmt::Write;
use std::time::{Duration, Instant};

/// Window over which fps and bytes/s are measured.
pub const RATE_WINDOW: Duration = Duration::from_secs(2);

/// Latencies kept for the median.
pub const LATENCY_WINDOW: usize = 256;

/// What a client has received and how quickly.
#[derive(Clone, Debug)]
pub struct ClientStats {
    /// When the client connected.
    pub connected: Instant,
    /// Frames sent.
    pub frames: u64,
    /// Frame bytes sent.
    pub bytes: u64,
    /// Input messages applied.
    pub inputs: u64,
    /// Messages answered with an error.
    pub errors: u64,
    /// Send time and size of the frames of the last [`RATE_WINDOW`].
    recent: VecDeque<(Instant, usize)>,
    /// Input-to-frame latencies of the last [`LATENCY_WINDOW`] inputs, ms.
    latencies: VecDeque<f64>,
}

impl ClientStats {
    /// Nothing received yet.
    pub fn new(now: Instant) -> Self {
        ClientStats {
            connected: now,
            frames: 0,
            bytes: 0,
            inputs: 0,
            errors: 0,
            recent: VecDeque::new(),
            latencies: VecDeque::new(),
        }
    }

    /// A frame of `bytes` sent at `now` that shows inputs received at
    /// `inputs`.
    pub fn frame_sent(&mut self, now: Instant, bytes: usize, inputs: &[Instant]) {
        self.frames += 1;
        self.bytes += bytes as u64;
        self.recent.push_back((now, bytes));
        self.trim(now);
        for &t in inputs {
            if self.latencies.len() == LATENCY_WINDOW {
                self.latencies.pop_front();
            }
            self.latencies
                .push_back(now.saturating_duration_since(t).as_secs_f64() * 1e3);
        }
    }

    fn trim(&mut self, now: Instant) {
        while let Some(&(t, _)) = self.recent.front() {
            if now.saturating_duration_since(t) > RATE_WINDOW {
                self.recent.pop_front();
            } else {
                break;
            }
        }
    }

    /// Length of the rate window at `now`: [`RATE_WINDOW`], or the time
    /// since connecting when shorter.
    fn window(&self, now: Instant) -> f64 {
        now.saturating_duration_since(self.connected)
            .min(RATE_WINDOW)
            .as_secs_f64()
            .max(1e-3)
    }

    /// Frames per second over the last [`RATE_WINDOW`].
    pub fn fps(&mut self, now: Instant) -> f64 {
        self.trim(now);
        self.recent.len() as f64 / self.window(now)
    }

    /// Bytes per second over the last [`RATE_WINDOW`].
    pub fn bytes_per_second(&mut self, now: Instant) -> f64 {
        self.trim(now);
        self.recent.iter().map(|&(_, b)| b as f64).sum::<f64>() / self.window(now)
    }

    /// Median latency of the last inputs, ms.
    pub fn median_latency_ms(&self) -> Option<f64> {
        median(self.latencies.iter().copied().collect())
    }
}

/// Median of `values` (mean of the middle two for an even count).
pub fn median(mut values: Vec<f64>) -> Option<f64> {
    if values.is_empty() {
        return None;
    }
    values.sort_by(f64::total_cmp);
    let n = values.len();
    Some(if n % 2 == 1 {
        values[n / 2]
    } else {
        0.5 * (values[n / 2 - 1] + values[n / 2])
    })
}

/// One client's line in the metrics.
pub struct ClientSample {
    /// Client id.
    pub id: u64,
    /// `ws` or `mjpeg`.
    pub kind: &'static str,
    /// Stats at sampling time.
    pub fps: f64,
    /// Median latency, ms.
    pub latency_ms: Option<f64>,
    /// Bytes per second.
    pub bytes_per_second: f64,
    /// Totals.
    pub frames: u64,
    /// Inputs applied.
    pub inputs: u64,
    /// Errors answered.
    pub errors: u64,
}

/// Server-wide counters.
#[derive(Clone, Copy, Debug, Default)]
pub struct Totals {
    /// Frames sent to all clients.
    pub frames: u64,
    /// Frame bytes sent.
    pub bytes: u64,
    /// Connections refused (client limit, token).
    pub rejected: u64,
    /// Messages answered with an error.
    pub errors: u64,
    /// Seconds spent rendering and encoding.
    pub render_seconds: f64,
    /// Scenes loaded.
    pub scenes_loaded: u64,
}

/// The Prometheus text format (version 0.0.4) of `clients` and `totals`.
pub fn prometheus(clients: &[ClientSample], totals: &Totals, triangles: usize) -> String {
    let mut s = String::new();
    let mut family = |name: &str, kind: &str, help: &str, lines: Vec<(String, f64)>| {
        let _ = writeln!(s, "# HELP {name} {help}\n# TYPE {name} {kind}");
        for (labels, v) in lines {
            let _ = writeln!(s, "{name}{labels} {v}");
        }
    };
    let per = |f: &dyn Fn(&ClientSample) -> Option<f64>| -> Vec<(String, f64)> {
        clients
            .iter()
            .filter_map(|c| {
                f(c).map(|v| (format!("{{client=\"{}\",kind=\"{}\"}}", c.id, c.kind), v))
            })
            .collect()
    };
    family(
        "raykit_clients",
        "gauge",
        "Connected clients.",
        vec![(String::new(), clients.len() as f64)],
    );
    family(
        "raykit_scene_triangles",
        "gauge",
        "Triangles in the loaded scene.",
        vec![(String::new(), triangles as f64)],
    );
    family(
        "raykit_frames_total",
        "counter",
        "Frames sent to all clients.",
        vec![(String::new(), totals.frames as f64)],
    );
    family(
        "raykit_frame_bytes_total",
        "counter",
        "JPEG frame bytes sent.",
        vec![(String::new(), totals.bytes as f64)],
    );
    family(
        "raykit_render_seconds_total",
        "counter",
        "Time spent rendering and encoding frames.",
        vec![(String::new(), totals.render_seconds)],
    );
    family(
        "raykit_rejected_connections_total",
        "counter",
        "Connections refused for the client limit or a missing token.",
        vec![(String::new(), totals.rejected as f64)],
    );
    family(
        "raykit_errors_total",
        "counter",
        "Client messages answered with an error.",
        vec![(String::new(), totals.errors as f64)],
    );
    family(
        "raykit_scenes_loaded_total",
        "counter",
        "Scenes loaded since start.",
        vec![(String::new(), totals.scenes_loaded as f64)],
    );
    family(
        "raykit_client_fps",
        "gauge",
        "Frames per second delivered to the client over the last 2 s.",
        per(&|c| Some(c.fps)),
    );
    family(
        "raykit_client_latency_ms",
        "gauge",
        "Median input-to-frame time of the client's last 256 inputs, ms.",
        per(&|c| c.latency_ms),
    );
    family(
        "raykit_client_bytes_per_second",
        "gauge",
        "Frame bytes per second sent to the client over the last 2 s.",
        per(&|c| Some(c.bytes_per_second)),
    );
    family(
        "raykit_client_frames_total",
        "counter",
        "Frames sent to the client.",
        per(&|c| Some(c.frames as f64)),
    );
    family(
        "raykit_client_inputs_total",
        "counter",
        "Input messages applied for the client.",
        per(&|c| Some(c.inputs as f64)),
    );
    family(
        "raykit_client_errors_total",
        "counter",
        "Messages of the client answered with an error.",
        per(&|c| Some(c.errors as f64)),
    );
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn median_of_odd_and_even_counts() {
        assert_eq!(median(vec![]), None);
        assert_eq!(median(vec![3.0, 1.0, 2.0]), Some(2.0));
        assert_eq!(median(vec![4.0, 1.0, 2.0, 3.0]), Some(2.5));
    }

    #[test]
    fn rates_count_only_the_window() {
        let t0 = Instant::now();
        let mut s = ClientStats::new(t0);
        for i in 0..10 {
            s.frame_sent(t0 + Duration::from_millis(500 * i), 1000, &[]);
        }
        // At 4.5 s the window holds the frames sent at 2.5..=4.5 s.
        let now = t0 + Duration::from_millis(4500);
        assert_eq!(s.fps(now), 5.0 / 2.0);
        assert_eq!(s.bytes_per_second(now), 5000.0 / 2.0);
        assert_eq!((s.frames, s.bytes), (10, 10_000));
    }

    #[test]
    fn latency_is_frame_time_minus_input_time() {
        let t0 = Instant::now();
        let mut s = ClientStats::new(t0);
        let inputs = [
            t0,
            t0 + Duration::from_millis(20),
            t0 + Duration::from_millis(30),
        ];
        s.frame_sent(t0 + Duration::from_millis(50), 10, &inputs);
        let m = s.median_latency_ms().unwrap();
        assert!((m - 30.0).abs() < 1e-9, "{m}");
    }
}
