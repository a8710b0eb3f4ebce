//! The WebSocket protocol against an in-process server: frames equal a
//! direct render of the same camera, inputs move the camera as the camera
//! functions say, refinement follows preview → full → refined, a client
//! that does not acknowledge gets no backlog and does not slow others.

mod support;

use raykit_serve::camera_control::orbit;
use raykit_serve::protocol::Stage;
use std::time::Duration;
use support::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn frames_match_a_direct_render_and_refine_in_stages() {
    let server = server(config()).await;
    let (mut ws, hello) = connect(&server, "").await;
    assert_eq!(hello["full"], serde_json::json!([160, 90]));
    assert_eq!(hello["triangles"], 1314);

    let (h, img) = next_frame(&mut ws).await;
    assert_eq!(
        (h.stage, h.width, h.height, h.spp, h.frame),
        (Stage::Preview, 80, 45, 1, 1)
    );
    let camera = camera_of(&h);
    let want = direct_render(&server, &camera, 80, 45, 1);
    let diff = mean_diff(img.as_raw(), &want);
    assert!(
        diff < 4.0,
        "preview differs from the direct render by {diff}"
    );
    // The comparison can tell pictures apart: another view differs a lot.
    let other = direct_render(&server, &orbit(&camera, 0.6, 0.3), 80, 45, 1);
    let other_diff = mean_diff(img.as_raw(), &other);
    eprintln!("mean difference to the direct render {diff:.2}, to another view {other_diff:.2}");
    assert!(other_diff > 3.0 * diff.max(1.0));

    ack(&mut ws, &h).await;
    let (h2, img2) = next_frame(&mut ws).await;
    assert_eq!(
        (h2.stage, h2.width, h2.height, h2.spp),
        (Stage::Full, 160, 90, 1)
    );
    let d2 = mean_diff(img2.as_raw(), &direct_render(&server, &camera, 160, 90, 1));
    assert!(d2 < 4.0, "full frame differs by {d2}");
    ack(&mut ws, &h2).await;
    let (h3, img3) = next_frame(&mut ws).await;
    assert_eq!(
        (h3.stage, h3.width, h3.height, h3.spp),
        (Stage::Refined, 160, 90, 4)
    );
    let d3 = mean_diff(img3.as_raw(), &direct_render(&server, &camera, 160, 90, 4));
    assert!(d3 < 4.0, "refined frame differs by {d3}");
    ack(&mut ws, &h3).await;
    // Fully refined and nothing changed: no more frames.
    assert!(frame_within(&mut ws, Duration::from_millis(400))
        .await
        .is_none());
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn inputs_move_the_camera_and_the_frame_reports_their_seq() {
    let server = server(config()).await;
    let (mut ws, _) = connect(&server, "").await;
    let (h, img) = next_frame(&mut ws).await;
    let before = camera_of(&h);
    send(&mut ws, r#"{"type":"orbit","yaw":0.5,"pitch":0.2,"seq":1}"#).await;
    ack(&mut ws, &h).await;
    let (h2, img2) = loop {
        let (h2, img2) = next_frame(&mut ws).await;
        if h2.input_seq >= 1 {
            break (h2, img2);
        }
        ack(&mut ws, &h2).await;
    };
    assert_eq!(h2.stage, Stage::Preview);
    let want = orbit(&before, 0.5, 0.2);
    let got = camera_of(&h2);
    assert!(
        (got.eye - want.eye).length() < 1e-4 && got.target == want.target,
        "{got:?} vs {want:?}"
    );
    assert!(
        mean_diff(img.as_raw(), img2.as_raw()) > 2.0,
        "the picture did not change"
    );
    ack(&mut ws, &h2).await;
    // Pan, zoom, fly, reset: each shows up in the next frame's camera.
    send(&mut ws, r#"{"type":"zoom","factor":0.5,"seq":2}"#).await;
    let h3 = loop {
        let (h3, _) = next_frame(&mut ws).await;
        ack(&mut ws, &h3).await;
        if h3.input_seq >= 2 {
            break h3;
        }
    };
    let c3 = camera_of(&h3);
    assert!((c3.eye.distance(c3.target) - 0.5 * want.eye.distance(want.target)).abs() < 1e-3);
    send(&mut ws, r#"{"type":"reset","seq":3}"#).await;
    let h4 = loop {
        let (h4, _) = next_frame(&mut ws).await;
        ack(&mut ws, &h4).await;
        if h4.input_seq >= 3 {
            break h4;
        }
    };
    assert_eq!(camera_of(&h4), before);
    server.shutdown().await.unwrap();
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_that_does_not_ack_gets_no_backlog_and_does_not_slow_others() {
    let server = server(config()).await;
    let (mut slow, _) = connect(&server, "").await;
    let (mut fast, _) = connect(&server, "").await;
    let (first, _) = next_frame(&mut slow).await;
    // The slow client keeps moving but never acknowledges.
    for seq in 1..=20 {
        send(
            &mut slow,
            &format!(r#"{{"type":"orbit","yaw":0.01,"seq":{seq}}}"#),
        )
        .await;
    }
    // Meanwhile the fast client moves and acknowledges every frame.
    let mut fast_frames = 0;
    let start = std::time::Instant::now();
    let mut seq = 0;
    while start.elapsed() < Duration::from_millis(1500) {
        seq += 1;
        send(
            &mut fast,
            &format!(r#"{{"type":"orbit","yaw":-0.01,"seq":{seq}}}"#),
        )
        .await;
        let (h, _) = next_frame(&mut fast).await;
        ack(&mut fast, &h).await;
        fast_frames += 1;
    }
    assert!(
        fast_frames >= 5,
        "the fast client got only {fast_frames} frames in 1.5 s"
    );
    // Nothing more reached the slow client while its frame was unacknowledged.
    assert!(frame_within(&mut slow, Duration::from_millis(300))
        .await
        .is_none());
    // After the ack it gets the latest view (all 20 inputs), not a backlog.
    ack(&mut slow, &first).await;
    let (h, _) = next_frame(&mut slow).await;
    assert_eq!((h.frame, h.input_seq, h.stage), (2, 20, Stage::Preview));
    let status = server.state().samples();
    let slow_sample = status
        .iter()
        .find(|s| s.frames == 2)
        .expect("slow client listed");
    assert_eq!(slow_sample.inputs, 20);
    server.shutdown().await.unwrap();
}
