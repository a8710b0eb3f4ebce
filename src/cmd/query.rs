//! `raykit query`: point and multi-hit ray queries on a mesh's surface,
//! from a point or ray file to a binary answer file.

use anyhow::{bail, Context, Result};
use clap::{Args, ValueEnum};
use raykit_core::query::{QueryKind, SurfaceBvh};
use raykit_core::{Ray, Vec3};
use raykit_io::{write_answers, write_scene_hit_lists, write_u32s};
use raykit_lab::args::scene_arg;
use raykit_lab::measure::{per_second, pool, timed};
use serde_json::json;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::ExitCode;

/// The question asked of each point or ray.
#[derive(Clone, Copy, PartialEq, Eq, ValueEnum)]
pub enum Query {
    /// Per point: the nearest point of the surface and its triangle
    /// (Ericson 2005's closest point on a triangle, nearest box first).
    Closest,
    /// Per point: the unsigned distance to the surface.
    Distance,
    /// Per point: the distance, negative inside (inside by the generalized
    /// winding number).
    SignedDistance,
    /// Per point: 1 inside, 0 outside, by the generalized winding number
    /// (Jacobson et al. 2013, with Barill et al. 2018's fast far-field
    /// approximation); right on open and self-intersecting meshes too.
    Inside,
    /// Per ray: how many triangles it crosses within [tnear, tfar].
    Count,
    /// Per ray: every hit within [tnear, tfar], nearest first (at most
    /// --max-hits).
    AllHits,
}

impl Query {
    /// The library's query of the same name.
    fn kind(self) -> QueryKind {
        match self {
            Query::Closest => QueryKind::Closest,
            Query::Distance => QueryKind::Distance,
            Query::SignedDistance => QueryKind::SignedDistance,
            Query::Inside => QueryKind::Inside,
            Query::Count => QueryKind::Count,
            Query::AllHits => QueryKind::AllHits,
        }
    }

    fn name(self) -> &'static str {
        self.kind().name()
    }

    fn takes_rays(self) -> bool {
        self.kind().takes_rays()
    }
}

/// Arguments of `raykit query`.
#[derive(Args)]
#[command(after_help = "Queries:\n  \
closest          per point, the nearest point of the surface (Ericson 2005's closest point\n                   \
on a triangle, searched nearest box first in an 8-wide BVH)\n  \
distance         per point, the unsigned distance to the surface\n  \
signed-distance  per point, the distance, negative inside\n  \
inside           per point, whether it is inside: its generalized winding number (Jacobson\n                   \
et al. 2013; far triangles grouped by Barill et al. 2018's fast approximation)\n                   \
is at least 1/2, which is right on open and self-intersecting meshes too\n  \
count            per ray, the number of triangles it crosses within [tnear, tfar]\n  \
all-hits         per ray, every hit within [tnear, tfar], nearest first\n\
A ray through an edge or a corner that triangles share crosses the surface there once, and is\n\
counted and listed once (exact edge tests with one tie rule for both neighbours), so a ray from\n\
outside a closed surface crosses it an even number of times.\n\n\
Files (little-endian):\n  \
point file (--points): per point 3 f32 x y z (12 bytes)\n  \
ray file (--rays): the ray file of `raykit rays` and `raykit trace` (t counts lengths of the\n    \
ray's direction)\n  \
distance, signed-distance: one f32 per point (NaN for a point that is not finite)\n  \
inside: one byte per point (1 = inside)\n  \
closest: per point f32 x y z distance, u32 triangle (20 bytes; NaN and 4294967295\n    \
when there is no answer: a point that is not finite, or an empty mesh)\n  \
count: one u32 per ray\n  \
all-hits: per ray a u32 n, then n pairs f32 t, u32 triangle, nearest first\n\n\
Prints one JSON line of statistics on stderr:\n\
{\"query\", \"mesh_triangles\", \"points\" or \"rays\", \"answered\" (points or rays with a finite\n\
answer or at least one hit), \"hits\" (count, all-hits), \"truncated\" (all-hits: rays with more\n\
hits than --max-hits), \"inside\" (inside),\n\
\"load_ms\", \"build_ms\", \"query_ms\", \"per_s\", \"threads\"} (query_ms excludes loading and building;\n\
per_s is points or rays per second).\n\n\
Several --mesh (or --instanced), for count and all-hits: an instanced scene under a two-level\n\
BVH (each file a geometry placed once; a glTF file one geometry per mesh, one instance per node).\n\
count is unchanged; all-hits gives per ray a u32 n, then n records f32 t, u32 triangle,\n\
u32 geometry, u32 instance (16 bytes), nearest first. The JSON line gives the scene's figures\n\
(geometries, instances, stored_triangles, instanced_triangles, scene_bytes, inputs) in place of\n\
mesh_triangles.")]
pub struct QueryArgs {
    /// The query (see below).
    #[arg(value_enum)]
    query: Query,
    /// Mesh file or builtin:NAME; several (--mesh A --mesh B) make an
    /// instanced scene (count and all-hits).
    #[arg(long, required = true)]
    mesh: Vec<String>,
    /// Query an instanced scene even with one --mesh (a glTF file keeps its
    /// instancing); count and all-hits.
    #[arg(long)]
    instanced: bool,
    /// Point file (closest, distance, signed-distance, inside).
    #[arg(long, conflicts_with = "rays")]
    points: Option<PathBuf>,
    /// Ray file (count, all-hits).
    #[arg(long)]
    rays: Option<PathBuf>,
    /// Output file.
    #[arg(long)]
    out: PathBuf,
    /// all-hits: keep at most this many hits per ray, the nearest (0 = all
    /// of them) [default: 64].
    #[arg(long)]
    max_hits: Option<u32>,
    /// Worker threads (0 = one per core; at most 4096).
    #[arg(long, default_value_t = 0)]
    threads: usize,
}

/// The hits kept per ray for `--max-hits` (0: all of them).
fn hit_cap(max_hits: Option<u32>) -> usize {
    match max_hits.unwrap_or(64) {
        0 => usize::MAX,
        m => m as usize,
    }
}

/// Cut every list to `cap` entries; the number of lists that were longer.
fn cut_to<T>(lists: &mut [Vec<T>], cap: usize) -> usize {
    lists
        .iter_mut()
        .filter(|l| l.len() > cap)
        .map(|l| l.truncate(cap))
        .count()
}

/// Write `out` atomically with `write`.
fn write_out(out: &Path, write: impl FnOnce(&mut dyn Write) -> std::io::Result<()>) -> Result<()> {
    raykit_io::write_atomic(out, write).with_context(|| format!("{}: cannot write", out.display()))
}

/// Run the query.
pub fn run(args: QueryArgs) -> Result<ExitCode> {
    let q = args.query;
    let input = match (q.takes_rays(), &args.points, &args.rays) {
        (false, Some(p), _) => p,
        (true, _, Some(r)) => r,
        (false, _, _) => bail!("`query {}` reads points: give --points FILE", q.name()),
        (true, _, _) => bail!("`query {}` reads rays: give --rays FILE", q.name()),
    };
    if args.max_hits.is_some() && q != Query::AllHits {
        bail!(
            "--max-hits is for `query all-hits`, not `query {}`",
            q.name()
        );
    }
    if args.instanced || args.mesh.len() > 1 {
        if !q.takes_rays() {
            bail!(
                "`query {}` answers on one mesh, not an instanced scene: several --mesh and \
                 --instanced are for count and all-hits",
                q.name()
            );
        }
        return run_instanced(&args, input);
    }
    crate::paths::ensure_output(&args.out, &[input, Path::new(&args.mesh[0])])?;
    let pool = pool(args.threads)?;
    let threads = pool.current_num_threads();
    let bar = crate::stage::spinner(format!("reading {}", args.mesh[0]));
    let (scene, load_s) = timed(|| scene_arg::load(&args.mesh[0]));
    let mesh = scene?.mesh;
    bar.set_message(format!("reading {}", input.display()));
    let (points, rays): (Vec<Vec3>, Vec<Ray>) = if q.takes_rays() {
        (Vec::new(), raykit_io::read_rays(input)?)
    } else {
        (raykit_io::read_points(input)?, Vec::new())
    };
    bar.set_message(format!("building over {} triangles", mesh.num_triangles()));
    let (bvh, build_s) = pool.install(|| {
        timed(|| {
            let bvh = SurfaceBvh::build(&mesh);
            bvh.prepare(q.kind());
            bvh
        })
    });
    let n = points.len() + rays.len();
    let what = if q.takes_rays() { "rays" } else { "points" };
    bar.set_message(format!("{} of {n} {what} on {threads} threads", q.name()));
    let cap = hit_cap(args.max_hits);
    let (mut answers, query_s) =
        pool.install(|| timed(|| bvh.answer(q.kind(), &points, &rays, cap.saturating_add(1))));
    bar.set_message(format!("writing {}", args.out.display()));
    let truncated = match &mut answers {
        raykit_core::query::Answers::HitLists(lists) => Some(cut_to(lists, cap)),
        _ => None,
    };
    write_out(&args.out, |w| write_answers(w, &answers))?;
    bar.finish_and_clear();
    let (answered, hits, inside_count) =
        (answers.answered(&points), answers.hits(), answers.inside());
    let mut stats = json!({
        "query": q.name(),
        "mesh_triangles": mesh.num_triangles(),
    });
    let obj = stats.as_object_mut().expect("an object");
    obj.insert(
        (if q.takes_rays() { "rays" } else { "points" }).into(),
        json!(n),
    );
    obj.insert("answered".into(), json!(answered));
    if let Some(h) = hits {
        obj.insert("hits".into(), json!(h));
    }
    if let Some(t) = truncated {
        obj.insert("truncated".into(), json!(t));
    }
    if let Some(c) = inside_count {
        obj.insert("inside".into(), json!(c));
    }
    obj.insert("load_ms".into(), json!(load_s * 1e3));
    obj.insert("build_ms".into(), json!(build_s * 1e3));
    obj.insert("query_ms".into(), json!(query_s * 1e3));
    obj.insert("per_s".into(), json!(per_second(n, query_s)));
    obj.insert("threads".into(), json!(threads));
    eprintln!("{stats}");
    Ok(ExitCode::SUCCESS)
}

/// count and all-hits on an instanced scene (several meshes or
/// `--instanced`): all-hits records carry the geometry and instance ids.
fn run_instanced(args: &QueryArgs, input: &Path) -> Result<ExitCode> {
    let q = args.query;
    let mut inputs: Vec<&Path> = vec![input];
    inputs.extend(args.mesh.iter().map(Path::new));
    crate::paths::ensure_output(&args.out, &inputs)?;
    let pool = pool(args.threads)?;
    let threads = pool.current_num_threads();
    let bar = crate::stage::spinner(format!("reading {}", input.display()));
    let rays = raykit_io::read_rays(input)?;
    bar.set_message(format!("reading and building {} meshes", args.mesh.len()));
    let loaded = pool.install(|| {
        crate::instanced_arg::load(&args.mesh, &raykit_core::accel::BuildOptions::default())
    })?;
    bar.set_message(format!(
        "{} of {} rays on {threads} threads",
        q.name(),
        rays.len()
    ));
    let scene = &loaded.scene;
    let mask = raykit_core::instancing::MASK_ALL;
    let n = rays.len();
    let (answered, hits, query_s);
    let mut truncated = None;
    if q == Query::Count {
        let mut counts = vec![0u32; n];
        query_s = pool.install(|| timed(|| scene.count_hits_batch(&rays, mask, &mut counts)).1);
        answered = counts.iter().filter(|&&c| c > 0).count();
        hits = counts.iter().map(|&c| u64::from(c)).sum::<u64>();
        write_out(&args.out, |w| write_u32s(w, &counts))?;
    } else {
        let cap = hit_cap(args.max_hits);
        let (mut lists, s) =
            pool.install(|| timed(|| scene.ray_hits_batch(&rays, mask, cap.saturating_add(1))));
        truncated = Some(cut_to(&mut lists, cap));
        query_s = s;
        answered = lists.iter().filter(|l| !l.is_empty()).count();
        hits = lists.iter().map(|l| l.len() as u64).sum();
        write_out(&args.out, |w| write_scene_hit_lists(w, &lists))?;
    }
    bar.finish_and_clear();
    let per_s = per_second(n, query_s);
    let mut stats = json!({
        "query": q.name(),
        "instanced": true,
        "rays": n,
        "answered": answered,
        "hits": hits,
        "load_ms": loaded.load_s * 1e3,
        "build_ms": loaded.build_s * 1e3,
        "query_ms": query_s * 1e3,
        "per_s": per_s,
        "threads": threads,
    });
    if let (Some(o), serde_json::Value::Object(extra)) = (
        stats.as_object_mut(),
        crate::instanced_arg::stats_json(&loaded),
    ) {
        if let Some(t) = truncated {
            o.insert("truncated".into(), json!(t));
        }
        o.extend(extra);
    }
    eprintln!("{stats}");
    Ok(ExitCode::SUCCESS)
}
