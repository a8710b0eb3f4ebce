//! Raw RGB frames and the link measurement against an in-process server:
//! a raw frame equals a direct render of its camera byte for byte, the
//! JPEG of the same view decodes to it within JPEG error, previews can be
//! turned off, and `measure_link` counts what the server actually sent.

mod support;

use futures_util::SinkExt;
use raykit_serve::link::{measure_link, LinkOptions};
use raykit_serve::protocol::{decode_frame, FrameFormat, Stage};
use std::time::Duration;
use support::*;
use tokio_tungstenite::tungstenite::Message;

/// The next binary frame, raw header and payload.
async fn next_raw(ws: &mut Ws) -> (raykit_serve::protocol::FrameHeader, Vec<u8>) {
    loop {
        if let Message::Binary(b) = next_message(ws).await {
            let (h, payload) = decode_frame(&b).expect("frame decodes");
            return (h, payload.to_vec());
        }
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn raw_frames_equal_the_direct_render_and_jpeg_decodes_close_to_them() {
    let server = server(config()).await;
    let (mut ws, hello) = connect(&server, "").await;
    assert_eq!(hello["format"], "jpeg");
    assert_eq!(hello["previews"], true);
    // Drain the first (JPEG preview) frame, then ask for raw full-size
    // frames without previews and move the camera.
    let (h0, _) = next_raw(&mut ws).await;
    assert_eq!(h0.format, FrameFormat::Jpeg);
    send(
        &mut ws,
        r#"{"type":"settings","width":96,"height":64,"spp":1,"format":"raw","previews":false}"#,
    )
    .await;
    send(&mut ws, r#"{"type":"orbit","yaw":0.3,"pitch":0.1,"seq":1}"#).await;
    ack(&mut ws, &h0).await;
    let (h, raw) = loop {
        let (h, p) = next_raw(&mut ws).await;
        if h.input_seq >= 1 && h.format == FrameFormat::Raw {
            break (h, p);
        }
        ack(&mut ws, &h).await;
    };
    assert_eq!(
        (h.width, h.height, h.stage, h.spp),
        (96, 64, Stage::Full, 1)
    );
    let want = direct_render(&server, &camera_of(&h), 96, 64, 1);
    assert_eq!(raw.len(), 96 * 64 * 3);
    assert_eq!(raw, want, "raw payload differs from the direct render");

    // The same view as JPEG decodes to the raw pixels within JPEG error,
    // and is smaller.
    ack(&mut ws, &h).await;
    send(&mut ws, r#"{"type":"settings","format":"jpeg"}"#).await;
    let (hj, img) = loop {
        let (hj, img) = next_frame(&mut ws).await;
        if hj.format == FrameFormat::Jpeg && hj.camera == h.camera {
            break (hj, img);
        }
        ack(&mut ws, &hj).await;
    };
    assert_eq!((hj.width, hj.height, hj.stage), (96, 64, Stage::Full));
    let diff = mean_diff(img.as_raw(), &raw);
    assert!(diff < 4.0, "JPEG differs from the raw frame by {diff}");
    // Bad formats are refused and change nothing.
    send(&mut ws, r#"{"type":"settings","format":"png"}"#).await;
    let err = next_text_acking(&mut ws).await;
    assert_eq!(err["type"], "error", "{err}");
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn measure_link_counts_the_frames_and_bytes_the_server_sent() {
    let server = server(config()).await;
    for format in [FrameFormat::Raw, FrameFormat::Jpeg] {
        let before = server.state().totals.lock().unwrap().frames;
        let r = measure_link(&LinkOptions {
            url: format!("ws://{}/ws", server.addr()),
            size: (64, 48),
            format,
            quality: None,
            seconds: 1.5,
            warmup: 0.3,
            input_hz: 60.0,
        })
        .await
        .unwrap();
        let served = server.state().totals.lock().unwrap().frames - before;
        assert!(r.errors.is_empty(), "{:?}", r.errors);
        assert!(r.frames >= 3, "{format:?}: {} frames", r.frames);
        assert!(r.frames as u64 <= served);
        assert_eq!(r.other_frames, 0);
        assert!((r.fps - r.frames as f64 / r.seconds).abs() < 1e-9);
        // Bits per second from bytes per frame and frame rate.
        let mbit = r.message_bytes_per_frame * 8.0 * r.fps / 1e6;
        assert!((r.mbit_per_second - mbit).abs() < 1e-9 * mbit.max(1.0));
        if format == FrameFormat::Raw {
            assert_eq!(r.payload_bytes_per_frame, (64 * 48 * 3) as f64);
        } else {
            assert!(r.payload_bytes_per_frame < (64 * 48 * 3) as f64);
        }
        assert!(r.message_bytes_per_frame > r.payload_bytes_per_frame);
        assert!(r.latency_p50_ms.is_some() && r.latency_p50_ms <= r.latency_p95_ms);
    }
    // Options that cannot be measured are refused before connecting.
    let bad = LinkOptions {
        url: "ws://127.0.0.1:9/ws".into(),
        size: (64, 48),
        format: FrameFormat::Raw,
        quality: None,
        seconds: 1.0,
        warmup: 2.0,
        input_hz: 60.0,
    };
    assert!(measure_link(&bad).await.is_err());
    tokio::time::sleep(Duration::from_millis(10)).await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn raw_frames_over_the_reading_limit_of_the_server_still_arrive() {
    // Frames are not bounded by the size limit of client messages: a
    // 512×512 raw frame (786 KB) passes a server that reads 16 KiB at most.
    let server = server(config()).await;
    let (mut ws, _) = connect(&server, "").await;
    ws.send(Message::text(
        r#"{"type":"settings","width":512,"height":512,"spp":1,"format":"raw","previews":false}"#,
    ))
    .await
    .unwrap();
    loop {
        let (h, p) = next_raw(&mut ws).await;
        if h.format == FrameFormat::Raw && h.width == 512 {
            assert_eq!(p.len(), 512 * 512 * 3);
            break;
        }
        ack(&mut ws, &h).await;
    }
    server.shutdown().await.unwrap();
}
