//! `raykit serve` with `--scene-dir`, through the command line's own scene
//! loader: files a scene brings in stay inside the folder (links followed),
//! refusals do not tell which files exist elsewhere or where the folder is,
//! a built-in scene over the triangle limit is refused before it is built,
//! a camera the file defines that clients could not set is replaced by a
//! fitted one, and a connection that never finishes its headers is closed.

use std::io::{Read, Write};
use std::net::{SocketAddr, TcpStream};
use std::path::Path;
use std::time::{Duration, Instant};

/// `POST /api/scene` with `{"scene": scene}`: the status and the body.
fn load_scene(addr: SocketAddr, scene: &str) -> (u16, String) {
    let body = serde_json::json!({ "scene": scene }).to_string();
    let mut s = TcpStream::connect(addr).unwrap();
    write!(
        s,
        "POST /api/scene HTTP/1.1\r\nHost: x\r\nConnection: close\r\n\
         Content-Type: application/json\r\nContent-Length: {}\r\n\r\n{body}",
        body.len()
    )
    .unwrap();
    let mut reply = String::new();
    s.read_to_string(&mut reply).unwrap();
    let status = reply[9..12].parse().unwrap();
    let body = reply.split_once("\r\n\r\n").unwrap().1.to_string();
    (status, body)
}

fn write(path: &Path, text: &str) {
    std::fs::write(path, text).unwrap();
}

#[cfg(unix)]
#[test]
fn scene_files_and_what_they_read_stay_in_the_scene_folder() {
    let top = tempfile::tempdir().unwrap();
    let (scenes, outside) = (top.path().join("scenes"), top.path().join("outside"));
    std::fs::create_dir_all(&scenes).unwrap();
    std::fs::create_dir_all(&outside).unwrap();
    let data = Path::new(env!("CARGO_MANIFEST_DIR")).join("crates/io/tests/data");
    std::fs::copy(data.join("transforms.gltf"), scenes.join("transforms.gltf")).unwrap();
    std::fs::copy(data.join("transforms.bin"), outside.join("b.bin")).unwrap();
    // A buffer that is a link to a file outside the folder.
    std::os::unix::fs::symlink(outside.join("b.bin"), scenes.join("transforms.bin")).unwrap();
    // An OBJ file whose material library lies outside, holding a secret.
    write(&outside.join("leak.mtl"), "newmtl x\nNs SECRET-42\n");
    write(
        &scenes.join("leak.obj"),
        "mtllib ../outside/leak.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl x\nf 1 2 3\n",
    );
    // A camera no client could set: a field of view of 179.3 degrees.
    let gltf = std::fs::read_to_string(data.join("transforms.gltf")).unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(&gltf).unwrap();
    doc["cameras"] = serde_json::json!([{"type": "perspective",
        "perspective": {"yfov": 3.13, "znear": 0.1}}]);
    doc["nodes"]
        .as_array_mut()
        .unwrap()
        .push(serde_json::json!({"camera": 0, "translation": [0, 0, 5]}));
    let main = doc["scene"].as_u64().unwrap() as usize;
    let camera_node = doc["nodes"].as_array().unwrap().len() - 1;
    let roots = doc["scenes"][main]["nodes"].as_array_mut().unwrap();
    roots.push(serde_json::json!(camera_node));
    std::fs::copy(data.join("transforms.bin"), scenes.join("wide.bin")).unwrap();
    write(
        &scenes.join("wide.gltf"),
        &doc.to_string().replace("transforms.bin", "wide.bin"),
    );

    let rt = tokio::runtime::Runtime::new().unwrap();
    let config = raykit_serve::ServeConfig {
        addr: "127.0.0.1:0".parse().unwrap(),
        full: (160, 90),
        scene_dir: Some(scenes.clone()),
        max_scene_triangles: 200_000,
        header_timeout: Duration::from_millis(500),
        ..raykit_serve::ServeConfig::default()
    };
    let loader = raykit_lab::args::scene_arg::loader();
    let server = rt
        .block_on(raykit_serve::start(config, loader, "builtin:cornell"))
        .unwrap();
    let addr = server.addr();
    let top_path = top.path().to_string_lossy().into_owned();

    let (status, body) = load_scene(addr, "transforms.gltf");
    assert_eq!(status, 400, "{body}");
    assert!(body.contains("reads a file outside --scene-dir"), "{body}");

    let (status, body) = load_scene(addr, "leak.obj");
    assert_eq!(status, 400, "{body}");
    assert!(body.contains("reads a file outside --scene-dir"), "{body}");
    assert!(!body.contains("SECRET"), "{body}");

    // Outside names are refused alike whether the file exists or not.
    let exists = format!("../outside/{}", "b.bin");
    for name in [exists.as_str(), "../outside/nothing.obj", "/etc/passwd"] {
        let (status, body) = load_scene(addr, name);
        assert_eq!(status, 400, "{name}: {body}");
        assert!(body.contains("is outside --scene-dir"), "{name}: {body}");
    }
    for name in ["", "."] {
        let (status, body) = load_scene(addr, name);
        assert_eq!(status, 400, "{name}: {body}");
        assert!(!body.contains(&top_path), "{name}: {body}");
    }

    let started = Instant::now();
    let (status, body) = load_scene(addr, "builtin:scatter:triangles=50_000_000");
    assert_eq!(status, 400, "{body}");
    assert!(body.contains("asks for 50000000 triangles"), "{body}");
    assert_eq!(server.state().world().geometry.scene.name, "cornell");
    eprintln!("refused in {:?}", started.elapsed());

    let (status, body) = load_scene(addr, "wide.gltf");
    assert_eq!(status, 200, "{body}");
    let camera = server.state().world().geometry.default_camera(16.0 / 9.0);
    assert!(
        raykit_serve::camera_control::camera_problem(&camera).is_none(),
        "{camera:?}"
    );

    // Headers never finished: the server closes the connection.
    let mut slow = TcpStream::connect(addr).unwrap();
    slow.write_all(b"GET /api/status HTTP/1.1\r\nHost: x\r\n")
        .unwrap();
    slow.set_read_timeout(Some(Duration::from_secs(30)))
        .unwrap();
    let mut rest = Vec::new();
    let closed = slow.read_to_end(&mut rest);
    assert!(closed.is_ok(), "{closed:?}");
    // Headers complete, the body never finished: 408, and the connection
    // is closed.
    let mut trickle = TcpStream::connect(addr).unwrap();
    trickle
        .write_all(
            b"POST /api/scene HTTP/1.1\r\nHost: x\r\nContent-Type: application/json\r\nContent-Length: 100\r\n\r\n{\"sc",
        )
        .unwrap();
    trickle
        .set_read_timeout(Some(Duration::from_secs(30)))
        .unwrap();
    let mut answer = Vec::new();
    let closed = trickle.read_to_end(&mut answer);
    assert!(closed.is_ok(), "{closed:?}");
    let answer = String::from_utf8_lossy(&answer);
    assert!(answer.starts_with("HTTP/1.1 408"), "{answer}");
    assert!(answer.contains("did not arrive within"), "{answer}");
    // Nor is a connection that sends nothing at all kept.
    let mut silent = TcpStream::connect(addr).unwrap();
    silent
        .set_read_timeout(Some(Duration::from_secs(30)))
        .unwrap();
    let closed = silent.read_to_end(&mut rest);
    assert!(closed.is_ok(), "{closed:?}");

    rt.block_on(server.shutdown()).unwrap();
}
