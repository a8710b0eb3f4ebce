//! Bad and hostile input: malformed, out-of-range, binary, flooding and
//! oversized messages get errors (or, for oversize, a 1009 close; for
//! frames that break the WebSocket protocol, 1002 or 1007) and never stop
//! the server or the other clients; client limits, token checks;
//! unknown query parameters, bodies announced over the limit and lights
//! beyond the camera bound are refused, as are unusable settings at start.

mod support;

use futures_util::SinkExt;
use raykit_serve::{CLOSE_GOING_AWAY, CLOSE_TOO_BIG};
use std::time::Duration;
use support::*;
use tokio_tungstenite::tungstenite::Message;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn malformed_messages_get_errors_and_the_connection_keeps_working() {
    let server = server(config()).await;
    let (mut ws, _) = connect(&server, "").await;
    let (h, _) = next_frame(&mut ws).await;
    ack(&mut ws, &h).await;
    let bad = [
        "not json",
        r#"{"type":"warp"}"#,
        r#"{"no":"type"}"#,
        r#"{"type":"zoom","factor":1e9}"#,
        r#"{"type":"zoom","factor":"big"}"#,
        r#"{"type":"orbit","yaw":1e30}"#,
        r#"{"type":"camera","eye":[1e39,0,0]}"#,
        r#"{"type":"camera","eye":[0,5,0],"target":[0,5,0]}"#,
        r#"{"type":"camera","fov":0}"#,
        r#"{"type":"settings","width":100000}"#,
        r#"{"type":"settings","quality":0}"#,
        r#"{"type":"settings","spp":100000}"#,
        r#"{"type":"ack","frame":999}"#,
        r#"{"type":"reset","fov":10}"#,
        r#"{"type":"reset","seq":5,"sqe":1}"#,
        "[1,2,3]",
        "",
    ];
    for b in bad {
        send(&mut ws, b).await;
        let e = next_text(&mut ws).await;
        assert_eq!(e["type"], "error", "for {b}: {e}");
        assert!(!e["message"].as_str().unwrap().is_empty());
    }
    ws.send(Message::binary(vec![1u8, 2, 3])).await.unwrap();
    let e = next_text(&mut ws).await;
    assert!(e["message"].as_str().unwrap().contains("binary"), "{e}");
    // Still served: a valid input gives a frame showing it.
    send(&mut ws, r#"{"type":"orbit","yaw":0.2,"seq":5}"#).await;
    loop {
        let (h, _) = next_frame(&mut ws).await;
        ack(&mut ws, &h).await;
        if h.input_seq == 5 {
            break;
        }
    }
    let errors = server.state().samples()[0].errors;
    assert_eq!(errors, bad.len() as u64 + 1);
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn floods_are_rate_limited_and_oversized_messages_close_only_that_connection() {
    let mut c = config();
    c.max_inputs_per_second = 50;
    c.max_message_bytes = 1024;
    let server = server(c).await;
    let (mut flood, _) = connect(&server, "").await;
    let (mut calm, _) = connect(&server, "").await;
    for seq in 1..=400 {
        send(
            &mut flood,
            &format!(r#"{{"type":"orbit","yaw":0.001,"seq":{seq}}}"#),
        )
        .await;
    }
    let mut rate_error = false;
    let mut first = None;
    for _ in 0..50 {
        match next_message(&mut flood).await {
            Message::Text(t) if t.contains("per second") => {
                rate_error = true;
                break;
            }
            Message::Binary(b) => first = Some(raykit_serve::protocol::decode_frame(&b).unwrap().0),
            _ => {}
        }
    }
    assert!(rate_error, "no rate-limit error after 400 inputs at once");
    // Acknowledgements still get through while inputs are being dropped.
    let first = match first {
        Some(h) => h,
        None => next_frame(&mut flood).await.0,
    };
    for seq in 401..=500 {
        send(
            &mut flood,
            &format!(r#"{{"type":"orbit","yaw":0.001,"seq":{seq}}}"#),
        )
        .await;
    }
    ack(&mut flood, &first).await;
    let (second, _) = next_frame(&mut flood).await;
    assert_eq!(second.frame, first.frame + 1);
    let applied = server
        .state()
        .samples()
        .iter()
        .map(|s| s.inputs)
        .max()
        .unwrap();
    assert!(
        (50..=60).contains(&applied),
        "{applied} inputs applied, the burst allows 50"
    );

    // An oversized message ends that connection with 1009 …
    flood.send(Message::text("x".repeat(4096))).await.unwrap();
    let closed = loop {
        match tokio::time::timeout(
            Duration::from_secs(10),
            futures_util::StreamExt::next(&mut flood),
        )
        .await
        {
            Ok(Some(Ok(Message::Close(f)))) => break f.map(|f| u16::from(f.code)),
            Ok(Some(Ok(_))) => continue,
            Ok(_) => break None,
            Err(_) => panic!("the oversized message did not end the connection"),
        }
    };
    assert!(
        closed.is_none() || closed == Some(CLOSE_TOO_BIG),
        "{closed:?}"
    );
    // … while the other client and the HTTP API carry on.
    let (h, _) = next_frame(&mut calm).await;
    ack(&mut calm, &h).await;
    send(&mut calm, r#"{"type":"orbit","yaw":0.3,"seq":1}"#).await;
    loop {
        let (h, _) = next_frame(&mut calm).await;
        ack(&mut calm, &h).await;
        if h.input_seq == 1 {
            break;
        }
    }
    let (status, _, _) = http(&server, "GET", "/api/status", "", "").await;
    assert_eq!(status, 200);
    // Binary messages are answered within the same limit: of 200 at once,
    // at most the burst of 50 (and what refills meanwhile) gets a reply.
    let (mut bin, _) = connect(&server, "").await;
    for _ in 0..200 {
        bin.send(Message::binary(vec![7u8; 8])).await.unwrap();
    }
    let mut replies = 0;
    while let Ok(Some(Ok(m))) = tokio::time::timeout(
        Duration::from_millis(500),
        futures_util::StreamExt::next(&mut bin),
    )
    .await
    {
        if matches!(&m, Message::Text(t) if t.contains("binary")) {
            replies += 1;
        }
    }
    assert!(
        (1..=60).contains(&replies),
        "{replies} replies to 200 binary messages"
    );
    // A body over the limit is refused with 413.
    let big = format!(r#"{{"scene":"builtin:{}"}}"#, "a".repeat(2000));
    let (status, _, _) = http(&server, "POST", "/api/scene", "", &big).await;
    assert_eq!(status, 413);
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_client_limit_is_kept() {
    let mut c = config();
    c.max_clients = 2;
    let server = server(c).await;
    let (a, _) = connect(&server, "").await;
    let (_b, _) = connect(&server, "").await;
    let url = format!("ws://{}/ws", server.addr());
    let refused = tokio_tungstenite::connect_async(url.as_str()).await;
    match refused {
        Err(tokio_tungstenite::tungstenite::Error::Http(r)) => assert_eq!(r.status(), 503),
        other => panic!("third client not refused: {:?}", other.map(|_| ())),
    }
    let (status, _, _) = http(&server, "GET", "/mjpeg", "", "").await;
    assert_eq!(status, 503);
    drop(a);
    // The slot frees once the first client's session has ended.
    let mut ok = false;
    for _ in 0..50 {
        tokio::time::sleep(Duration::from_millis(100)).await;
        if tokio_tungstenite::connect_async(url.as_str()).await.is_ok() {
            ok = true;
            break;
        }
    }
    assert!(ok, "the freed slot was not reusable");
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_token_is_required_when_set() {
    let mut c = config();
    c.token = Some("s3cr3t".into());
    let server = server(c).await;
    let (status, _, body) = http(&server, "GET", "/api/status", "", "").await;
    assert_eq!(status, 401);
    assert!(json_body(&body)["error"]
        .as_str()
        .unwrap()
        .contains("token"));
    assert_eq!(
        http(&server, "GET", "/api/status?token=wrong", "", "")
            .await
            .0,
        401
    );
    assert_eq!(
        http(&server, "GET", "/api/status?token=s3cr3t", "", "")
            .await
            .0,
        200
    );
    assert_eq!(
        http(
            &server,
            "GET",
            "/metrics",
            "Authorization: Bearer s3cr3t\r\n",
            ""
        )
        .await
        .0,
        200
    );
    // The scheme's name is case-insensitive (RFC 9110).
    let lower = "Authorization: bearer s3cr3t\r\n";
    assert_eq!(http(&server, "GET", "/metrics", lower, "").await.0, 200);
    let url = format!("ws://{}/ws", server.addr());
    assert!(tokio_tungstenite::connect_async(url.as_str())
        .await
        .is_err());
    let (mut ws, _) = connect(&server, "?token=s3cr3t").await;
    next_frame(&mut ws).await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn silent_clients_are_disconnected_and_answering_ones_stay() {
    let mut c = config();
    c.ping_every = Duration::from_millis(100);
    c.idle_timeout = Duration::from_millis(400);
    let server = server(c).await;
    // This one never reads, so it never answers a ping.
    let url = format!("ws://{}/ws", server.addr());
    let (_silent, _) = tokio_tungstenite::connect_async(url.as_str())
        .await
        .unwrap();
    // This one reads (tungstenite answers pings while reading) and acks.
    let (mut live, hello) = connect(&server, "").await;
    let live_id = hello["client"].as_u64().unwrap();
    let start = std::time::Instant::now();
    while start.elapsed() < Duration::from_millis(1500) {
        if let Some(h) = frame_within(&mut live, Duration::from_millis(50)).await {
            ack(&mut live, &h).await;
        }
    }
    let ids: Vec<u64> = server.state().samples().iter().map(|s| s.id).collect();
    assert_eq!(
        ids,
        vec![live_id],
        "the silent client should be gone, the live one kept"
    );
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn api_writes_must_be_json() {
    let server = server(config()).await;
    let (status, _, body) = http(
        &server,
        "POST",
        "/api/scene",
        "Content-Type: text/plain\r\n",
        r#"{"scene":"builtin:shirley6"}"#,
    )
    .await;
    assert_eq!(status, 415);
    assert!(json_body(&body)["error"]
        .as_str()
        .unwrap()
        .contains("application/json"));
    assert_eq!(server.state().world().geometry.scene.name, "cornell");
    // The lights the status reports can be sent back as they are, and a
    // misspelt field is named.
    let (_, _, status) = http(&server, "GET", "/api/status", "", "").await;
    let lights = serde_json::json!({ "lights": json_body(&status)["lights"] }).to_string();
    let (code, _, reply) = http(&server, "PUT", "/api/lights", "", &lights).await;
    assert_eq!(code, 200, "{}", String::from_utf8_lossy(&reply));
    let typo = r#"{"lights":[{"position":[0,1,2],"colour":[1,1,1]}]}"#;
    let (code, _, reply) = http(&server, "PUT", "/api/lights", "", typo).await;
    assert_eq!(code, 400);
    assert!(json_body(&reply)["error"]
        .as_str()
        .unwrap()
        .contains("colour"));
    // The errors the framework answers are JSON too.
    let big = format!(r#"{{"scene":"{}"}}"#, "x".repeat(64 << 10));
    let cases = [
        ("GET", "/nowhere", "", 404),
        ("DELETE", "/api/scene", "", 405),
        ("POST", "/api/scene", big.as_str(), 413),
        ("GET", "/ws", "", 400),
    ];
    for (method, path, body, want) in cases {
        let (status, head, reply) = http(&server, method, path, "", body).await;
        assert_eq!(status, want, "{method} {path}");
        let message = json_body(&reply)["error"].as_str().unwrap().to_string();
        assert!(!message.is_empty(), "{method} {path}: {head}");
        if want == 405 {
            assert!(head.to_ascii_lowercase().contains("allow:"), "{head}");
        }
    }
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn shutdown_closes_sessions_with_going_away() {
    let server = server(config()).await;
    let (mut ws, _) = connect(&server, "").await;
    next_frame(&mut ws).await;
    // An MJPEG client that never reads its stream does not hold shutdown up
    // for longer than the grace period.
    let mut mjpeg = tokio::net::TcpStream::connect(server.addr()).await.unwrap();
    tokio::io::AsyncWriteExt::write_all(
        &mut mjpeg,
        b"GET /mjpeg?width=1920&height=1080 HTTP/1.1\r\nHost: x\r\n\r\n",
    )
    .await
    .unwrap();
    while server.state().clients().len() < 2 {
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
    let addr = server.addr();
    let stop = tokio::spawn(server.shutdown());
    let code = loop {
        match next_message(&mut ws).await {
            Message::Close(f) => break f.map(|f| u16::from(f.code)),
            _ => continue,
        }
    };
    assert_eq!(code, Some(CLOSE_GOING_AWAY));
    tokio::time::timeout(raykit_serve::SHUTDOWN_GRACE + Duration::from_secs(2), stop)
        .await
        .expect("shutdown within the grace period")
        .unwrap()
        .unwrap();
    assert!(
        tokio::net::TcpStream::connect(addr).await.is_err(),
        "still listening"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn unknown_query_parameters_are_refused_naming_them() {
    let mut c = config();
    c.token = Some("s3cr3t".into());
    let server = server(c).await;
    let before = server.state().world().full;
    let auth = "Authorization: Bearer s3cr3t\r\n";
    let size = r#"{"width":64,"height":48}"#;
    for (method, path, body, name) in [
        ("PUT", "/api/resolution?clinet=1", size, "clinet"),
        ("GET", "/mjpeg?widht=10&height=10", "", "widht"),
        ("GET", "/api/camera?cilent=1", "", "cilent"),
        ("GET", "/api/status?verbose=1", "", "verbose"),
        ("GET", "/ws?format=raw", "", "format"),
    ] {
        let (status, _, reply) = http(&server, method, path, auth, body).await;
        assert_eq!(status, 400, "{method} {path}");
        let message = json_body(&reply)["error"].as_str().unwrap().to_string();
        assert!(message.contains(&format!("'{name}'")), "{path}: {message}");
    }
    // Nothing changed, and the parameters a path takes (and the token) pass.
    assert_eq!(server.state().world().full, before);
    let (status, _, reply) = http(&server, "PUT", "/api/resolution?token=s3cr3t", "", size).await;
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&reply));
    assert_eq!(server.state().world().full, (64, 48));
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_body_announced_over_the_limit_is_refused_at_once() {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut c = config();
    c.header_timeout = Duration::from_secs(5);
    let limit = c.max_message_bytes;
    let server = server(c).await;
    let mut s = tokio::net::TcpStream::connect(server.addr()).await.unwrap();
    let start = std::time::Instant::now();
    let req = format!(
        "PUT /api/lights HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\n\
         Content-Length: {}\r\n\r\n{{\"lights\":[]}}",
        limit * 60
    );
    s.write_all(req.as_bytes()).await.unwrap();
    let mut reply = Vec::new();
    let mut buf = [0u8; 4096];
    // The answer comes without waiting for the rest of the body.
    while !reply.windows(4).any(|w| w == b"\r\n\r\n") {
        let n = tokio::time::timeout(Duration::from_secs(4), s.read(&mut buf))
            .await
            .expect("an answer before the body timeout")
            .unwrap();
        assert!(n > 0, "closed without an answer");
        reply.extend_from_slice(&buf[..n]);
    }
    assert!(
        start.elapsed() < Duration::from_secs(3),
        "{:?}",
        start.elapsed()
    );
    let head = String::from_utf8_lossy(&reply);
    assert!(head.starts_with("HTTP/1.1 413"), "{head}");
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn lights_beyond_the_camera_bound_are_refused_naming_the_field() {
    let server = server(config()).await;
    let (_, _, before) = http(&server, "GET", "/api/status", "", "").await;
    let bound = raykit_core::MAX_CAMERA_COORDINATE;
    for (lights, field) in [
        (
            format!(r#"{{"lights":[{{"position":[{:e},1,0]}}]}}"#, bound * 1e12),
            "lights[0].position",
        ),
        (
            format!(
                r#"{{"lights":[{{"position":[0,1,0]}},{{"position":[0,{:e},0]}}]}}"#,
                -bound * 10.0
            ),
            "lights[1].position",
        ),
        // Within the bound, but too bright that far: the intensity overflows.
        (
            format!(
                r#"{{"lights":[{{"position":[{:e},0,0],"color":[1e6,1,1]}}]}}"#,
                bound
            ),
            "lights[0].color",
        ),
    ] {
        let (status, _, reply) = http(&server, "PUT", "/api/lights", "", &lights).await;
        assert_eq!(status, 400, "{lights}");
        let message = json_body(&reply)["error"].as_str().unwrap().to_string();
        assert!(message.contains(field), "{lights}: {message}");
    }
    // The lights are as they were, each with a finite colour.
    let (_, _, after) = http(&server, "GET", "/api/status", "", "").await;
    assert_eq!(json_body(&before)["lights"], json_body(&after)["lights"]);
    // A far light within the bound is kept, with the colour it was given.
    let far = format!(
        r#"{{"lights":[{{"position":[{:e},1,0],"color":[0.5,0.5,0.5]}}]}}"#,
        bound / 10.0
    );
    let (status, _, reply) = http(&server, "PUT", "/api/lights", "", &far).await;
    assert_eq!(status, 200, "{}", String::from_utf8_lossy(&reply));
    let (_, _, after) = http(&server, "GET", "/api/status", "", "").await;
    let colour = &json_body(&after)["lights"][0]["color"];
    for c in colour.as_array().unwrap() {
        assert!((c.as_f64().unwrap() - 0.5).abs() < 1e-3, "{colour}");
    }
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_empty_token_or_a_missing_scene_folder_is_refused_at_start() {
    let mut c = config();
    c.token = Some(String::new());
    let e = raykit_serve::start(c, loader(), "builtin:cornell")
        .await
        .err()
        .expect("an empty token is refused");
    assert!(format!("{e:#}").contains("token"), "{e:#}");
    let missing =
        std::env::temp_dir().join(format!("raykit-no-such-folder-{}", std::process::id()));
    let mut c = config();
    c.scene_dir = Some(missing.clone());
    let e = raykit_serve::start(c, loader(), "builtin:cornell")
        .await
        .err()
        .expect("a missing scene folder is refused");
    let message = format!("{e:#}");
    let os = std::fs::read_dir(&missing).unwrap_err().to_string();
    assert!(
        message.contains(&missing.display().to_string()),
        "{message}"
    );
    assert!(message.contains(&os), "{message}");
}

/// A WebSocket client over a plain TCP socket, to send frames a WebSocket
/// library would refuse to: the handshake, then raw bytes.
async fn raw_connect(server: &raykit_serve::Server) -> tokio::net::TcpStream {
    use tokio::io::{AsyncReadExt, AsyncWriteExt};
    let mut s = tokio::net::TcpStream::connect(server.addr()).await.unwrap();
    s.write_all(
        b"GET /ws HTTP/1.1\r\nHost: x\r\nUpgrade: websocket\r\nConnection: Upgrade\r\n\
          Sec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\nSec-WebSocket-Version: 13\r\n\r\n",
    )
    .await
    .unwrap();
    let mut head = Vec::new();
    while !head.ends_with(b"\r\n\r\n") {
        head.push(s.read_u8().await.unwrap());
    }
    assert!(head.starts_with(b"HTTP/1.1 101"), "{head:?}");
    s
}

/// The payload of the server's close frame, skipping other frames; `None`
/// if the connection ends without one.
async fn raw_close(s: &mut tokio::net::TcpStream) -> Option<Vec<u8>> {
    use tokio::io::AsyncReadExt;
    let read = async {
        loop {
            let b0 = s.read_u8().await.ok()?;
            let b1 = s.read_u8().await.ok()?;
            let len = match b1 & 0x7f {
                126 => s.read_u16().await.ok()? as usize,
                127 => s.read_u64().await.ok()? as usize,
                n => n as usize,
            };
            let mut payload = vec![0u8; len];
            s.read_exact(&mut payload).await.ok()?;
            if b0 & 0x0f == 8 {
                return Some(payload);
            }
        }
    };
    tokio::time::timeout(Duration::from_secs(10), read)
        .await
        .expect("the server answers within 10 s")
}

/// A client frame: FIN and `opcode` in the first byte, masked with a zero
/// key (so the payload is sent as it is) unless `masked` is false.
fn client_frame(first: u8, payload: &[u8], masked: bool) -> Vec<u8> {
    let mask = if masked { 0x80 } else { 0 };
    let mut f = vec![first];
    if payload.len() < 126 {
        f.push(mask | payload.len() as u8);
    } else {
        f.push(mask | 126);
        f.extend_from_slice(&(payload.len() as u16).to_be_bytes());
    }
    if masked {
        f.extend_from_slice(&[0, 0, 0, 0]);
    }
    f.extend_from_slice(payload);
    f
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn frames_that_break_the_protocol_are_closed_with_its_codes() {
    use tokio::io::AsyncWriteExt;
    let server = server(config()).await;
    // RFC 6455 §7.4.1: 1007 for a text message that is not UTF-8, 1002 for
    // a frame the protocol does not allow (§5.1 masking, §5.2 opcodes and
    // reserved bits, §5.4 continuations, §5.5 control frames of at most
    // 125 bytes), 1009 for a message over the size limit.
    let cases: [(&str, Vec<u8>, u16); 7] = [
        (
            "invalid UTF-8",
            client_frame(0x81, &[0xff, 0xfe], true),
            1007,
        ),
        ("unmasked", client_frame(0x81, b"{}", false), 1002),
        ("reserved opcode", client_frame(0x83, b"", true), 1002),
        ("reserved bit", client_frame(0xc1, b"{}", true), 1002),
        ("orphan continuation", client_frame(0x80, b"x", true), 1002),
        ("200-byte ping", client_frame(0x89, &[0u8; 200], true), 1002),
        // Only the header: it announces the size, and the server answers
        // without reading on (unread data would reset the connection).
        (
            "over the size limit",
            client_frame(0x81, &[b' '; 20_000], true)[..8].to_vec(),
            CLOSE_TOO_BIG,
        ),
    ];
    for (what, frame, code) in cases {
        let mut s = raw_connect(&server).await;
        s.write_all(&frame).await.unwrap();
        let close = raw_close(&mut s).await;
        let got = close
            .as_deref()
            .and_then(|p| p.get(..2))
            .map(|b| u16::from_be_bytes([b[0], b[1]]));
        assert_eq!(got, Some(code), "{what}: close frame {close:?}");
    }
    // The server carries on.
    let (mut ws, _) = connect(&server, "").await;
    next_frame(&mut ws).await;
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn wrong_acks_are_answered_at_most_once_a_second_and_right_ones_still_work() {
    let server = server(config()).await;
    let (mut ws, _) = connect(&server, "").await;
    let (first, _) = next_frame(&mut ws).await;
    let start = std::time::Instant::now();
    let n = 5000u64;
    for i in 0..n {
        send(
            &mut ws,
            &format!(r#"{{"type":"ack","frame":{}}}"#, 123_456 + i),
        )
        .await;
    }
    // The right ack is still taken: the next frame comes.
    ack(&mut ws, &first).await;
    let mut replies = 0u64;
    loop {
        match next_message(&mut ws).await {
            Message::Text(t) if t.contains("ack for frame") => replies += 1,
            Message::Binary(_) => break,
            other => panic!("unexpected {other:?}"),
        }
    }
    // Every wrong ack is counted, but at most one reply a second is sent.
    let seconds = start.elapsed().as_secs();
    assert!(
        (1..=seconds + 1).contains(&replies),
        "{replies} replies to {n} wrong acks in {seconds} s"
    );
    // The frame came after the right ack, which came after the wrong ones.
    assert_eq!(server.state().samples()[0].errors, n);
    server.shutdown().await.unwrap();
}
