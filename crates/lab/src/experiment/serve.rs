//! `raykit experiment serve`: the streaming server under load on loopback —
//! one client's frame rate while the camera moves and how soon the view
//! refines when it stops (a remote-rendering arrangement, judged
//! by its interactivity), then N clients at once for T seconds: frames,
//! errors, input-to-frame latency percentiles and the server's memory.

use super::{write_csv, write_text};
use crate::args::scene_arg::loader;
use crate::plot::{write_svg, LineChart, Series};
use anyhow::{bail, Result};
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use raykit_serve::link::LinkOptions;
use raykit_serve::load::{percentile, rss_kib, run_load, ClientReport, LoadOptions};
use raykit_serve::protocol::{FrameFormat, Stage};
use raykit_serve::runtime;
use raykit_serve::{start, ServeConfig};
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;
use std::time::{Duration, Instant};

/// Arguments of `raykit experiment serve`.
#[derive(Args)]
#[command(
    after_help = "Starts `raykit serve` in this process on a free loopback port and drives it with\n\
WebSocket clients that orbit the camera and acknowledge every frame, as the web client does.\n\
Phase 1: one client moves for --single-seconds at --input-hz, then stops for 3 s.\n\
Phase 2: --clients clients move for --seconds; the server's resident memory is sampled each second.\n\
Writes report.json, report.md, clients.csv and memory.svg into --out; exit status 1 when a client\n\
saw an error or got no frame.\n\n\
With --connect ws://HOST:PORT/ws it starts no server: one client drives that server for --seconds,\n\
asking for full-size --width x --height frames of one sample in --format (raw RGB or JPEG, no\n\
half-size previews), and reports fps, bytes per frame, Mbit/s and input-to-frame latency\n\
percentiles after --warmup seconds (link.json, link.md); scripts/serve-link.sh runs it across a\n\
rate-limited network link."
)]
pub struct ServeExperimentArgs {
    /// Scene to serve.
    #[arg(long, default_value = "builtin:cornell")]
    pub(super) scene: String,
    /// Clients in phase 2.
    #[arg(long, default_value_t = 8)]
    pub(super) clients: usize,
    /// Length of phase 2, seconds.
    #[arg(long, default_value_t = 60.0)]
    pub(super) seconds: f64,
    /// Length of phase 1's moving part, seconds.
    #[arg(long, default_value_t = 10.0)]
    pub(super) single_seconds: f64,
    /// Inputs per second the phase 1 client sends while moving.
    #[arg(long, default_value_t = 60.0)]
    pub(super) input_hz: f64,
    /// Inputs per second each phase 2 client sends.
    #[arg(long, default_value_t = 30.0)]
    pub(super) many_input_hz: f64,
    /// Full resolution (the preview while moving is half).
    #[arg(long, default_value_t = 1280)]
    pub(super) width: u32,
    /// Full resolution height.
    #[arg(long, default_value_t = 720)]
    pub(super) height: u32,
    /// Output folder.
    #[arg(long, default_value = "experiments/serve")]
    pub(super) out: PathBuf,
    /// Drive the server at this WebSocket URL instead of starting one.
    #[arg(long, value_name = "URL")]
    pub(super) connect: Option<String>,
    /// Frame payload; only with --connect.
    #[arg(long, value_enum, default_value_t = LinkFormat::Jpeg, requires = "connect")]
    pub(super) format: LinkFormat,
    /// JPEG quality to ask for (default: the server's); only with --connect.
    #[arg(long, value_parser = clap::value_parser!(u8).range(1..=100), requires = "connect")]
    pub(super) quality: Option<u8>,
    /// Seconds not counted at the start; only with --connect.
    #[arg(long, default_value_t = 2.0, requires = "connect")]
    pub(super) warmup: f64,
}

/// Frame payload of `--format`.
#[derive(Clone, Copy, Debug, clap::ValueEnum)]
pub(super) enum LinkFormat {
    /// Uncompressed 8-bit RGB.
    Raw,
    /// Baseline JPEG.
    Jpeg,
}

/// Phase 1's figures.
#[derive(Serialize)]
struct SingleClient {
    preview: (u32, u32),
    full: (u32, u32),
    fps_moving: f64,
    latency_p50_ms: Option<f64>,
    latency_p90_ms: Option<f64>,
    render_ms_median: Option<f64>,
    to_full_after_stop_ms: Option<f64>,
    to_refined_after_stop_ms: Option<f64>,
    kib_per_second_moving: f64,
    errors: usize,
}

/// One client of phase 2.
#[derive(Serialize)]
struct ClientRow {
    client: usize,
    frames: usize,
    fps: f64,
    inputs: u64,
    latency_p50_ms: Option<f64>,
    latency_p90_ms: Option<f64>,
    errors: usize,
}

/// Phase 2's figures.
#[derive(Serialize)]
struct ManyClients {
    clients: usize,
    seconds: f64,
    frames: usize,
    frames_per_second_total: f64,
    min_client_frames: usize,
    errors: usize,
    latency_p50_ms: Option<f64>,
    latency_p90_ms: Option<f64>,
    latency_p99_ms: Option<f64>,
    rss_start_mib: Option<f64>,
    rss_end_mib: Option<f64>,
    rss_max_mib: Option<f64>,
    /// Mean RSS of the last quarter minus that of the second quarter.
    rss_growth_mib: Option<f64>,
    rss_samples: Vec<(f64, f64)>,
}

#[derive(Serialize)]
struct Report {
    command: String,
    scene: String,
    threads: usize,
    single: SingleClient,
    many: ManyClients,
}

fn mib(k: u64) -> f64 {
    k as f64 / 1024.0
}

fn mean(xs: &[f64]) -> Option<f64> {
    (!xs.is_empty()).then(|| xs.iter().sum::<f64>() / xs.len() as f64)
}

/// Run both phases and write the report, or with `--connect` measure the
/// link to a running server.
pub fn run(args: ServeExperimentArgs) -> Result<ExitCode> {
    if let Some(url) = args.connect.clone() {
        let opts = LinkOptions {
            url,
            size: (args.width, args.height),
            format: match args.format {
                LinkFormat::Raw => FrameFormat::Raw,
                LinkFormat::Jpeg => FrameFormat::Jpeg,
            },
            quality: args.quality,
            seconds: args.seconds,
            warmup: args.warmup,
            input_hz: args.input_hz,
        };
        return super::serve_link::run(&opts, &args.out);
    }
    if args.clients == 0 || args.clients > 64 {
        bail!("--clients must be between 1 and 64");
    }
    for (name, v) in [
        ("--seconds", args.seconds),
        ("--single-seconds", args.single_seconds),
        ("--input-hz", args.input_hz),
        ("--many-input-hz", args.many_input_hz),
    ] {
        if !(v.is_finite() && v > 0.0 && v <= 3600.0) {
            bail!("{name} must be a number in (0, 3600], got {v}");
        }
    }
    let config = ServeConfig {
        addr: "127.0.0.1:0".parse()?,
        full: (args.width, args.height),
        max_clients: args.clients.max(1) + 1,
        max_inputs_per_second: (args.input_hz.max(args.many_input_hz) * 2.0).ceil() as u32 + 10,
        ..ServeConfig::default()
    };
    if let Some(p) = config.problem() {
        bail!("{p}");
    }
    let full = config.full;
    let preview = ServeConfig::preview_size(full);
    let rt = runtime()?;
    let (single_report, many_reports, samples) = rt.block_on(async {
        let server = start(config, loader(), &args.scene).await?;
        let url = format!("ws://{}/ws", server.addr());
        let total = args.single_seconds + 3.0 + args.seconds;
        let bar = ProgressBar::new(total.ceil() as u64).with_style(
            ProgressStyle::with_template("{bar:30} {pos}/{len} s {msg}").expect("valid template"),
        );
        bar.set_message("phase 1: one client");
        let ticker = {
            let bar = bar.clone();
            tokio::spawn(async move {
                loop {
                    tokio::time::sleep(Duration::from_secs(1)).await;
                    bar.inc(1);
                }
            })
        };
        let single = run_load(&LoadOptions {
            url: url.clone(),
            clients: 1,
            moving: Duration::from_secs_f64(args.single_seconds),
            still: Duration::from_secs(3),
            input_hz: args.input_hz,
            settings: None,
        })
        .await?;
        bar.set_message(format!("phase 2: {} clients", args.clients));
        let start_many = Instant::now();
        let sampling = tokio::spawn(async move {
            let mut samples = Vec::new();
            let end = start_many + Duration::from_secs_f64(args.seconds);
            while Instant::now() < end {
                if let Some(k) = rss_kib() {
                    samples.push((start_many.elapsed().as_secs_f64(), mib(k)));
                }
                tokio::time::sleep(Duration::from_secs(1)).await;
            }
            samples
        });
        let many = run_load(&LoadOptions {
            url,
            clients: args.clients,
            moving: Duration::from_secs_f64(args.seconds),
            still: Duration::ZERO,
            input_hz: args.many_input_hz,
            settings: None,
        })
        .await?;
        let samples = sampling.await?;
        ticker.abort();
        bar.finish_and_clear();
        server.shutdown().await?;
        anyhow::Ok((single, many, samples))
    })?;

    let s = &single_report[0];
    let moving_end = args.single_seconds;
    let moving_frames: Vec<_> = s
        .frames
        .iter()
        .filter(|f| f.at_s >= 1.0 && f.at_s < moving_end)
        .collect();
    let single = SingleClient {
        preview,
        full,
        fps_moving: s.fps_between(1.0, moving_end),
        latency_p50_ms: percentile(&s.latencies_ms, 50.0),
        latency_p90_ms: percentile(&s.latencies_ms, 90.0),
        render_ms_median: raykit_serve::stats::median(
            moving_frames.iter().map(|f| f.render_ms).collect(),
        ),
        to_full_after_stop_ms: s.first_after(moving_end, Stage::Full).map(|t| t * 1e3),
        to_refined_after_stop_ms: s.first_after(moving_end, Stage::Refined).map(|t| t * 1e3),
        kib_per_second_moving: moving_frames.iter().map(|f| f.bytes as f64).sum::<f64>()
            / 1024.0
            / (moving_end - 1.0).max(1e-9),
        errors: s.errors.len(),
    };
    let rows: Vec<ClientRow> = many_reports
        .iter()
        .enumerate()
        .map(|(i, r)| ClientRow {
            client: i + 1,
            frames: r.frames.len(),
            fps: r.frames.len() as f64 / args.seconds,
            inputs: r.inputs,
            latency_p50_ms: percentile(&r.latencies_ms, 50.0),
            latency_p90_ms: percentile(&r.latencies_ms, 90.0),
            errors: r.errors.len(),
        })
        .collect();
    let all_lat: Vec<f64> = many_reports
        .iter()
        .flat_map(|r| r.latencies_ms.clone())
        .collect();
    let rss: Vec<f64> = samples.iter().map(|&(_, m)| m).collect();
    let q = rss.len() / 4;
    let many = ManyClients {
        clients: args.clients,
        seconds: args.seconds,
        frames: rows.iter().map(|r| r.frames).sum(),
        frames_per_second_total: rows.iter().map(|r| r.fps).sum(),
        min_client_frames: rows.iter().map(|r| r.frames).min().unwrap_or(0),
        errors: rows.iter().map(|r| r.errors).sum(),
        latency_p50_ms: percentile(&all_lat, 50.0),
        latency_p90_ms: percentile(&all_lat, 90.0),
        latency_p99_ms: percentile(&all_lat, 99.0),
        rss_start_mib: rss.first().copied(),
        rss_end_mib: rss.last().copied(),
        rss_max_mib: rss.iter().copied().reduce(f64::max),
        rss_growth_mib: (q > 0)
            .then(|| Some(mean(&rss[rss.len() - q..])? - mean(&rss[q..2 * q])?))
            .flatten(),
        rss_samples: samples.clone(),
    };
    let report = Report {
        command: std::env::args().collect::<Vec<_>>().join(" "),
        scene: args.scene.clone(),
        threads: rayon::current_num_threads(),
        single,
        many,
    };
    write_outputs(&args, &report, &rows, &many_reports)?;
    let failed = report.single.errors > 0
        || report.many.errors > 0
        || report.many.min_client_frames == 0
        || s.frames.is_empty();
    Ok(if failed {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}

fn opt(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{v:.1}"))
}

fn write_outputs(
    args: &ServeExperimentArgs,
    r: &Report,
    rows: &[ClientRow],
    many_reports: &[ClientReport],
) -> Result<()> {
    let out = &args.out;
    write_text(out, "report.json", &serde_json::to_string_pretty(r)?)?;
    write_csv(out, "clients.csv", rows)?;
    let s = &r.single;
    let m = &r.many;
    let mut md = format!(
        "# raykit serve under load ({}, {} render threads)\n\n`{}`\n\n\
         ## One client, camera moving then still\n\n\
         | preview while moving | fps while moving | input-to-frame p50 / p90 ms | render ms (median) | KiB/s | full {}×{} after stop | refined after stop | errors |\n\
         |---|---:|---:|---:|---:|---:|---:|---:|\n\
         | {}×{} | {:.1} | {} / {} | {} | {:.0} | {} ms | {} ms | {} |\n\n",
        r.scene, r.threads, r.command, s.full.0, s.full.1, s.preview.0, s.preview.1, s.fps_moving,
        opt(s.latency_p50_ms), opt(s.latency_p90_ms), opt(s.render_ms_median), s.kib_per_second_moving,
        opt(s.to_full_after_stop_ms), opt(s.to_refined_after_stop_ms), s.errors,
    );
    md += &format!(
        "## {} clients moving for {:.0} s\n\n\
         | frames | total fps | fewest frames of a client | errors | latency p50 / p90 / p99 ms | RSS start → end (max) MiB | RSS growth, 2nd → 4th quarter |\n\
         |---:|---:|---:|---:|---:|---:|---:|\n\
         | {} | {:.1} | {} | {} | {} / {} / {} | {} → {} ({}) | {} MiB |\n\n\
         | client | frames | fps | inputs | latency p50 / p90 ms | errors |\n|---:|---:|---:|---:|---:|---:|\n",
        m.clients, m.seconds, m.frames, m.frames_per_second_total, m.min_client_frames, m.errors,
        opt(m.latency_p50_ms), opt(m.latency_p90_ms), opt(m.latency_p99_ms),
        opt(m.rss_start_mib), opt(m.rss_end_mib), opt(m.rss_max_mib), opt(m.rss_growth_mib),
    );
    for c in rows {
        md += &format!(
            "| {} | {} | {:.1} | {} | {} / {} | {} |\n",
            c.client,
            c.frames,
            c.fps,
            c.inputs,
            opt(c.latency_p50_ms),
            opt(c.latency_p90_ms),
            c.errors
        );
    }
    let errors: Vec<&String> = many_reports
        .iter()
        .flat_map(|c| &c.errors)
        .take(5)
        .collect();
    if !errors.is_empty() {
        md += &format!("\nFirst errors: {errors:?}\n");
    }
    write_text(out, "report.md", &md)?;
    print!("{md}");
    // Frames delivered per second (all clients) next to memory.
    let secs = m.seconds.ceil() as usize;
    let mut per_second = vec![0.0; secs.max(1)];
    for c in many_reports {
        for f in &c.frames {
            if let Some(b) = per_second.get_mut(f.at_s as usize) {
                *b += 1.0;
            }
        }
    }
    write_svg(
        &LineChart {
            title: format!(
                "raykit serve, {} clients: memory and frames over time",
                m.clients
            ),
            x_label: "seconds",
            y_label: "MiB resident / frames per second (all clients)",
            series: vec![
                Series {
                    name: "resident memory, MiB".into(),
                    points: m.rss_samples.clone(),
                },
                Series {
                    name: "frames per second, all clients".into(),
                    points: per_second
                        .iter()
                        .enumerate()
                        .map(|(i, &v)| (i as f64 + 0.5, v))
                        .collect(),
                },
            ],
            reference: Vec::new(),
        },
        &out.join("memory.svg"),
    )
}
