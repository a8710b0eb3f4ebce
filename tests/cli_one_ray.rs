//! `raykit trace --one-ray`: each ray through the per-ray API
//! (`Accel::intersect` / `occluded`). On a real scanned mesh (the Stanford
//! dragon at quarter resolution) and the three standard ray sets, its
//! answers are the batch path's (same hit or miss, the same distance; a
//! different triangle only at the same distance, on a shared edge), and a
//! sample of them matches brute force (`--verify`).

use std::path::{Path, PathBuf};

#[path = "support/cli.rs"]
mod cli;
use cli::{data, raykit, s, text};

fn dragon() -> PathBuf {
    data("meshes/dragon_vrip_res4.ply.gz")
}

/// `raykit trace` over `rays` into `out`, with `extra` arguments; returns
/// the JSON statistics line.
fn trace(mesh: &Path, rays: &Path, out: &Path, extra: &[&str]) -> serde_json::Value {
    let mut args = vec![
        "trace",
        "--mesh",
        s(mesh),
        "--rays",
        s(rays),
        "--out",
        s(out),
        "--threads",
        "2",
    ];
    args.extend_from_slice(extra);
    let o = raykit(&args);
    let err = text(&o.stderr);
    assert!(o.status.success(), "{args:?}: {err}");
    serde_json::from_str(err.lines().next().expect("a JSON line")).expect("JSON statistics")
}

#[test]
fn one_ray_answers_are_the_batch_answers_and_brute_force_agrees() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dragon();
    for kind in ["primary", "shadow", "incoherent"] {
        let rays = dir.path().join(format!("{kind}.rays"));
        let o = raykit(&[
            "rays",
            "--mesh",
            s(&mesh),
            "--kind",
            kind,
            "--size",
            "96",
            "--out",
            s(&rays),
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let occlusion: &[&str] = if kind == "shadow" {
            &["--occlusion"]
        } else {
            &[]
        };
        let batch = dir.path().join(format!("{kind}.batch"));
        let stats = trace(&mesh, &rays, &batch, occlusion);
        assert_eq!(stats["api"], "batch", "{stats}");
        let one = dir.path().join(format!("{kind}.one"));
        let mut extra = occlusion.to_vec();
        extra.extend(["--one-ray", "--verify", "1500"]);
        let stats = trace(&mesh, &rays, &one, &extra);
        assert_eq!(stats["api"], "one-ray", "{stats}");
        if kind == "shadow" {
            let a = raykit_io::read_occlusion(&batch).unwrap();
            let b = raykit_io::read_occlusion(&one).unwrap();
            assert_eq!(a.len(), b.len());
            let differ = a.iter().zip(&b).filter(|(x, y)| x != y).count();
            assert_eq!(
                differ,
                0,
                "{differ} of {} occlusion answers differ",
                a.len()
            );
            assert!(a.iter().any(|&x| x) && a.iter().any(|&x| !x), "{kind}");
        } else {
            let a = raykit_io::read_hits(&batch).unwrap();
            let b = raykit_io::read_hits(&one).unwrap();
            assert_eq!(a.len(), b.len());
            assert!(a.iter().filter(|h| h.is_some()).count() > a.len() / 10);
            for (i, (x, y)) in a.iter().zip(&b).enumerate() {
                match (x, y) {
                    (None, None) => {}
                    // The same distance; the triangle may differ only
                    // at a tie, two triangles met at that distance.
                    (Some(x), Some(y)) => assert!(
                        (x.t - y.t).abs() <= 1e-6 * x.t,
                        "{kind} ray {i}: batch {x:?}, one ray {y:?}"
                    ),
                    _ => panic!("{kind} ray {i}: batch {x:?}, one ray {y:?}"),
                }
            }
        }
    }
}

#[test]
fn one_ray_is_refused_on_the_gpu_and_for_instanced_scenes() {
    let dir = tempfile::tempdir().unwrap();
    let mesh = dragon();
    let rays = dir.path().join("r.rays");
    let o = raykit(&["rays", "--mesh", s(&mesh), "--size", "8", "--out", s(&rays)]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let out = dir.path().join("h.bin");
    for extra in [&["--backend", "gpu"][..], &["--instanced"][..]] {
        let mut args = vec![
            "trace",
            "--mesh",
            s(&mesh),
            "--rays",
            s(&rays),
            "--out",
            s(&out),
            "--one-ray",
        ];
        args.extend_from_slice(extra);
        let o = raykit(&args);
        assert!(!o.status.success(), "{extra:?}");
        assert!(text(&o.stderr).contains("--one-ray"), "{}", text(&o.stderr));
        assert!(!out.exists(), "{extra:?}: no output on refusal");
    }
}
