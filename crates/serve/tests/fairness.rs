//! One client's large frames do not hold up the others: while a client
//! renders a frame at many times the others' size and samples, another
//! client keeps getting the frames its inputs ask for, each equal to a
//! direct render of its camera.

mod support;

use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;
use support::*;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_client_keeps_getting_frames_while_another_renders_a_large_one() {
    let mut c = config();
    // Small slices, so that the large frame has hundreds of them.
    c.slice_samples_per_thread = 4096;
    c.settle = Duration::from_millis(50);
    let server = server(c).await;

    // The hog: full-size frames at 640×360, then a refined one with 16
    // samples per pixel, 3.7 million samples.
    let (mut hog, _) = connect(&server, "").await;
    send(
        &mut hog,
        r#"{"type":"settings","width":640,"height":360,"spp":16,"previews":false,"seq":1}"#,
    )
    .await;
    loop {
        let (h, _) = next_frame(&mut hog).await;
        ack(&mut hog, &h).await;
        if h.input_seq == 1 && h.width == 640 {
            break;
        }
    }
    // Its refined frame is on the way; note when it arrives.
    let hog_done = Arc::new(AtomicBool::new(false));
    let done = hog_done.clone();
    let hog_task = tokio::spawn(async move {
        let (h, _) = next_frame(&mut hog).await;
        done.store(true, Ordering::SeqCst);
        (h, hog)
    });

    // The other client, at 160×90 with previews of 80×45, moves and gets
    // a frame for each move while the refined frame renders.
    let (mut ws, _) = connect(&server, "").await;
    let mut frames = 0;
    let mut seq = 0;
    while !hog_done.load(Ordering::SeqCst) {
        let (h, img) = next_frame(&mut ws).await;
        ack(&mut ws, &h).await;
        if hog_done.load(Ordering::SeqCst) {
            break;
        }
        if h.input_seq == seq {
            frames += 1;
            let direct = direct_render(&server, &camera_of(&h), h.width, h.height, h.spp);
            let d = mean_diff(img.as_raw(), &direct);
            assert!(
                d < 4.0,
                "frame {} differs from a direct render by {d}",
                h.frame
            );
            seq += 1;
            send(
                &mut ws,
                &format!(r#"{{"type":"orbit","yaw":0.05,"seq":{seq}}}"#),
            )
            .await;
        }
    }
    let (refined, _hog) = hog_task.await.unwrap();
    assert_eq!(
        (refined.width, refined.height, refined.spp),
        (640, 360, 16),
        "the hog's refined frame"
    );
    assert!(
        frames >= 5,
        "{frames} frames for the small client while the large one rendered"
    );
    server.shutdown().await.unwrap();
}
