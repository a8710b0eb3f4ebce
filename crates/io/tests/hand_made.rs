//! Small hand-made files in `tests/data` whose exact answer is worked out by
//! hand (see `tests/data/README.md`): glTF node transforms (TRS and matrix,
//! nesting, mirroring), strips, skipped modes, scene choice, external and
//! data-URI buffers, materials; OBJ groups, MTL materials and a missing MTL.

mod common;

use common::*;
use raykit_core::{Part, Vec3};
use raykit_io::{load, load_mesh, ErrorKind, Location};

fn close(a: Vec3, b: Vec3) -> bool {
    (a - b).abs().max_element() < 1e-5
}

#[test]
fn gltf_node_transforms_match_hand_computation() {
    let loaded = load(&local("transforms.gltf")).unwrap();
    let m = &loaded.mesh;
    // root: T(10,0,0) S(2); tri_child: Rz(90°); strip_child: matrix T(0,0,5);
    // mirror: S(-1,1,1) at the scene root. The decoy scene is not loaded.
    let expect: [[Vec3; 3]; 4] = [
        // (0,0,0) (1,0,0) (0,1,0) rotated, scaled, translated.
        [
            Vec3::new(10.0, 0.0, 0.0),
            Vec3::new(10.0, 2.0, 0.0),
            Vec3::new(8.0, 0.0, 0.0),
        ],
        // Strip (0,1,2), then (2,1,3) for the odd triangle; p -> 2(p + 5z) + 10x.
        [
            Vec3::new(10.0, 0.0, 10.0),
            Vec3::new(12.0, 0.0, 10.0),
            Vec3::new(10.0, 2.0, 10.0),
        ],
        [
            Vec3::new(10.0, 2.0, 10.0),
            Vec3::new(12.0, 0.0, 10.0),
            Vec3::new(12.0, 2.0, 10.0),
        ],
        // Mirrored: winding flipped so the face still points along +z.
        [
            Vec3::new(0.0, 0.0, 0.0),
            Vec3::new(0.0, 1.0, 0.0),
            Vec3::new(-1.0, 0.0, 0.0),
        ],
    ];
    assert_eq!(m.num_triangles(), 4);
    for (i, e) in expect.iter().enumerate() {
        let got = m.triangle(i);
        for k in 0..3 {
            assert!(
                close(got[k], e[k]),
                "triangle {i} corner {k}: {:?} vs {:?}",
                got[k],
                e[k]
            );
        }
        assert!(m.face_normal(i).z > 0.0, "triangle {i} faces +z");
    }
    assert!((m.area() - (2.0 + 4.0 + 0.5)).abs() < 1e-5, "{}", m.area());
    let b = m.bounds();
    assert!(close(b.min, Vec3::new(-1.0, 0.0, 0.0)) && close(b.max, Vec3::new(12.0, 2.0, 10.0)));
    // Parts: one per node with a mesh, in scene order.
    let part = |name: &str, node| Part {
        name: name.into(),
        node: Some(node),
    };
    assert_eq!(
        m.parts,
        vec![
            part("tri_child", 1),
            part("strip_child", 2),
            part("mirror", 3)
        ]
    );
    assert_eq!(m.tri_part, vec![0, 1, 1, 2]);
    // The LINES primitive is skipped with a warning naming it, and the
    // texture image (which is not there) with one naming the image.
    assert_eq!(loaded.warnings.len(), 2, "{:?}", loaded.warnings);
    assert!(loaded.warnings[0].contains("images[0] (uri \"checker.png\")"));
    assert!(loaded.warnings[0].contains("checker.png"));
    assert!(loaded.warnings[1].contains("meshes[1].primitives[1]"));
    assert!(loaded.warnings[1].contains("Lines"));
    assert!(m.materials[0].base_texture.is_none());
    // The strip has no normals: its corners hold zeros ("use the face's"),
    // the other primitives keep theirs, unit length.
    let normals = m.normals.as_ref().expect("normals of the other primitives");
    for (t, tri) in m.indices.iter().enumerate() {
        for &v in tri {
            let len = normals[v as usize].length();
            if m.tri_part[t] == 1 {
                assert_eq!(len, 0.0, "strip triangle {t}");
            } else {
                assert!((len - 1.0).abs() < 1e-5, "triangle {t}: {len}");
            }
        }
    }
    // Materials: the tinted one, then the default for the strip.
    assert_eq!(m.tri_material, vec![0, 1, 1, 0]);
    assert_eq!(m.materials[0].name, "tinted");
    assert_eq!(m.materials[0].diffuse, [0.5, 0.25, 1.0]);
    assert_eq!(
        m.materials[0].diffuse_texture.as_deref(),
        Some("checker.png")
    );
    assert_eq!(m.materials[1].name, "default");
}

#[test]
fn gltf_normals_follow_the_inverse_transpose() {
    // Only the triangle mesh: keep the hierarchy but drop the strip node.
    let text = std::fs::read_to_string(local("transforms.gltf")).unwrap();
    let text = text.replace("\"children\": [\n    1,\n    2\n   ]", "\"children\": [1]");
    assert!(text.contains("\"children\": [1]"), "fixture layout changed");
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(local("transforms.bin"), dir.path().join("transforms.bin")).unwrap();
    let p = dir.path().join("t.gltf");
    std::fs::write(&p, text).unwrap();
    let m = load_mesh(&p).unwrap();
    assert_eq!(m.num_triangles(), 2);
    for n in m.normals.as_ref().unwrap() {
        assert!(close(*n, Vec3::Z), "{n:?}");
    }
}

#[test]
fn gltf_missing_external_buffer_is_an_io_error_naming_the_buffer() {
    let e = load(&local("missing_buffer.gltf")).unwrap_err();
    assert_eq!(e.kind(), ErrorKind::Io);
    assert_eq!(e.location(), &Location::Json("buffers[0].uri".into()));
    assert!(e
        .to_string()
        .contains("missing_buffer.gltf: buffers[0].uri: cannot read"));
    assert!(e.to_string().contains("no_such_file.bin"));
}

#[test]
fn obj_with_mtl_groups_and_vt_vn() {
    let m = load_mesh(&local("cube.obj")).unwrap();
    assert_eq!(m.num_triangles(), 12);
    // 6 faces x 4 distinct (v, vt, vn) corners.
    assert_eq!(m.positions.len(), 24);
    assert!((m.area() - 6.0).abs() < 1e-9);
    let b = m.bounds();
    assert_eq!((b.min, b.max), (Vec3::ZERO, Vec3::ONE));
    let names: Vec<&str> = m.parts.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, vec!["cube/bottom_top", "cube/sides"]);
    assert_eq!(m.tri_part, [vec![0; 4], vec![1; 8]].concat());
    assert_eq!(m.tri_material, [vec![0; 4], vec![1; 8]].concat());
    let red = &m.materials[0];
    assert_eq!((red.name.as_str(), red.diffuse), ("red", [1.0, 0.0, 0.0]));
    assert_eq!((red.shininess, red.reflectivity), (50.0, 0.25));
    let glass = &m.materials[1];
    assert_eq!(glass.name, "glass");
    assert!((glass.transmission - 0.9).abs() < 1e-6);
    let tex = local("textures/glass tint.png");
    assert_eq!(glass.diffuse_texture.as_deref(), tex.to_str());
    // Each triangle's normal attribute agrees with its geometric normal.
    let normals = m.normals.as_ref().unwrap();
    let uvs = m.uvs.as_ref().unwrap();
    for i in 0..m.num_triangles() {
        let g = m.face_normal(i).normalize();
        for &v in &m.indices[i] {
            let n = normals[v as usize];
            assert!(n.dot(g).abs() > 0.999, "triangle {i}");
            let t = uvs[v as usize];
            assert!(t.x == 0.0 || t.x == 1.0);
        }
    }
}

#[test]
fn missing_mtl_falls_back_to_default_material_with_a_warning() {
    let loaded = load(&local("missing_mtl.obj")).unwrap();
    assert_eq!(loaded.warnings.len(), 1, "{:?}", loaded.warnings);
    let w = &loaded.warnings[0];
    assert!(
        w.contains("mtllib") && w.contains("cannot read") && w.contains("default colours"),
        "{w}"
    );
    let m = loaded.mesh;
    assert_eq!(m.materials.len(), 1);
    assert_eq!(m.materials[0].name, "shiny");
    assert_eq!(
        m.materials[0].diffuse,
        raykit_core::Material::default().diffuse
    );
    assert_eq!(m.tri_material, vec![0]);
}

/// A glTF file's external buffers must lie beside or below it: absolute
/// paths, `..` and URIs with a scheme are refused by name, a device is not
/// read, and only the first byteLength bytes of a longer file are used.
#[test]
fn gltf_external_files_stay_in_the_files_folder() {
    let text = std::fs::read_to_string(local("transforms.gltf")).unwrap();
    assert!(
        text.contains("\"uri\": \"transforms.bin\""),
        "fixture layout changed"
    );
    let dir = tempfile::tempdir().unwrap();
    let inner = dir.path().join("scene");
    std::fs::create_dir_all(inner.join("sub")).unwrap();
    std::fs::copy(local("transforms.bin"), dir.path().join("outside.bin")).unwrap();
    let with_uri = |uri: &str| {
        let p = inner.join("t.gltf");
        std::fs::write(
            &p,
            text.replace("\"transforms.bin\"", &format!("\"{uri}\"")),
        )
        .unwrap();
        load(&p)
    };
    let outside = dir.path().join("outside.bin");
    for (uri, needle) in [
        ("../outside.bin", "leaves the folder of the file naming it"),
        (
            outside.to_str().unwrap(),
            "leaves the folder of the file naming it",
        ),
        (
            "sub/..%2F../outside.bin",
            "leaves the folder of the file naming it",
        ),
        ("file:///etc/passwd", "has a scheme"),
        ("/dev/zero", "leaves the folder of the file naming it"),
        ("sub", "not a regular file (a folder)"),
    ] {
        let e = with_uri(uri).unwrap_err();
        assert_eq!(
            e.location(),
            &Location::Json("buffers[0].uri".into()),
            "{uri}"
        );
        assert!(e.to_string().contains(needle), "{uri}: {e}");
    }
    // Beside and below the file it loads, and a longer file gives the same mesh.
    let want = load(&local("transforms.gltf")).unwrap().mesh;
    let mut longer = std::fs::read(local("transforms.bin")).unwrap();
    std::fs::write(inner.join("sub/b.bin"), &longer).unwrap();
    assert_eq!(
        with_uri("sub/b.bin").unwrap().mesh.positions,
        want.positions
    );
    longer.extend_from_slice(&[7u8; 100]);
    std::fs::write(inner.join("b.bin"), &longer).unwrap();
    assert_eq!(with_uri("./b.bin").unwrap().mesh.positions, want.positions);
}

/// POSITION must be float unless the file declares KHR_mesh_quantization:
/// bytes declared as anything else are refused at the accessor, and with
/// the extension declared the same file loads.
#[test]
fn gltf_quantized_positions_need_their_extension() {
    let text = std::fs::read_to_string(local("transforms.gltf")).unwrap();
    let first = "\"componentType\": 5126";
    assert!(text.contains(first), "fixture layout changed");
    let byte_positions = text.replacen(first, "\"componentType\": 5120", 1);
    let dir = tempfile::tempdir().unwrap();
    std::fs::copy(local("transforms.bin"), dir.path().join("transforms.bin")).unwrap();
    let p = dir.path().join("t.gltf");
    std::fs::write(&p, &byte_positions).unwrap();
    let e = load(&p).unwrap_err();
    assert_eq!(e.location(), &Location::Json("accessors[0]".into()), "{e}");
    assert!(e.to_string().contains("KHR_mesh_quantization"), "{e}");
    let declared = byte_positions.replacen(
        "\"asset\": {",
        "\"extensionsUsed\": [\"KHR_mesh_quantization\"],\n \"asset\": {",
        1,
    );
    std::fs::write(&p, declared).unwrap();
    let m = load(&p).unwrap().mesh;
    let floats = load(&local("transforms.gltf")).unwrap().mesh;
    assert_eq!(m.num_triangles(), floats.num_triangles());
}

/// A one-triangle glTF (data-URI buffer) with `nodes` (the last carries the
/// mesh) and `scene` as the scene's root list.
fn gltf_with_nodes(nodes: &[String], scene: &str) -> String {
    format!(
        r#"{{"asset":{{"version":"2.0"}},
"buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,AAAAAAAAAAAAAAAAAACAPwAAAAAAAAAAAAAAAAAAgD8AAAAA"}}],
"bufferViews":[{{"buffer":0,"byteLength":36}}],
"accessors":[{{"bufferView":0,"componentType":5126,"count":3,"type":"VEC3","min":[0,0,0],"max":[1,1,0]}}],
"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}}}}]}}],
"nodes":[{}],"scenes":[{{"nodes":[{scene}]}}],"scene":0}}"#,
        nodes.join(",")
    )
}

/// Nodes form disjoint trees in glTF 2.0. A node that two parents share,
/// nesting 40 deep, would be walked 2^40 times (a 1.4 KB file made the
/// loader abort asking for gigabytes); it, a root listed twice and a cycle
/// are refused naming the node, and the same tree without the sharing
/// loads its one triangle.
#[test]
fn gltf_nodes_reached_twice_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    let chain = |children: &dyn Fn(usize) -> String| -> Vec<String> {
        (0..40)
            .map(|i| format!(r#"{{"children":[{}]}}"#, children(i)))
            .chain([r#"{"mesh":0}"#.to_string()])
            .collect()
    };
    let shared = chain(&|i| format!("{0},{0}", i + 1));
    let single = chain(&|i| format!("{}", i + 1));
    let cycle = vec![
        r#"{"children":[1]}"#.to_string(),
        r#"{"children":[0],"mesh":0}"#.to_string(),
    ];
    for (name, nodes, scene, node) in [
        ("shared", &shared, "0", 40),
        ("twice", &single, "0,0", 0),
        ("cycle", &cycle, "0", 0),
    ] {
        let path = dir.path().join(format!("{name}.gltf"));
        std::fs::write(&path, gltf_with_nodes(nodes, scene)).unwrap();
        let e = load(&path).unwrap_err().to_string();
        assert!(e.contains("reached twice"), "{name}: {e}");
        assert!(e.contains(&format!("nodes[{node}]")), "{name}: {e}");
    }
    let path = dir.path().join("single.gltf");
    std::fs::write(&path, gltf_with_nodes(&single, "0")).unwrap();
    assert_eq!(load(&path).unwrap().mesh.num_triangles(), 1);
}

/// glTF indices are 32-bit. The `gltf` crate reads `"mesh": 4294967296`
/// as mesh 0; such a file is refused at the index's line, and the same file
/// with index 0 loads.
#[test]
fn gltf_indices_beyond_32_bits_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    for (mesh, wraps) in [
        ("0", false),
        ("4294967296", true),
        ("18446744073709551615", true),
    ] {
        let path = dir.path().join(format!("m{mesh}.gltf"));
        let text = gltf_with_nodes(&[format!("{{\"mesh\":{mesh}}}")], "0");
        std::fs::write(&path, &text).unwrap();
        match load(&path) {
            Ok(m) => assert!(!wraps && m.mesh.num_triangles() == 1, "{mesh} loaded"),
            Err(e) => {
                assert!(wraps, "{mesh}: {e}");
                let line = text.lines().position(|l| l.contains(mesh)).unwrap() + 1;
                let e = e.to_string();
                assert!(e.contains(&format!(".gltf:{line}: ")), "{e}");
                assert!(e.contains(&format!("\"mesh\": {mesh} is beyond")), "{e}");
            }
        }
    }
}

/// Text formats end a line at `\n`, `\r\n` or a lone `\r` (classic Mac
/// OS), so an OBJ or ASCII STL written with any of them loads the same
/// triangles, and errors name the same line.
#[test]
fn every_line_end_convention_loads_the_same_mesh() {
    let dir = tempfile::tempdir().unwrap();
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 1 1 0\nf 1 2 3\nf 2 4 3\n";
    let stl = "solid s\nfacet normal 0 0 1\nouter loop\nvertex 0 0 0\nvertex 1 0 0\n\
               vertex 0 1 0\nendloop\nendfacet\nendsolid s\n";
    for (name, text) in [("m.obj", obj), ("m.stl", stl)] {
        let mut loaded = Vec::new();
        for end in ["\n", "\r\n", "\r"] {
            let path = dir.path().join(name);
            std::fs::write(&path, text.replace('\n', end)).unwrap();
            let m = load(&path)
                .unwrap_or_else(|e| panic!("{name} {end:?}: {e}"))
                .mesh;
            loaded.push((m.positions, m.indices));
            let broken = text.replacen("0 1 0", "0 x 0", 1).replace('\n', end);
            std::fs::write(&path, broken).unwrap();
            let e = load(&path).unwrap_err().to_string();
            let line = text.lines().position(|l| l.contains("0 1 0")).unwrap() + 1;
            assert!(e.contains(&format!("{name}:{line}: ")), "{end:?}: {e}");
        }
        assert!(loaded.iter().all(|m| *m == loaded[0]), "{name}");
        assert!(!loaded[0].1.is_empty(), "{name}");
    }
}

/// OBJ material libraries and their textures are read from regular files
/// only (a FIFO named by `mtllib` made the loader wait forever), each
/// library once however often it is named, and each texture decoded once
/// per OBJ file, whatever the spelling of its path or the library naming
/// it.
#[cfg(unix)]
#[test]
fn obj_libraries_and_textures_are_read_once_from_regular_files() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    image::RgbImage::from_pixel(4, 2, image::Rgb([200, 100, 50]))
        .save(d.join("wood.png"))
        .unwrap();
    std::fs::write(
        d.join("a.mtl"),
        "newmtl a\nmap_Kd wood.png\nnewmtl b\nmap_Kd ./wood.png\n",
    )
    .unwrap();
    std::fs::write(d.join("c.mtl"), "newmtl c\nmap_Kd sub/../wood.png\n").unwrap();
    std::fs::create_dir(d.join("sub")).unwrap();
    let fifo = d.join("fifo.mtl");
    assert!(std::process::Command::new("mkfifo")
        .arg(&fifo)
        .status()
        .unwrap()
        .success());
    let mut obj = String::from("mtllib fifo.mtl\nmtllib gone.mtl\n");
    for _ in 0..100 {
        obj.push_str("mtllib a.mtl c.mtl\n");
    }
    obj.push_str("v 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n");
    let path = d.join("m.obj");
    std::fs::write(&path, obj).unwrap();
    let scene = load(&path).unwrap();
    let materials = &scene.mesh.materials;
    let names: Vec<&str> = materials.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["a", "b", "c"]);
    // The libraries that cannot be read are named in warnings, once each.
    let unread: Vec<&String> = scene
        .warnings
        .iter()
        .filter(|w| w.contains("default colours"))
        .collect();
    assert_eq!(unread.len(), 2, "{:?}", scene.warnings);
    assert!(
        unread[0].starts_with("line 1: mtllib fifo.mtl: ")
            && unread[0].contains("not a regular file"),
        "{}",
        unread[0]
    );
    assert!(
        unread[1].starts_with("line 2: mtllib gone.mtl: cannot read "),
        "{}",
        unread[1]
    );
    let textures: Vec<_> = materials
        .iter()
        .map(|m| m.base_texture.clone().expect("texture loaded"))
        .collect();
    assert!(textures
        .iter()
        .all(|t| std::sync::Arc::ptr_eq(t, &textures[0])));
    assert_eq!((textures[0].width, textures[0].height), (4, 2));
}

/// glTF images that share their bytes (the same URI or buffer view) are
/// decoded once and shared: twelve images of one 250 KB PNG of 8000²
/// texels took 12 GB and aborted the loader.
#[test]
fn gltf_images_with_one_source_are_decoded_once() {
    let dir = tempfile::tempdir().unwrap();
    image::RgbImage::from_pixel(2, 2, image::Rgb([10, 20, 30]))
        .save(dir.path().join("tex.png"))
        .unwrap();
    let primitive = |m: usize| format!(r#"{{"attributes":{{"POSITION":0}},"material":{m}}}"#);
    let json = gltf_with_nodes(&[r#"{"mesh":0}"#.to_string()], "0").replace(
        r#""meshes":[{"primitives":[{"attributes":{"POSITION":0}}]}]"#,
        &format!(
            r#""meshes":[{{"primitives":[{},{}]}}],
"images":[{{"uri":"tex.png"}},{{"uri":"tex.png"}}],
"textures":[{{"source":0}},{{"source":1}}],
"materials":[{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":0}}}}}},
{{"pbrMetallicRoughness":{{"baseColorTexture":{{"index":1}}}}}}]"#,
            primitive(0),
            primitive(1)
        ),
    );
    let path = dir.path().join("two.gltf");
    std::fs::write(&path, json).unwrap();
    let scene = load(&path).unwrap();
    let textures: Vec<_> = scene
        .mesh
        .materials
        .iter()
        .map(|m| m.base_texture.clone().expect("texture loaded"))
        .collect();
    assert_eq!(textures.len(), 2);
    assert!(std::sync::Arc::ptr_eq(&textures[0], &textures[1]));
}

/// A concave face, the L of three unit squares listed from a corner that
/// does not see the whole face, in OBJ, ASCII PLY and OFF: its triangles
/// cover the L (area 3) and nothing of the notch [1, 2]² beside it, which
/// a fan from the first corner would cover. The face is tilted out of the
/// axis planes, so the cut works in the face's own plane.
#[test]
fn concave_faces_are_cut_without_covering_their_notch() {
    let l2 = [
        [2.0f32, 0.0],
        [2.0, 1.0],
        [1.0, 1.0],
        [1.0, 2.0],
        [0.0, 2.0],
        [0.0, 0.0],
    ];
    // The plane z = 0.3 x + 0.2 y.
    let lift = |p: [f32; 2]| Vec3::new(p[0], p[1], 0.3 * p[0] + 0.2 * p[1]);
    let verts: Vec<Vec3> = l2.iter().map(|&p| lift(p)).collect();
    let vlines: String = verts
        .iter()
        .map(|v| format!("{} {} {}\n", v.x, v.y, v.z))
        .collect();
    let dir = tempfile::tempdir().unwrap();
    let files = [
        (
            "l.obj",
            format!(
                "{}f 1 2 3 4 5 6\n",
                vlines
                    .lines()
                    .map(|l| format!("v {l}\n"))
                    .collect::<String>()
            ),
        ),
        (
            "l.ply",
            format!(
                "ply\nformat ascii 1.0\nelement vertex 6\nproperty float x\nproperty float y\n\
                 property float z\nelement face 1\nproperty list uchar int vertex_indices\n\
                 end_header\n{vlines}6 0 1 2 3 4 5\n"
            ),
        ),
        ("l.off", format!("OFF\n6 1 0\n{vlines}6 0 1 2 3 4 5\n")),
    ];
    for (name, text) in files {
        let path = dir.path().join(name);
        std::fs::write(&path, text).unwrap();
        let m = load_mesh(&path).unwrap_or_else(|e| panic!("{e}"));
        assert_eq!(m.num_triangles(), 4, "{name}");
        // Areas in the (x, y) projection, wound as the face (counter-clockwise).
        let mut area = 0.0;
        let tris: Vec<[Vec3; 3]> = (0..4).map(|i| m.triangle(i)).collect();
        for [a, b, c] in &tris {
            let twice = (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
            assert!(twice > 0.0, "{name}: a triangle wound against the face");
            area += twice / 2.0;
        }
        assert!((area - 3.0).abs() < 1e-5, "{name}: area {area}");
        for k in 0..100 {
            let q = [1.05 + 0.09 * (k % 10) as f32, 1.05 + 0.09 * (k / 10) as f32];
            let covered = tris.iter().any(|[a, b, c]| {
                let side =
                    |p: &Vec3, r: &Vec3| (r.x - p.x) * (q[1] - p.y) - (r.y - p.y) * (q[0] - p.x);
                side(a, b) >= 0.0 && side(b, c) >= 0.0 && side(c, a) >= 0.0
            });
            assert!(!covered, "{name}: the notch at {q:?} is covered");
        }
    }
}
