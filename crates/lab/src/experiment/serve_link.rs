//! `raykit experiment serve --connect URL`: one stream from a server running
//! elsewhere (across a network link), measured as remote rendering to a
//! handheld over 802.11g was in the remote-rendering paper after Purcell et al. (2002): frames per second at one size,
//! bytes per frame, the bit rate, and input-to-frame latency percentiles.

use super::{provenance, write_text};
use anyhow::Result;
use raykit_serve::link::{measure_link, LinkOptions, LinkReport};
use raykit_serve::runtime;
use serde::Serialize;
use std::path::Path;
use std::process::ExitCode;

#[derive(Serialize)]
struct Report<'a> {
    provenance: String,
    input_hz: f64,
    warmup_s: f64,
    link: &'a LinkReport,
}

fn opt(v: Option<f64>) -> String {
    v.map_or("–".into(), |v| format!("{v:.1}"))
}

/// Measure the stream `opts` describes and write link.json and link.md into
/// `out`; exit status 1 when no frame of the asked size and format came or
/// the client saw an error.
pub fn run(opts: &LinkOptions, out: &Path) -> Result<ExitCode> {
    let prov = provenance();
    let link = runtime()?.block_on(measure_link(opts))?;
    let report = Report {
        provenance: prov.clone(),
        input_hz: opts.input_hz,
        warmup_s: opts.warmup,
        link: &link,
    };
    write_text(out, "link.json", &serde_json::to_string_pretty(&report)?)?;
    let l = &link;
    let mut md = format!(
        "# raykit serve over a link: {}×{} {:?}\n\n{prov}\n\
         | frames | fps | KB/frame | Mbit/s | latency p50 / p95 / p99 ms | render ms (median) | errors |\n\
         |---:|---:|---:|---:|---:|---:|---:|\n\
         | {} | {:.2} | {:.1} | {:.2} | {} / {} / {} | {} | {} |\n",
        l.width, l.height, l.format, l.frames, l.fps, l.message_bytes_per_frame / 1e3,
        l.mbit_per_second, opt(l.latency_p50_ms), opt(l.latency_p95_ms), opt(l.latency_p99_ms),
        opt(l.render_ms_median), l.errors.len(),
    );
    if !l.errors.is_empty() {
        md += &format!("\nErrors: {:?}\n", &l.errors[..l.errors.len().min(5)]);
    }
    write_text(out, "link.md", &md)?;
    print!("{md}");
    Ok(if l.frames == 0 || !l.errors.is_empty() {
        ExitCode::FAILURE
    } else {
        ExitCode::SUCCESS
    })
}
