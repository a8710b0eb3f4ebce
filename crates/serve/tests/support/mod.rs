//! Shared test helpers: an in-process server, a WebSocket client that reads
//! frames, a minimal HTTP client, and a direct render to compare against.

#![allow(dead_code)]

use futures_util::{SinkExt, StreamExt};
use raykit_core::Camera;
use raykit_render::{render, RenderOptions};
use raykit_serve::protocol::{decode_frame, FrameHeader};
use raykit_serve::{start, SceneLoader, ServeConfig, Server};
use serde_json::Value;
use std::sync::Arc;
use std::time::Duration;
use tokio::io::{AsyncReadExt, AsyncWriteExt};
use tokio::net::TcpStream;
use tokio_tungstenite::tungstenite::Message;
use tokio_tungstenite::{MaybeTlsStream, WebSocketStream};

pub type Ws = WebSocketStream<MaybeTlsStream<TcpStream>>;

/// Built-in scenes only.
pub fn loader() -> SceneLoader {
    Arc::new(|spec: &str| {
        let name = spec
            .strip_prefix("builtin:")
            .ok_or_else(|| anyhow::anyhow!("test loader: builtin scenes only, got '{spec}'"))?;
        Ok(raykit_scene::builtin(name)?)
    })
}

/// A small, fast configuration on a free port.
pub fn config() -> ServeConfig {
    ServeConfig {
        addr: "127.0.0.1:0".parse().unwrap(),
        full: (160, 90),
        spp: 4,
        settle: Duration::from_millis(100),
        quality: 95,
        ..ServeConfig::default()
    }
}

pub async fn server(config: ServeConfig) -> Server {
    start(config, loader(), "builtin:cornell")
        .await
        .expect("server starts")
}

pub async fn connect(server: &Server, query: &str) -> (Ws, Value) {
    let url = format!("ws://{}/ws{query}", server.addr());
    let (mut ws, _) = tokio_tungstenite::connect_async(url)
        .await
        .expect("websocket connects");
    let hello = next_text(&mut ws).await;
    assert_eq!(hello["type"], "hello", "{hello}");
    (ws, hello)
}

/// The next message within 10 s, skipping pings and pongs (tungstenite
/// answers pings by itself).
pub async fn next_message(ws: &mut Ws) -> Message {
    loop {
        let m = tokio::time::timeout(Duration::from_secs(10), ws.next())
            .await
            .expect("a message within 10 s")
            .expect("connection open")
            .expect("message ok");
        if !matches!(m, Message::Ping(_) | Message::Pong(_)) {
            return m;
        }
    }
}

pub async fn next_text(ws: &mut Ws) -> Value {
    loop {
        match next_message(ws).await {
            Message::Text(t) => return serde_json::from_str(&t).expect("JSON text"),
            Message::Binary(_) => continue,
            other => panic!("unexpected {other:?}"),
        }
    }
}

/// The next text message, acknowledging the frames before it.
pub async fn next_text_acking(ws: &mut Ws) -> Value {
    loop {
        match next_message(ws).await {
            Message::Text(t) => return serde_json::from_str(&t).expect("JSON text"),
            Message::Binary(b) => {
                let (h, _) = decode_frame(&b).expect("frame decodes");
                ack(ws, &h).await;
            }
            other => panic!("unexpected {other:?}"),
        }
    }
}

/// The next frame (skipping text), decoded.
pub async fn next_frame(ws: &mut Ws) -> (FrameHeader, image::RgbImage) {
    loop {
        if let Message::Binary(b) = next_message(ws).await {
            let (h, jpeg) = decode_frame(&b).expect("frame decodes");
            let img = image::load_from_memory_with_format(jpeg, image::ImageFormat::Jpeg)
                .expect("JPEG decodes")
                .to_rgb8();
            assert_eq!((img.width(), img.height()), (h.width, h.height));
            return (h, img);
        }
    }
}

/// Whether any frame arrives within `wait`.
pub async fn frame_within(ws: &mut Ws, wait: Duration) -> Option<FrameHeader> {
    let deadline = tokio::time::Instant::now() + wait;
    loop {
        let left = deadline.saturating_duration_since(tokio::time::Instant::now());
        match tokio::time::timeout(left, ws.next()).await {
            Err(_) => return None,
            Ok(Some(Ok(Message::Binary(b)))) => return Some(decode_frame(&b).unwrap().0),
            Ok(Some(Ok(_))) => continue,
            Ok(other) => panic!("connection ended: {other:?}"),
        }
    }
}

pub async fn send(ws: &mut Ws, json: &str) {
    ws.send(Message::text(json.to_string()))
        .await
        .expect("send");
}

pub async fn ack(ws: &mut Ws, h: &FrameHeader) {
    send(ws, &format!(r#"{{"type":"ack","frame":{}}}"#, h.frame)).await;
}

/// The camera in a frame header.
pub fn camera_of(h: &FrameHeader) -> Camera {
    h.camera.apply(&Camera {
        eye: raykit_core::Vec3::ZERO,
        target: raykit_core::Vec3::Z,
        up: raykit_core::Vec3::Y,
        vfov_deg: 1.0,
    })
}

/// The frame the server should have sent: the same renderer, called
/// directly with the server's lights.
pub fn direct_render(server: &Server, camera: &Camera, w: u32, h: u32, spp: u32) -> Vec<u8> {
    let world = server.state().world();
    let g = &world.geometry;
    let opts = RenderOptions {
        width: w,
        height: h,
        samples_per_pixel: spp,
        ..RenderOptions::default()
    };
    render(
        &g.scene.mesh,
        &world.lights,
        g.accel.as_ref(),
        camera,
        &opts,
        &|_| {},
    )
    .rgb
}

/// Mean absolute difference per channel, 0..=255.
pub fn mean_diff(a: &[u8], b: &[u8]) -> f64 {
    assert_eq!(a.len(), b.len());
    a.iter()
        .zip(b)
        .map(|(&x, &y)| (x as f64 - y as f64).abs())
        .sum::<f64>()
        / a.len() as f64
}

/// A one-shot HTTP/1.1 request; returns status, head and body.
pub async fn http(
    server: &Server,
    method: &str,
    path: &str,
    headers: &str,
    body: &str,
) -> (u16, String, Vec<u8>) {
    http_to(server.addr(), method, path, headers, body).await
}

/// [`http`] to any address.
pub async fn http_to(
    addr: std::net::SocketAddr,
    method: &str,
    path: &str,
    headers: &str,
    body: &str,
) -> (u16, String, Vec<u8>) {
    let mut s = TcpStream::connect(addr).await.unwrap();
    let req = format!(
        "{method} {path} HTTP/1.1\r\nHost: localhost\r\nConnection: close\r\n{}{headers}Content-Length: {}\r\n\r\n{body}",
        if headers.contains("Content-Type") { "" } else { "Content-Type: application/json\r\n" },
        body.len()
    );
    s.write_all(req.as_bytes()).await.unwrap();
    // Read until the body is complete (Content-Length, the last chunk, or
    // the end of the stream): not every server closes after the response.
    let mut out = Vec::new();
    let mut buf = [0u8; 65536];
    let read_all = async {
        loop {
            if let Some(split) = out.windows(4).position(|w| w == b"\r\n\r\n") {
                let head = String::from_utf8_lossy(&out[..split]).to_ascii_lowercase();
                let body = &out[split + 4..];
                let length = head
                    .lines()
                    .find_map(|l| l.strip_prefix("content-length:"))
                    .and_then(|v| v.trim().parse::<usize>().ok());
                if length.is_some_and(|n| body.len() >= n)
                    || (head.contains("transfer-encoding: chunked") && body.ends_with(b"0\r\n\r\n"))
                {
                    return;
                }
            }
            let n = s.read(&mut buf).await.unwrap();
            if n == 0 {
                return;
            }
            out.extend_from_slice(&buf[..n]);
        }
    };
    tokio::time::timeout(Duration::from_secs(20), read_all)
        .await
        .expect("response within 20 s");
    let split = out
        .windows(4)
        .position(|w| w == b"\r\n\r\n")
        .expect("header end");
    let head = String::from_utf8_lossy(&out[..split]).into_owned();
    let status = head[9..12].parse().unwrap();
    let body = out[split + 4..].to_vec();
    let body = if head
        .to_ascii_lowercase()
        .contains("transfer-encoding: chunked")
    {
        dechunk(&body)
    } else {
        body
    };
    (status, head, body)
}

fn dechunk(mut b: &[u8]) -> Vec<u8> {
    let mut out = Vec::new();
    loop {
        let Some(eol) = b.windows(2).position(|w| w == b"\r\n") else {
            return out;
        };
        let n = usize::from_str_radix(std::str::from_utf8(&b[..eol]).unwrap().trim(), 16).unwrap();
        if n == 0 {
            return out;
        }
        out.extend_from_slice(&b[eol + 2..eol + 2 + n]);
        b = &b[eol + 2 + n + 2..];
    }
}

pub fn json_body(body: &[u8]) -> Value {
    serde_json::from_slice(body)
        .unwrap_or_else(|e| panic!("JSON body ({e}): {}", String::from_utf8_lossy(body)))
}
