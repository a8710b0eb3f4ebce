//! `raykit cull` as a user runs it, on a synthetic assembly with a known
//! answer (a closed box with parts inside: only the box can be seen): the
//! output file is read back and compared with the box by position, the
//! report with the counts; bad arguments give a clear error.

use raykit_core::{Aabb, Part, TriangleMesh, Vec3};
use raykit_cull::synthetic::{assembly, closed_box, icosphere};
use std::collections::BTreeSet;

#[path = "support/cli.rs"]
mod cli;
use cli::{raykit, s, text};

type Corners = [[u32; 3]; 3];

/// Every triangle's corners as exact f32 bit patterns (-0 folded into +0).
fn triangle_set(m: &TriangleMesh) -> BTreeSet<Corners> {
    (0..m.num_triangles())
        .map(|t| {
            m.triangle(t)
                .map(|p| p.to_array().map(|x| (x + 0.0).to_bits()))
        })
        .collect()
}

const SPHERES: usize = 8;
const SPHERE_TRIS: usize = 80;
const BOX_TRIS: usize = 6 * 3 * 3 * 2;

/// The box (3 × 3 squares per face, part "shell") and a 2 × 2 × 2 lattice of
/// icospheres inside it (parts "ball0".."ball7"), with the box alone.
fn boxed_balls() -> (TriangleMesh, TriangleMesh) {
    let shell = closed_box(&Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0)), 3);
    let mut pieces = vec![shell.clone()];
    for k in 0..SPHERES {
        let c = Vec3::new(
            0.5 + (k & 1) as f32,
            0.3 + 0.4 * ((k >> 1) & 1) as f32,
            0.3 + 0.4 * ((k >> 2) & 1) as f32,
        );
        pieces.push(icosphere(c, 0.15, 1));
    }
    let mut m = assembly(pieces);
    m.parts = std::iter::once("shell".to_string())
        .chain((0..SPHERES).map(|k| format!("ball{k}")))
        .map(|name| Part { name, node: None })
        .collect();
    assert_eq!(shell.num_triangles(), BOX_TRIS);
    assert_eq!(m.num_triangles(), BOX_TRIS + SPHERES * SPHERE_TRIS);
    m.validate().unwrap();
    (m, shell)
}

#[test]
fn a_box_full_of_parts_comes_out_as_the_box_with_a_matching_report() {
    let dir = tempfile::tempdir().unwrap();
    let (model, shell) = boxed_balls();
    let input = dir.path().join("assembly.glb");
    raykit_io::save_mesh(&input, &model).unwrap();
    let loaded = raykit_io::load_mesh(&input).unwrap();
    assert_eq!(loaded.parts.len(), 1 + SPHERES);
    let want = triangle_set(&shell);
    for (by, out_name) in [("triangle", "out.glb"), ("part", "out.gltf")] {
        let output = dir.path().join(out_name);
        let report = dir.path().join(format!("{by}.json"));
        let o = raykit(&[
            "cull",
            s(&input),
            s(&output),
            "--mode",
            "conservative",
            "--resolution",
            "64",
            "--by",
            by,
            "--report",
            s(&report),
        ]);
        assert!(o.status.success(), "{by}: {}", text(&o.stderr));
        let out = text(&o.stdout);
        let total = BOX_TRIS + SPHERES * SPHERE_TRIS;
        assert!(
            out.contains(&format!("triangles: {total} -> {BOX_TRIS}")),
            "{out}"
        );
        assert!(out.contains("parts: 9 -> 1 (8 removed"), "{out}");
        assert!(out.contains("distance field"), "{out}");

        let culled = raykit_io::load_mesh(&output).unwrap();
        assert_eq!(culled.num_triangles(), BOX_TRIS, "{by}");
        assert_eq!(triangle_set(&culled), want, "{by}: the box's triangles");
        let names: Vec<&str> = culled.parts.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, ["shell"], "{by}: parts");

        let r: serde_json::Value =
            serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
        assert_eq!(r["by"], by, "{r}");
        assert_eq!(r["mode"], "conservative", "{r}");
        assert_eq!(r["resolution"], 64, "{r}");
        assert_eq!(r["triangles_in"], total, "{r}");
        assert_eq!(r["triangles_out"], BOX_TRIS, "{r}");
        assert_eq!(r["triangles_removed"], SPHERES * SPHERE_TRIS, "{r}");
        assert_eq!(r["parts_in"], 1 + SPHERES, "{r}");
        assert_eq!(r["parts_out"], 1, "{r}");
        assert_eq!(r["parts_removed"], SPHERES, "{r}");
        let st = &r["stats"];
        assert_eq!(st["triangles"], total, "{r}");
        assert_eq!(st["triangles_removed"], SPHERES * SPHERE_TRIS, "{r}");
        assert_eq!(st["parts"], 1 + SPHERES, "{r}");
        assert_eq!(st["parts_removed"], SPHERES, "{r}");
        assert_eq!(st["grid"][0], 64, "{r}");
        for key in ["load_s", "cull_s", "save_s"] {
            assert!(r[key].is_number(), "{key} missing: {r}");
        }
        for key in [
            "distance_field_seconds",
            "propagation_seconds",
            "outside_points",
        ] {
            assert!(st[key].is_number(), "{key} missing: {r}");
        }
    }
}

#[test]
fn the_rays_mode_keeps_the_box_and_reports_its_search() {
    let dir = tempfile::tempdir().unwrap();
    let (model, shell) = boxed_balls();
    let input = dir.path().join("assembly.glb");
    raykit_io::save_mesh(&input, &model).unwrap();
    let output = dir.path().join("out.glb");
    let o = raykit(&[
        "cull",
        s(&input),
        s(&output),
        "--mode",
        "rays",
        "--by",
        "part",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["mode"], "rays", "{r}");
    assert_eq!(r["triangles_out"], BOX_TRIS, "{r}");
    assert_eq!(r["parts_removed"], SPHERES, "{r}");
    let x = &r["stats"]["rays"];
    assert_eq!(x["converged"], true, "{r}");
    let k = x["rays_per_removed"].as_u64().unwrap();
    assert!(k > 0, "{r}");
    let f = x["escape_fraction_95"].as_f64().unwrap();
    // About 3 / k: the rule of three.
    let three = f * k as f64;
    assert!(three > 2.9 && three < 3.1, "{r}");
    let culled = raykit_io::load_mesh(&output).unwrap();
    assert_eq!(triangle_set(&culled), triangle_set(&shell));
    let names: Vec<&str> = culled.parts.iter().map(|p| p.name.as_str()).collect();
    assert_eq!(names, ["shell"]);
}

#[test]
fn json_on_stdout_and_paper_mode_on_an_obj() {
    let dir = tempfile::tempdir().unwrap();
    let (model, shell) = boxed_balls();
    let input = dir.path().join("assembly.obj");
    raykit_io::save_mesh(&input, &model).unwrap();
    let output = dir.path().join("shell.ply");
    let o = raykit(&[
        "cull",
        s(&input),
        s(&output),
        "--resolution",
        "48",
        "--paper",
        "--json",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let r: serde_json::Value = serde_json::from_slice(&o.stdout).unwrap();
    assert_eq!(r["mode"], "paper", "{r}");
    assert_eq!(r["triangles_out"], BOX_TRIS, "{r}");
    assert_eq!(r["stats"]["kept_by_contact"], 0, "{r}");
    let culled = raykit_io::load_mesh(&output).unwrap();
    assert_eq!(triangle_set(&culled), triangle_set(&shell));
}

#[test]
fn bad_arguments_fail_with_a_clear_message() {
    let dir = tempfile::tempdir().unwrap();
    let (model, _) = boxed_balls();
    let input = dir.path().join("assembly.glb");
    raykit_io::save_mesh(&input, &model).unwrap();
    let bytes = std::fs::read(&input).unwrap();
    let same = dir.path().join(".").join("assembly.glb");
    let out = dir.path().join("out.glb");
    let missing = dir.path().join("missing.glb");
    let report = dir.path().join("r.json");
    let truth = dir.path().join("t.json");
    let no_folder = dir.path().join("none").join("t.json");
    std::fs::write(&truth, "{}").unwrap();
    for (args, want) in [
        (vec![s(&input), s(&same)], "also an input"),
        (vec![s(&input), "out.xyz"], "unknown mesh file extension"),
        (vec![s(&missing), s(&out)], "missing.glb"),
        (
            vec![s(&input), s(&out), "--report", s(&input)],
            "also an input",
        ),
        (vec![s(&input), s(&out), "--resolution", "2"], "resolution"),
        (vec![s(&input), s(&out), "--by", "node"], "--by"),
        (
            vec![s(&input), s(&out), "--paper", "--confirm"],
            "--confirm",
        ),
        (vec![s(&input), s(&out), "--eval-rounds", "3"], "--evaluate"),
        (
            vec![s(&input), s(&out), "--evaluate", "--eval-rounds", "33"],
            "--eval-rounds",
        ),
        (
            vec![
                s(&input),
                s(&out),
                "--evaluate",
                "--eval-min-opening",
                "inf",
            ],
            "outside 0..=0.1",
        ),
    ] {
        let o = raykit(&[&["cull"], &args[..]].concat());
        assert!(!o.status.success(), "{args:?}");
        let err = text(&o.stderr);
        assert!(err.contains(want), "{args:?}: {err}");
        assert!(!err.contains("panicked"), "{err}");
    }
    // The labels' files: --save-truth is checked like every output, before
    // any work; saved labels that cannot be used fail before the output is
    // written.
    for (extra, want) in [
        (vec!["--save-truth", s(&input)], "also an input"),
        (vec!["--save-truth", s(&out)], "name the same file"),
        (
            vec!["--save-truth", s(&report), "--report", s(&report)],
            "name the same file",
        ),
        (vec!["--save-truth", s(&no_folder)], "does not exist"),
        (
            vec!["--truth", s(&truth)],
            "not a ground truth saved by --save-truth",
        ),
        (vec!["--truth", s(&missing)], "missing.glb"),
        (
            vec!["--truth", s(&truth), "--report", s(&truth)],
            "also an input",
        ),
    ] {
        let o = raykit(&[&["cull", s(&input), s(&out), "--evaluate"], &extra[..]].concat());
        assert!(!o.status.success(), "{extra:?}");
        let err = text(&o.stderr);
        assert!(err.contains(want), "{extra:?}: {err}");
    }
    assert!(
        !out.exists() && !report.exists(),
        "no output is written on errors"
    );
    assert_eq!(
        std::fs::read(&input).unwrap(),
        bytes,
        "the input is untouched"
    );
    let o = raykit(&["cull", "--help"]);
    let help = text(&o.stdout);
    assert!(
        help.contains("--resolution") && help.contains("--mode") && help.contains("Grid modes")
    );
}

#[test]
fn evaluate_reports_the_ground_truth_and_exits_2_on_false_removals() {
    let dir = tempfile::tempdir().unwrap();
    let (model, _) = boxed_balls();
    let input = dir.path().join("assembly.ply");
    raykit_io::save_mesh(&input, &model).unwrap();
    let output = dir.path().join("out.ply");
    let report = dir.path().join("r.json");
    let o = raykit(&[
        "cull",
        s(&input),
        s(&output),
        "--resolution",
        "32",
        "--evaluate",
        "--eval-rounds",
        "2",
        "--report",
        s(&report),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).contains("false removals 0"),
        "{}",
        text(&o.stdout)
    );
    let r: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&report).unwrap()).unwrap();
    // The geometry's answer: the box is seen, the balls are not.
    let g = &r["ground_truth"];
    assert_eq!(g["visible_count"], BOX_TRIS, "{g}");
    assert!(g["rounds"].as_u64().unwrap() <= 2);
    let e = &r["evaluation"];
    assert_eq!(e["truly_visible"], BOX_TRIS, "{e}");
    assert_eq!(e["truly_hidden"], SPHERES * SPHERE_TRIS, "{e}");
    assert_eq!(e["false_removals"], 0, "{e}");
    assert_eq!(e["missed_removals"], 0, "{e}");

    // Take the lid off: the balls are in plain view, and Min (2008)'s rule
    // on a coarse grid misses some of their small triangles.
    let open = raykit_cull::synthetic::box_surface(
        &Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0)),
        3,
        |axis, max_side, _, _| axis == 2 && max_side,
    );
    let mut pieces = vec![open];
    pieces.extend(model_balls(&model));
    let lidless = assembly(pieces);
    let input = dir.path().join("lidless.ply");
    raykit_io::save_mesh(&input, &lidless).unwrap();
    let o = raykit(&[
        "cull",
        s(&input),
        s(&output),
        "--paper",
        "--resolution",
        "6",
        "--evaluate",
        "--eval-rounds",
        "2",
        "--json",
    ]);
    assert_eq!(o.status.code(), Some(3), "{}", text(&o.stderr));
    let r: serde_json::Value = serde_json::from_str(&text(&o.stdout)).unwrap();
    let e = &r["evaluation"];
    assert!(e["false_removals"].as_u64().unwrap() > 0, "{e}");
    assert!(e["false_removal_ids"].as_array().unwrap().len() <= 20);
}

/// The balls of [`boxed_balls`]' model, one mesh each.
fn model_balls(model: &TriangleMesh) -> Vec<TriangleMesh> {
    (1..=SPHERES as u32)
        .map(|p| {
            let tris: Vec<[u32; 3]> = (0..model.num_triangles())
                .filter(|&t| model.part_of(t) == p)
                .map(|t| model.indices[t])
                .collect();
            TriangleMesh::new(model.positions.clone(), tris)
        })
        .collect()
}

/// Labels saved for one model are refused for another with as many
/// triangles (the same model moved), naming the field; for the model they
/// were saved for they give the evaluation a fresh one gives.
#[test]
fn saved_labels_are_refused_for_another_mesh_with_as_many_triangles() {
    let dir = tempfile::tempdir().unwrap();
    let (model, _) = boxed_balls();
    let input = dir.path().join("assembly.ply");
    raykit_io::save_mesh(&input, &model).unwrap();
    let mut moved = model.clone();
    for p in &mut moved.positions {
        *p += Vec3::new(0.25, 0.0, 0.0);
    }
    let other = dir.path().join("moved.ply");
    raykit_io::save_mesh(&other, &moved).unwrap();
    let truth = dir.path().join("t.json");
    let output = dir.path().join("out.ply");
    let run = |mesh: &std::path::Path, extra: &[&str]| {
        let args = [
            &["cull", s(mesh), s(&output), "--resolution", "32"][..],
            &["--evaluate", "--eval-rounds", "2", "--json"],
            extra,
        ]
        .concat();
        raykit(&args)
    };
    let fresh = run(&input, &["--save-truth", s(&truth)]);
    assert!(fresh.status.success(), "{}", text(&fresh.stderr));
    let again = run(&input, &["--truth", s(&truth)]);
    assert!(again.status.success(), "{}", text(&again.stderr));
    let evaluation = |o: &std::process::Output| {
        let r: serde_json::Value = serde_json::from_str(&text(&o.stdout)).unwrap();
        r["evaluation"].clone()
    };
    assert_eq!(evaluation(&again), evaluation(&fresh));
    std::fs::remove_file(&output).unwrap();
    let refused = run(&other, &["--truth", s(&truth)]);
    assert!(!refused.status.success());
    let err = text(&refused.stderr);
    assert!(
        err.contains("t.json") && err.contains("mesh_digest") && err.contains("moved.ply"),
        "{err}"
    );
    assert!(!output.exists(), "no output is written on errors");
}

/// Each triangle of `got` lies within `tol` of a distinct triangle of
/// `want` (corner by corner), and the two have as many.
fn same_triangles(got: &TriangleMesh, want: &TriangleMesh, tol: f32, what: &str) {
    assert_eq!(got.num_triangles(), want.num_triangles(), "{what}");
    let mut used = vec![false; want.num_triangles()];
    for t in 0..got.num_triangles() {
        let g = got.triangle(t);
        let hit = (0..want.num_triangles()).find(|&u| {
            !used[u]
                && want
                    .triangle(u)
                    .iter()
                    .zip(&g)
                    .all(|(a, b)| (*a - *b).abs().max_element() <= tol)
        });
        match hit {
            Some(u) => used[u] = true,
            None => panic!("{what}: triangle {t} {g:?} is not in the expected output"),
        }
    }
}

/// A box (one mesh) with a ball mesh placed by eleven nodes: eight inside
/// the box, one through its wall and two outside. The culled glTF keeps the
/// instancing (the outside balls share one mesh; the ball through the wall
/// keeps part of it, a mesh of its own, or, with `--shared-meshes`, all of
/// it and the shared mesh), and holds the triangles that the flattened
/// writer, given the same cull, writes to an OBJ file.
#[test]
fn an_instanced_assembly_keeps_its_instancing() {
    use raykit_core::glam::{DAffine3, DVec3};
    use raykit_io::{load_gltf_instances, write_gltf_placed, PlacedMesh};

    let dir = tempfile::tempdir().unwrap();
    let mut shell = closed_box(&Aabb::new(Vec3::ZERO, Vec3::new(2.0, 1.0, 1.0)), 3);
    shell.parts = vec![Part {
        name: "shell".into(),
        node: None,
    }];
    let ball = icosphere(Vec3::ZERO, 0.15, 1);
    let at = |x: f64, y: f64, z: f64, name: String| PlacedMesh {
        mesh: 1,
        to_world: DAffine3::from_translation(DVec3::new(x, y, z)),
        name,
    };
    let mut nodes = vec![PlacedMesh {
        mesh: 0,
        to_world: DAffine3::IDENTITY,
        name: "shell".into(),
    }];
    for k in 0..SPHERES {
        nodes.push(at(
            0.5 + (k & 1) as f64,
            0.3 + 0.4 * ((k >> 1) & 1) as f64,
            0.3 + 0.4 * ((k >> 2) & 1) as f64,
            format!("inside{k}"),
        ));
    }
    nodes.push(at(2.0, 0.5, 0.5, "wall".into()));
    nodes.push(at(3.0, 0.5, 0.5, "out0".into()));
    nodes.push(at(-1.0, 0.5, 0.5, "out1".into()));
    let input = dir.path().join("instanced.glb");
    raykit_io::write_atomic(&input, |w| {
        write_gltf_placed(w, &[shell, ball.clone()], &nodes, None, &[], true)
    })
    .unwrap();

    for (flags, meshes_out) in [(&[][..], 3), (&["--shared-meshes"][..], 2)] {
        let what = format!("{flags:?}");
        let glb = dir.path().join("out.glb");
        let obj = dir.path().join("out.obj");
        let mut args = vec!["cull", s(&input), s(&glb), "--resolution", "64"];
        args.extend(flags);
        let o = raykit(&args);
        assert!(o.status.success(), "{what}: {}", text(&o.stderr));
        let out = text(&o.stdout);
        assert!(
            out.contains(&format!(
                "instancing: 12 nodes placing 2 meshes -> 4 nodes placing {meshes_out} meshes"
            )),
            "{what}: {out}"
        );

        let inst = load_gltf_instances(&glb).unwrap();
        assert_eq!(inst.geometries.len(), meshes_out, "{what}");
        let names: Vec<&str> = inst.instances.iter().map(|i| i.name.as_str()).collect();
        assert_eq!(names, ["shell", "wall", "out0", "out1"], "{what}");
        let [_, wall, out0, out1] = &inst.instances[..] else {
            unreachable!()
        };
        assert_eq!(
            out0.geometry, out1.geometry,
            "{what}: the outside balls share a mesh"
        );
        for (i, n) in inst
            .instances
            .iter()
            .zip([&nodes[0], &nodes[9], &nodes[10], &nodes[11]])
        {
            assert_eq!(i.to_world_f64, n.to_world, "{what}: {}", i.name);
        }
        let whole = inst.geometries[out0.geometry as usize].num_triangles();
        assert_eq!(
            whole,
            ball.num_triangles(),
            "{what}: the outside balls are whole"
        );
        let wall_kept = inst.geometries[wall.geometry as usize].num_triangles();
        if flags.is_empty() {
            assert_ne!(wall.geometry, out0.geometry, "{what}");
            assert!(
                0 < wall_kept && wall_kept < whole,
                "{what}: the ball through the wall keeps {wall_kept} of {whole}"
            );
        } else {
            assert_eq!(wall.geometry, out0.geometry, "{what}: one ball mesh");
        }

        // The same cull through the flattened writer (shared meshes are a
        // glTF output's: refused for an OBJ), and with them the ball
        // through the wall made whole.
        let mut args = vec!["cull", s(&input), s(&obj), "--resolution", "64"];
        let o = raykit(&[args.as_slice(), flags].concat());
        if !flags.is_empty() {
            assert!(!o.status.success(), "{what}");
            let err = text(&o.stderr);
            assert!(
                err.contains(
                    "--shared-meshes needs a glTF or GLB input and a .gltf or .glb output"
                ),
                "{err}"
            );
            args.truncate(5);
            let o = raykit(&args);
            assert!(o.status.success(), "{what}: {}", text(&o.stderr));
        } else {
            assert!(o.status.success(), "{what}: {}", text(&o.stderr));
        }
        let flat = raykit_io::load_mesh(&obj).unwrap();
        let want = if flags.is_empty() {
            flat
        } else {
            let wall = flat.parts.iter().position(|p| p.name == "wall").unwrap() as u32;
            let keep: Vec<bool> = (0..flat.num_triangles())
                .map(|t| flat.part_of(t) != wall)
                .collect();
            let mut w = flat.retain_triangles(&keep);
            w.append(&icosphere(Vec3::new(2.0, 0.5, 0.5), 0.15, 1));
            w
        };
        let got = raykit_io::load_mesh(&glb).unwrap();
        same_triangles(&got, &want, 1e-6, &what);
    }
}

/// The 2CylinderEngine (67 nodes placing 29 meshes) culled by parts keeps
/// every mesh shared as in the file, and its triangles are those the
/// flattened writer puts in an OBJ file for the same cull.
#[test]
fn the_engine_culled_by_parts_keeps_its_29_meshes() {
    let dir = tempfile::tempdir().unwrap();
    let input = cli::data("meshes/2CylinderEngine.glb");
    let glb = dir.path().join("engine.glb");
    let obj = dir.path().join("engine.obj");
    for out in [&glb, &obj] {
        let o = raykit(&["cull", s(&input), s(out), "--by", "part"]);
        assert!(o.status.success(), "{}", text(&o.stderr));
    }
    let before = raykit_io::load_gltf_instances(&input).unwrap();
    let after = raykit_io::load_gltf_instances(&glb).unwrap();
    assert_eq!((before.instances.len(), before.geometries.len()), (67, 29));
    // Every part has a visible triangle: all 67 nodes stay, in order, each
    // placing its mesh whole with its transform, and the meshes the file
    // shared are shared still.
    assert_eq!(after.instances.len(), 67);
    assert_eq!(after.geometries.len(), 29);
    for (i, b) in after.instances.iter().zip(&before.instances) {
        assert_eq!(i.name, b.name);
        assert!(
            i.to_world_f64.abs_diff_eq(b.to_world_f64, 1e-9),
            "{}: {:?} against {:?}",
            i.name,
            i.to_world_f64,
            b.to_world_f64
        );
        assert_eq!(
            after.geometries[i.geometry as usize].indices,
            before.geometries[b.geometry as usize].indices,
            "{}",
            i.name
        );
    }
    for (a, x) in after.instances.iter().zip(&before.instances) {
        for (b, y) in after.instances.iter().zip(&before.instances) {
            assert_eq!(
                a.geometry == b.geometry,
                x.geometry == y.geometry,
                "{} and {}",
                a.name,
                b.name
            );
        }
    }
    let flat = raykit_io::load_mesh(&obj).unwrap();
    let got = raykit_io::load_mesh(&glb).unwrap();
    assert_eq!(got.num_triangles(), flat.num_triangles());
    let sorted = |m: &TriangleMesh| {
        let mut v: Vec<[i64; 9]> = (0..m.num_triangles())
            .map(|t| {
                let c = m.triangle(t);
                std::array::from_fn(|k| (c[k / 3][k % 3] * 1e4).round() as i64)
            })
            .collect();
        v.sort_unstable();
        v
    };
    let (a, b) = (sorted(&got), sorted(&flat));
    let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
    // Rounding to 0.1 mm may split a corner the two writers round apart.
    assert!(
        differ * 1000 <= a.len(),
        "{differ} of {} triangles differ",
        a.len()
    );
}
