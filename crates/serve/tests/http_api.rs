//! The HTTP side: MJPEG parts equal a direct render, the API changes the
//! default and per-client cameras, lights, resolution and scene, bad
//! requests name their problem, and /metrics is valid Prometheus text that
//! agrees with what the clients received.

mod support;

use raykit_serve::BOUNDARY;
use std::time::Duration;
use support::*;
use tokio::io::{AsyncReadExt, AsyncWriteExt};

/// Read from an MJPEG response until `parts` JPEG parts have arrived.
async fn mjpeg_parts(
    server: &raykit_serve::Server,
    query: &str,
    parts: usize,
    between: impl AsyncFn(usize),
) -> (String, Vec<Vec<u8>>) {
    let mut s = tokio::net::TcpStream::connect(server.addr()).await.unwrap();
    let req = format!("GET /mjpeg{query} HTTP/1.1\r\nHost: x\r\n\r\n");
    s.write_all(req.as_bytes()).await.unwrap();
    let mut buf = Vec::new();
    let mut found = Vec::new();
    let mut chunk = [0u8; 65536];
    let mut head = String::new();
    while found.len() < parts {
        let n = tokio::time::timeout(Duration::from_secs(20), s.read(&mut chunk))
            .await
            .expect("data within 20 s")
            .unwrap();
        assert!(n > 0, "stream ended");
        buf.extend_from_slice(&chunk[..n]);
        if head.is_empty() {
            if let Some(p) = buf.windows(4).position(|w| w == b"\r\n\r\n") {
                head = String::from_utf8_lossy(&buf[..p]).into_owned();
                buf.drain(..p + 4);
            }
        }
        // Parts: --BOUNDARY, headers with Content-Length, blank line, JPEG.
        let marker = format!("--{BOUNDARY}\r\n");
        while let Some(start) = buf
            .windows(marker.len())
            .position(|w| w == marker.as_bytes())
        {
            let rest = &buf[start..];
            let Some(hend) = rest.windows(4).position(|w| w == b"\r\n\r\n") else {
                break;
            };
            let headers = String::from_utf8_lossy(&rest[..hend]).to_ascii_lowercase();
            assert!(headers.contains("content-type: image/jpeg"), "{headers}");
            let len: usize = headers
                .lines()
                .find_map(|l| l.strip_prefix("content-length: "))
                .unwrap()
                .trim()
                .parse()
                .unwrap();
            if rest.len() < hend + 4 + len {
                break;
            }
            found.push(rest[hend + 4..hend + 4 + len].to_vec());
            buf.drain(..start + hend + 4 + len);
            between(found.len()).await;
        }
    }
    (head, found)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn mjpeg_streams_the_default_camera_and_follows_api_changes() {
    let server = server(config()).await;
    let before = server.state().world().camera;
    let srv = &server;
    let (head, parts) = mjpeg_parts(&server, "?width=64&height=48&quality=95", 2, async |n| {
        if n == 1 {
            let (status, _, body) =
                http(srv, "PUT", "/api/camera", "", r#"{"eye":[4,6,15]}"#).await;
            assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
        }
    })
    .await;
    assert!(
        head.to_ascii_lowercase()
            .contains(&format!("multipart/x-mixed-replace; boundary={BOUNDARY}")),
        "{head}"
    );
    let decode = |b: &[u8]| {
        image::load_from_memory_with_format(b, image::ImageFormat::Jpeg)
            .unwrap()
            .to_rgb8()
    };
    let (first, second) = (decode(&parts[0]), decode(&parts[1]));
    assert_eq!((first.width(), first.height()), (64, 48));
    let d0 = mean_diff(first.as_raw(), &direct_render(&server, &before, 64, 48, 1));
    assert!(
        d0 < 4.0,
        "first part differs from the direct render by {d0}"
    );
    let after = server.state().world().camera;
    assert_eq!(after.eye.to_array(), [4.0, 6.0, 15.0]);
    assert_eq!(after.target, before.target);
    let d1 = mean_diff(second.as_raw(), &direct_render(&server, &after, 64, 48, 1));
    assert!(
        d1 < 4.0,
        "second part differs from the direct render by {d1}"
    );
    assert!(mean_diff(first.as_raw(), second.as_raw()) > 2.0);
    let (status, _, body) = http(&server, "GET", "/mjpeg?width=64", "", "").await;
    assert_eq!(status, 400);
    assert!(json_body(&body)["error"]
        .as_str()
        .unwrap()
        .contains("height"));
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_api_sets_cameras_lights_resolution_and_scene() {
    let server = server(config()).await;
    let (mut ws, hello) = connect(&server, "").await;
    let id = hello["client"].as_u64().unwrap();
    let (h, _) = next_frame(&mut ws).await;
    ack(&mut ws, &h).await;

    // This client's camera.
    let (status, _, body) = http(
        &server,
        "PUT",
        &format!("/api/camera?client={id}"),
        "",
        r#"{"eye":[2,5,14],"fov":50}"#,
    )
    .await;
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
    let h = loop {
        let (h, _) = next_frame(&mut ws).await;
        ack(&mut ws, &h).await;
        if h.camera.eye == Some([2.0, 5.0, 14.0]) {
            break h;
        }
    };
    assert_eq!(h.camera.fov, Some(50.0));
    let (_, _, body) = http(&server, "GET", &format!("/api/camera?client={id}"), "", "").await;
    assert_eq!(json_body(&body)["eye"], serde_json::json!([2.0, 5.0, 14.0]));

    // Its resolution.
    let (status, _, _) = http(
        &server,
        "PUT",
        &format!("/api/resolution?client={id}"),
        "",
        r#"{"width":96,"height":64}"#,
    )
    .await;
    assert_eq!(status, 200);
    loop {
        let (h, _) = next_frame(&mut ws).await;
        ack(&mut ws, &h).await;
        if (h.width, h.height) == (48, 32) {
            break;
        }
    }

    // Lights: one dim light darkens the next frame.
    let (h, bright) = loop {
        let (h, img) = next_frame(&mut ws).await;
        ack(&mut ws, &h).await;
        if h.stage == raykit_serve::protocol::Stage::Full {
            break (h, img);
        }
    };
    let _ = h;
    let (status, _, _) = http(
        &server,
        "PUT",
        "/api/lights",
        "",
        r#"{"lights":[{"position":[0,9,1],"color":[0.1,0.1,0.1]}]}"#,
    )
    .await;
    assert_eq!(status, 200);
    let dim = loop {
        let (h, img) = next_frame(&mut ws).await;
        ack(&mut ws, &h).await;
        if h.stage == raykit_serve::protocol::Stage::Full {
            break img;
        }
    };
    let mean = |i: &image::RgbImage| {
        i.as_raw().iter().map(|&v| v as f64).sum::<f64>() / i.as_raw().len() as f64
    };
    assert!(
        mean(&dim) < 0.8 * mean(&bright),
        "{} vs {}",
        mean(&dim),
        mean(&bright)
    );

    // Another scene: the client is told and its frames follow.
    let (status, _, body) = http(
        &server,
        "POST",
        "/api/scene",
        "",
        r#"{"scene":"builtin:shirley6"}"#,
    )
    .await;
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&body));
    let tri = json_body(&body)["triangles"].as_u64().unwrap();
    let scene_msg = next_text_acking(&mut ws).await;
    assert_eq!(scene_msg["type"], "scene");
    assert_eq!(scene_msg["triangles"].as_u64(), Some(tri));
    let want = server.state().world().camera;
    loop {
        let (h, _) = next_frame(&mut ws).await;
        ack(&mut ws, &h).await;
        if camera_of(&h) == want {
            break;
        }
    }

    // Bad requests name the problem.
    for (method, path, body, want_status, needle) in [
        (
            "POST",
            "/api/scene",
            r#"{"scene":"/etc/passwd"}"#,
            400,
            "scene-dir",
        ),
        (
            "POST",
            "/api/scene",
            r#"{"scene":"builtin:nosuch"}"#,
            400,
            "nosuch",
        ),
        (
            "POST",
            "/api/scene",
            r#"{"scen":"builtin:cornell"}"#,
            400,
            "scene",
        ),
        (
            "PUT",
            "/api/camera",
            r#"{"eye":[0,0,0],"target":[0,0,0]}"#,
            400,
            "differ",
        ),
        ("PUT", "/api/camera?client=999", r#"{}"#, 404, "999"),
        ("PUT", "/api/camera?client=x", r#"{}"#, 400, "client"),
        (
            "PUT",
            "/api/resolution",
            r#"{"width":8,"height":8}"#,
            400,
            "resolution",
        ),
        (
            "PUT",
            "/api/lights",
            r#"{"lights":[{"position":[0,1]}]}"#,
            400,
            "request body",
        ),
        ("PUT", "/api/lights", "{", 400, "request body"),
    ] {
        let (status, _, b) = http(&server, method, path, "", body).await;
        let msg = json_body(&b)["error"]
            .as_str()
            .unwrap_or_default()
            .to_string();
        assert_eq!(status, want_status, "{method} {path} {body}: {msg}");
        assert!(
            msg.contains(needle),
            "{method} {path}: '{msg}' lacks '{needle}'"
        );
    }
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn metrics_are_prometheus_text_and_count_what_clients_got() {
    let server = server(config()).await;
    let (mut ws, hello) = connect(&server, "").await;
    let id = hello["client"].as_u64().unwrap();
    let mut got = 0;
    for seq in 1..=5 {
        send(
            &mut ws,
            &format!(r#"{{"type":"orbit","yaw":0.05,"seq":{seq}}}"#),
        )
        .await;
        let (h, _) = next_frame(&mut ws).await;
        ack(&mut ws, &h).await;
        got += 1;
    }
    let (status, head, body) = http(&server, "GET", "/metrics", "", "").await;
    assert_eq!(status, 200);
    assert!(head.contains("text/plain; version=0.0.4"));
    let text = String::from_utf8(body).unwrap();
    let mut values = std::collections::HashMap::new();
    for line in text.lines() {
        if line.starts_with('#') {
            assert!(
                line.starts_with("# HELP raykit_") || line.starts_with("# TYPE raykit_"),
                "{line}"
            );
            continue;
        }
        let (name, value) = line
            .rsplit_once(' ')
            .unwrap_or_else(|| panic!("bad line {line}"));
        let v: f64 = value
            .parse()
            .unwrap_or_else(|_| panic!("bad value in {line}"));
        assert!(name.starts_with("raykit_"), "{line}");
        values.insert(name.to_string(), v);
    }
    let label = format!("{{client=\"{id}\",kind=\"ws\"}}");
    let frames = values[&format!("raykit_client_frames_total{label}")];
    assert!(frames >= got as f64, "{frames} < {got}");
    assert!(values["raykit_frames_total"] >= frames);
    assert_eq!(values[&format!("raykit_client_inputs_total{label}")], 5.0);
    assert!(values[&format!("raykit_client_fps{label}")] > 0.0);
    assert!(values.contains_key(&format!("raykit_client_latency_ms{label}")));
    assert_eq!(values["raykit_clients"], 1.0);
    assert_eq!(values["raykit_scene_triangles"], 1314.0);
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_short_load_test_delivers_frames_to_every_client() {
    let server = server(config()).await;
    let opts = raykit_serve::load::LoadOptions {
        url: format!("ws://{}/ws", server.addr()),
        clients: 3,
        moving: Duration::from_millis(1500),
        still: Duration::from_millis(800),
        input_hz: 30.0,
        settings: None,
    };
    let reports = raykit_serve::load::run_load(&opts).await.unwrap();
    for (i, r) in reports.iter().enumerate() {
        assert!(r.errors.is_empty(), "client {i}: {:?}", r.errors);
        assert!(r.frames.len() >= 3, "client {i}: {} frames", r.frames.len());
        assert!(!r.latencies_ms.is_empty(), "client {i}: no input was shown");
        // After the camera stopped, the full-resolution frame came.
        assert!(
            r.first_after(1.5, raykit_serve::protocol::Stage::Full)
                .is_some(),
            "client {i}"
        );
    }
    let total: usize = reports.iter().map(|r| r.frames.len()).sum();
    let served = server.state().totals.lock().unwrap().frames;
    assert!(served as usize >= total);
    server.shutdown().await.unwrap();
}
