//! `raykit experiment split-heuristic`: Kim's (2013) sweep of the split-plane
//! weight H = 0..20 (its Figures 5 to 8) with the SAH tree as a reference.

use super::{shared_mesh, write_csv, write_text};
use crate::args::build_args::BuildArgs;
use crate::args::ranges::{self, image_side, in_range};
use crate::args::scene_arg;
use crate::measure::{median_min_max, pool, timed};
use crate::plot::{write_svg, LineChart, Series};
use anyhow::Result;
use clap::Args;
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::accel::kdtree::{
    build_game, build_tree, cut_mesh, KdBuildNode, KdOptions, KdSplit,
};
use raykit_core::accel::{build_accel, kd_accel_from_tree, AccelKind, BuildOptions};
use raykit_core::query::{parts_in_frustum, parts_overlapping_brute, Frustum};
use raykit_core::rng::Pcg32;
use raykit_core::tjunction::{eliminate, Method, TJunctionOptions};
use raykit_core::tri::TestKind;
use raykit_core::{raysets, Aabb, Camera, Hit, Ray, TriangleMesh};
use raykit_render::raster::primary_visibility;
use serde::Serialize;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `raykit experiment split-heuristic`.
#[derive(Args)]
#[command(
    after_help = "Default mesh: the shared bunny (3,674 triangles; Kim's (2013) game level had 15,382\n\
polygons). A scene of many objects, e.g. --mesh builtin:scatter:triangles=15000, gives\n\
the frustum queries objects to cull. Large CAD models explode under the game heuristic\n\
(the engine: 121k -> 864k triangles at H = 8), so expect minutes per H there.\n\
Writes results.csv, results.md and the SVG figures fig5..fig8 into --out. The naive\n\
T-junction finder runs where its size limit allows."
)]
pub struct SplitHeuristicArgs {
    /// Mesh file or builtin:NAME.
    #[arg(long)]
    mesh: Option<String>,
    /// Image side of the primary ray set (SIZE² rays); 1 to 16384.
    #[arg(long, default_value_t = 256)]
    size: u32,
    /// Random view frustums per query-speed measurement; 1 to 100000.
    #[arg(long, default_value_t = 40)]
    frustums: usize,
    /// Repetitions of every timing (the median is reported); 1 to 1000.
    #[arg(long, default_value_t = 3)]
    reps: usize,
    /// Threads (1 gives the steadiest figures).
    #[arg(long, default_value_t = 1)]
    threads: usize,
    /// Leaf size of the game trees (nodes with at most this many pieces stop).
    #[arg(long, default_value_t = 8)]
    game_leaf: usize,
    /// Output folder.
    #[arg(long, default_value = "experiments/split-heuristic")]
    out: PathBuf,
    #[command(flatten)]
    build: BuildArgs,
}

/// One tree of the sweep.
#[derive(Serialize, Clone)]
struct Row {
    split: String,
    h: Option<u8>,
    /// Pieces cut by split planes over the build (split polygons); the SAH
    /// tree, which cuts nothing, counts its leaf references beyond one per
    /// triangle instead.
    split_polygons: usize,
    /// Original triangles in more than one piece (SAH: listed by more than
    /// one leaf); at most the mesh's triangle count.
    split_triangles: usize,
    cut_mesh_triangles: usize,
    depth: u32,
    leaves: usize,
    build_ms: f64,
    t_junctions: Option<usize>,
    tjunction_fast_ms: Option<f64>,
    tjunction_naive_ms: Option<f64>,
    naive_equals_fast: Option<bool>,
    ray_mrays: f64,
    frustum_queries_per_s: f64,
    /// Frames per second: frustum culling of the parts, then rasterizing the
    /// pieces of the parts kept at [`FRAME_WIDTH`] × [`FRAME_HEIGHT`].
    culled_fps: f64,
    ray_disagreements: usize,
    frustum_disagreements: usize,
}

/// The most random view frustums (`--frustums`): each is drawn once per
/// tree and repetition.
const MAX_FRUSTUMS: usize = 100_000;

/// Size of the frames drawn after frustum culling (16:9, as the frustums).
const FRAME_WIDTH: u32 = 512;
const FRAME_HEIGHT: u32 = 288;

/// Run the experiment.
pub fn run(args: SplitHeuristicArgs) -> Result<ExitCode> {
    image_side("--size", args.size)?;
    let reps = ranges::reps(args.reps)?;
    in_range("--frustums", args.frustums, 1, MAX_FRUSTUMS)?;
    let spec = args
        .mesh
        .clone()
        .unwrap_or_else(|| shared_mesh("bunny_3674.obj"));
    let scene = scene_arg::load(&spec)?;
    let mesh = &scene.mesh;
    let threads = pool(args.threads)?;
    let base = args.build.options();
    let camera = raysets::standard_camera(mesh);
    let rays = raysets::primary(&camera, args.size);
    let reference = build_accel(AccelKind::Bvh2, TestKind::Moller, mesh, &base);
    let mut want = vec![None; rays.len()];
    reference.intersect_batch(&rays, &mut want);
    let (cameras, frustums): (Vec<Camera>, Vec<Frustum>) =
        random_views(&mesh.bounds(), args.frustums, 7)
            .into_iter()
            .unzip();
    let views = Views {
        reference: frustums
            .iter()
            .map(|f| parts_overlapping_brute(mesh, f))
            .collect(),
        frustums,
        cameras,
    };

    eprintln!(
        "{}: {} triangles, {} parts",
        scene.name,
        mesh.num_triangles(),
        mesh.parts.len().max(1)
    );
    let bar = ProgressBar::new(22)
        .with_style(ProgressStyle::with_template("{bar:30} {pos}/{len} {msg}").unwrap());
    let mut rows = Vec::new();
    let splits: Vec<KdSplit> = (0..=20u8)
        .map(KdSplit::Game)
        .chain([KdSplit::Sah])
        .collect();
    for split in splits {
        bar.set_message(split.name());
        let kd = KdOptions {
            split,
            max_leaf_size: args.game_leaf,
            ..base.kd.clone()
        };
        let opts = BuildOptions {
            kd: kd.clone(),
            ..base.clone()
        };
        let row = threads.install(|| sweep_point(mesh, &opts, &rays, &want, &views, reps));
        rows.push(row?);
        bar.inc(1);
    }
    bar.finish_and_clear();
    write_csv(&args.out, "results.csv", &rows)?;
    let md = markdown(&rows, &scene.name, mesh.num_triangles(), &args);
    write_text(&args.out, "results.md", &md)?;
    print!("{md}");
    plots(&rows, &args.out, &scene.name)?;
    eprintln!(
        "wrote {}/results.csv, results.md, fig5..fig8 SVGs",
        args.out.display()
    );
    let bad: usize = rows
        .iter()
        .map(|r| r.ray_disagreements + r.frustum_disagreements)
        .sum();
    Ok(if bad == 0 {
        ExitCode::SUCCESS
    } else {
        ExitCode::FAILURE
    })
}

fn sweep_point(
    mesh: &TriangleMesh,
    opts: &BuildOptions,
    rays: &[Ray],
    want: &[Option<Hit>],
    views: &Views,
    reps: usize,
) -> Result<Row> {
    let (frustums, cameras) = (&views.frustums, &views.cameras);
    let mut build_times = Vec::new();
    let mut built = None;
    for _ in 0..reps {
        let (b, t) = timed(|| match opts.kd.split {
            KdSplit::Game(h) => {
                let (root, cell, game) = build_game(mesh, h, &opts.kd);
                (root, cell, Some(game))
            }
            _ => {
                let (root, cell) = build_tree(mesh, &opts.kd);
                (root, cell, None)
            }
        });
        build_times.push(t);
        built = Some(b);
    }
    let (root, cell, game) = built.expect("at least one repetition");
    let build_s = median_min_max(&build_times).0;
    let accel = kd_accel_from_tree(
        AccelKind::KdStack,
        TestKind::Moller,
        mesh,
        &root,
        &cell,
        opts,
        build_s,
    )
    .expect("kd-stack is a kd-tree traversal");
    let stats = accel.stats();
    let h = match opts.kd.split {
        KdSplit::Game(h) => Some(h),
        _ => None,
    };

    // T-junction elimination on the cut mesh.
    // The SAH tree cuts nothing: a triangle crossing a split plane is listed
    // by the leaves on both sides instead (see `LeafSharing`).
    let sharing = LeafSharing::of(&root, mesh.num_triangles());
    let (mut split_polygons, mut split_triangles) =
        (sharing.extra_references, sharing.shared_triangles);
    let mut cut_tris = 0;
    let (mut tj, mut fast_ms, mut naive_ms, mut same) = (None, None, None, None);
    // What a frame draws: the pieces of the cut mesh (the whole triangles
    // for the SAH tree), grouped by the part of their source triangle.
    let mut drawn = TriangleMesh::new(mesh.positions.clone(), Vec::new());
    let mut part_pieces: Vec<Vec<[u32; 3]>> = vec![Vec::new(); mesh.parts.len().max(1)];
    if game.is_none() {
        for (t, tri) in mesh.indices.iter().enumerate() {
            part_pieces[mesh.part_of(t) as usize].push(*tri);
        }
    }
    if let Some(game) = &game {
        let cut = cut_mesh(mesh, game);
        drawn.positions = cut.mesh.positions.clone();
        for (piece, &source) in cut.source.iter().enumerate() {
            part_pieces[mesh.part_of(source as usize) as usize].push(cut.mesh.indices[piece]);
        }
        split_polygons = game.cuts;
        split_triangles = cut.split_triangles;
        cut_tris = cut.mesh.num_triangles();
        let topts = TJunctionOptions::default();
        let mut times = Vec::new();
        let mut fast = None;
        for _ in 0..reps {
            let (r, t) = timed(|| eliminate(&cut.mesh, Method::Fast, &topts));
            times.push(t);
            fast = Some(r?);
        }
        let (fast_mesh, report) = fast.expect("at least one repetition");
        tj = Some(report.t_junctions);
        fast_ms = Some(median_min_max(&times).0 * 1e3);
        let (naive, t) = timed(|| eliminate(&cut.mesh, Method::Naive, &topts));
        if let Ok((naive_mesh, _)) = naive {
            naive_ms = Some(t * 1e3);
            same = Some(naive_mesh.indices == fast_mesh.indices);
        }
    }

    // Ray casting and frustum queries.
    let mut hits = vec![None; rays.len()];
    let mut ray_speed = Vec::new();
    for _ in 0..reps {
        let (_, t) = timed(|| accel.intersect_batch(rays, &mut hits));
        ray_speed.push(rays.len() as f64 / t / 1e6);
    }
    let ray_disagreements = raykit_core::verify::compare_hits(want, &hits).disagreements();
    let mut q_speed = Vec::new();
    let mut frustum_disagreements = 0;
    for rep in 0..reps {
        let (found, t) = timed(|| {
            frustums
                .iter()
                .map(|f| parts_in_frustum(accel.as_ref(), mesh, f))
                .collect::<Vec<_>>()
        });
        q_speed.push(frustums.len() as f64 / t);
        if rep == 0 {
            frustum_disagreements = found
                .iter()
                .zip(&views.reference)
                .filter(|(a, b)| a != b)
                .count();
        }
    }
    // Frames: cull the parts against each view's frustum, then draw the
    // pieces of the parts kept (the CPU rasterizer's visibility buffer).
    let mut fps = Vec::new();
    for _ in 0..reps {
        let (_, t) = timed(|| {
            for (f, camera) in frustums.iter().zip(cameras) {
                drawn.indices.clear();
                for part in parts_in_frustum(accel.as_ref(), mesh, f) {
                    drawn.indices.extend_from_slice(&part_pieces[part as usize]);
                }
                std::hint::black_box(primary_visibility(
                    &drawn,
                    TestKind::Moller,
                    camera,
                    FRAME_WIDTH,
                    FRAME_HEIGHT,
                ));
            }
        });
        fps.push(frustums.len() as f64 / t);
    }
    Ok(Row {
        split: opts.kd.split.name(),
        h,
        split_polygons,
        split_triangles,
        cut_mesh_triangles: cut_tris,
        depth: stats.depth,
        leaves: stats.leaves,
        build_ms: build_s * 1e3,
        t_junctions: tj,
        tjunction_fast_ms: fast_ms,
        tjunction_naive_ms: naive_ms,
        naive_equals_fast: same,
        ray_mrays: median_min_max(&ray_speed).0,
        frustum_queries_per_s: median_min_max(&q_speed).0,
        culled_fps: median_min_max(&fps).0,
        ray_disagreements,
        frustum_disagreements,
    })
}

/// How the leaves of a kd-tree share the mesh's triangles: the SAH tree's
/// counterpart of the game tree's cuts. A triangle that straddles a split
/// plane is listed by a leaf on each side, so each extra listing stands for
/// one cut piece.
#[derive(Debug, PartialEq, Eq)]
struct LeafSharing {
    /// Leaf references beyond one per listed triangle.
    extra_references: usize,
    /// Triangles listed by more than one leaf.
    shared_triangles: usize,
}

impl LeafSharing {
    /// Count, per triangle of a mesh of `triangles`, the leaves of `root`
    /// that list it.
    fn of(root: &KdBuildNode, triangles: usize) -> Self {
        let mut listed = vec![0usize; triangles];
        let mut stack = vec![root];
        while let Some(node) = stack.pop() {
            match node {
                KdBuildNode::Leaf(tris) => {
                    for &t in tris {
                        listed[t as usize] += 1;
                    }
                }
                KdBuildNode::Inner { children, .. } => stack.extend(children.iter()),
            }
        }
        Self::from_counts(&listed)
    }

    /// The figures from each triangle's number of listing leaves.
    fn from_counts(listed: &[usize]) -> Self {
        LeafSharing {
            extra_references: listed.iter().map(|&c| c.saturating_sub(1)).sum(),
            shared_triangles: listed.iter().filter(|&&c| c > 1).count(),
        }
    }
}

/// The views of the frustum measurements: each camera, its frustum, and
/// the parts a brute force finds in it.
struct Views {
    cameras: Vec<Camera>,
    frustums: Vec<Frustum>,
    reference: Vec<Vec<u32>>,
}

/// View frustums of random cameras outside the mesh looking at random
/// points of its box (60° field of view, aspect 16:9).
fn random_views(bounds: &Aabb, n: usize, seed: u64) -> Vec<(Camera, Frustum)> {
    let mut rng = Pcg32::new(seed);
    let r = bounds.diagonal() * 0.5;
    (0..n)
        .map(|_| {
            let target = rng.in_box(bounds.min, bounds.max);
            let eye = bounds.center() + rng.unit_vector() * r * (0.6 + 1.2 * rng.next_f32());
            let camera = Camera {
                eye,
                target,
                up: raykit_core::Vec3::Y,
                vfov_deg: 60.0,
            };
            let frustum = Frustum::from_camera(&camera, 16.0 / 9.0, 0.01 * r, 4.0 * r);
            (camera, frustum)
        })
        .collect()
}

fn fmt_opt<T: std::fmt::Display>(v: Option<T>) -> String {
    v.map(|v| v.to_string()).unwrap_or_else(|| "–".into())
}

fn markdown(rows: &[Row], name: &str, tris: usize, args: &SplitHeuristicArgs) -> String {
    let mut s = format!(
        "# Split-heuristic experiment (Kim 2013)\n\n`raykit experiment split-heuristic --size {} --frustums {} --reps {} --threads {} --game-leaf {}` on {name} ({tris} triangles).\n\n{}\nSplit polygons: pieces cut by a split plane, summed over the build; the SAH tree cuts nothing and counts its leaf references beyond one per triangle instead. Split triangles: original triangles in more than one piece (SAH tree: listed by more than one leaf).\n\nCulled frames/s: per view, the parts in the frustum are found through the tree and the pieces of those parts (the cut mesh's, for the game trees) are rasterized at {FRAME_WIDTH}×{FRAME_HEIGHT} by the CPU rasterizer (Kim 2013's Fig. 7 measured rendering frames of the culled level).\n\n",
        args.size, args.frustums, args.reps, args.threads, args.game_leaf, super::provenance()
    );
    s += "| split | split polygons | split triangles | depth | leaves | build ms | T-junctions | fast ms | naive ms | naive = fast | Mrays/s | frustum queries/s | culled frames/s |\n|---|---:|---:|---:|---:|---:|---:|---:|---:|---|---:|---:|---:|\n";
    for r in rows {
        s += &format!(
            "| {} | {} | {} | {} | {} | {:.1} | {} | {} | {} | {} | {:.2} | {:.1} | {:.1} |\n",
            r.split,
            r.split_polygons,
            r.split_triangles,
            r.depth,
            r.leaves,
            r.build_ms,
            fmt_opt(r.t_junctions),
            fmt_opt(r.tjunction_fast_ms.map(|v| format!("{v:.1}"))),
            fmt_opt(r.tjunction_naive_ms.map(|v| format!("{v:.0}"))),
            fmt_opt(r.naive_equals_fast),
            r.ray_mrays,
            r.frustum_queries_per_s,
            r.culled_fps
        );
    }
    let bad: usize = rows
        .iter()
        .map(|r| r.ray_disagreements + r.frustum_disagreements)
        .sum();
    s += &format!("\nRay answers checked against the BVH2 and frustum answers against brute force: {bad} disagreements.\n");
    s
}

fn plots(rows: &[Row], out: &std::path::Path, name: &str) -> Result<()> {
    let game: Vec<&Row> = rows.iter().filter(|r| r.h.is_some()).collect();
    let sah = rows.iter().find(|r| r.h.is_none());
    let series = |label: &str, f: &dyn Fn(&Row) -> Option<f64>| Series {
        name: label.to_string(),
        points: game
            .iter()
            .filter_map(|r| Some((r.h? as f64, f(r)?)))
            .collect(),
    };
    let reference = |f: &dyn Fn(&Row) -> f64| {
        sah.map(|r| vec![("SAH tree".to_string(), f(r))])
            .unwrap_or_default()
    };
    let figs: Vec<(&str, LineChart)> = vec![
        (
            "fig5_split_polygons.svg",
            LineChart {
                title: format!("Fig. 5: split polygons vs H ({name})"),
                x_label: "H",
                y_label: "split polygons",
                series: vec![series("game heuristic", &|r| Some(r.split_polygons as f64))],
                reference: sah
                    .map(|r| {
                        vec![(
                            "SAH tree (extra leaf references; no cuts)".to_string(),
                            r.split_polygons as f64,
                        )]
                    })
                    .unwrap_or_default(),
            },
        ),
        (
            "fig6_tjunction_time.svg",
            LineChart {
                title: format!("Fig. 6: T-junction elimination time vs H ({name})"),
                x_label: "H",
                y_label: "ms",
                series: vec![
                    series("fast (grid)", &|r| r.tjunction_fast_ms),
                    series("naive O(n²)", &|r| r.tjunction_naive_ms),
                ],
                reference: Vec::new(),
            },
        ),
        (
            "fig7_query_speed.svg",
            LineChart {
                title: format!("Fig. 7: ray casting speed vs H ({name})"),
                x_label: "H",
                y_label: "Mrays/s (kd-stack, Möller)",
                series: vec![series("game heuristic", &|r| Some(r.ray_mrays))],
                reference: reference(&|r| r.ray_mrays),
            },
        ),
        (
            "fig7c_culled_frames.svg",
            LineChart {
                title: format!("Fig. 7: frames/s drawing the frustum-culled parts vs H ({name})"),
                x_label: "H",
                y_label: "frames/s (cull + rasterize 512×288)",
                series: vec![series("game heuristic", &|r| Some(r.culled_fps))],
                reference: reference(&|r| r.culled_fps),
            },
        ),
        (
            "fig7b_frustum_queries.svg",
            LineChart {
                title: format!("Fig. 7b: frustum culling queries/s vs H ({name})"),
                x_label: "H",
                y_label: "queries/s (parts in frustum)",
                series: vec![series("game heuristic", &|r| Some(r.frustum_queries_per_s))],
                reference: reference(&|r| r.frustum_queries_per_s),
            },
        ),
        (
            "fig8_build_time.svg",
            LineChart {
                title: format!("Fig. 8: build, and build + T-junction elimination, vs H ({name})"),
                x_label: "H",
                y_label: "ms",
                series: vec![
                    series("build", &|r| Some(r.build_ms)),
                    series("build + T-junction elimination (grid)", &|r| {
                        Some(r.build_ms + r.tjunction_fast_ms?)
                    }),
                ],
                reference: reference(&|r| r.build_ms),
            },
        ),
        (
            "depth.svg",
            LineChart {
                title: format!("Tree depth vs H ({name})"),
                x_label: "H",
                y_label: "depth",
                series: vec![series("game heuristic", &|r| Some(r.depth as f64))],
                reference: reference(&|r| r.depth as f64),
            },
        ),
    ];
    std::fs::create_dir_all(out)?;
    for (file, chart) in figs {
        write_svg(&chart, &out.join(file))?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;
    use raykit_core::Vec3;

    /// A soup of random triangles of side up to `size` in the unit cube:
    /// enough of them for the SAH tree to split, each wide enough to
    /// straddle some of its planes.
    fn soup(n: usize, size: f32, seed: u64) -> TriangleMesh {
        let mut rng = Pcg32::new(seed);
        let mut positions = Vec::with_capacity(3 * n);
        for _ in 0..n {
            let corner = rng.in_box(Vec3::ZERO, Vec3::ONE);
            positions.push(corner);
            for _ in 0..2 {
                positions.push(corner + rng.in_box(Vec3::ZERO, Vec3::splat(size)));
            }
        }
        let indices = (0..n as u32)
            .map(|t| [3 * t, 3 * t + 1, 3 * t + 2])
            .collect();
        TriangleMesh::new(positions, indices)
    }

    /// The sharing figures of the SAH row against a count through the laid
    /// out tree's own leaves (`Accel::visit_regions` over the compact
    /// kd-stack layout, whose triangle order and leaf list differ from the
    /// pointer tree's).
    #[test]
    fn sah_sharing_matches_the_leaves_of_the_laid_out_tree() {
        for (n, size, seed) in [(200, 0.2, 1), (1000, 0.1, 2), (3000, 0.05, 3)] {
            let mesh = soup(n, size, seed);
            let opts = BuildOptions {
                kd: KdOptions {
                    split: KdSplit::Sah,
                    max_leaf_size: 4,
                    ..KdOptions::default()
                },
                ..BuildOptions::default()
            };
            let (root, cell) = build_tree(&mesh, &opts.kd);
            let accel = kd_accel_from_tree(
                AccelKind::KdStack,
                TestKind::Moller,
                &mesh,
                &root,
                &cell,
                &opts,
                0.0,
            )
            .expect("kd-stack is a kd-tree traversal");
            let mut listed = vec![0usize; n];
            accel.visit_regions(&mut |_| true, &mut |tris| {
                for &t in tris {
                    listed[t as usize] += 1;
                }
            });
            let want_shared = listed.iter().filter(|&&c| c > 1).count();
            let want_extra =
                accel.stats().triangle_refs - listed.iter().filter(|&&c| c > 0).count();
            let got = LeafSharing::of(&root, n);
            assert_eq!(got.shared_triangles, want_shared, "{n} triangles");
            assert_eq!(got.extra_references, want_extra, "{n} triangles");
            assert!(
                want_shared > 0,
                "the soup makes the SAH tree share triangles"
            );
            assert!(got.shared_triangles <= n);
        }
    }
}
