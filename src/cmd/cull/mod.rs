//! `raykit cull`: visibility culling of a model — removes the triangles (or
//! parts) that no viewpoint outside the model can see: by ray tracing (the
//! default), or by Min's (2008) grid method.

mod args;
mod placed;
mod truth_file;

pub use args::CullArgs;
use args::ModeArg;
use truth_file::{load_truth, save_truth};

use anyhow::{bail, Context, Result};
use indicatif::{ProgressBar, ProgressStyle};
use raykit_core::TriangleMesh;
use raykit_cull::{
    compare, cull, cull_by_rays, independent_truth, CullOptions, CullReport, EvalOptions,
    GroundTruth, Instancing, RayOptions,
};
use raykit_io::MeshFormat;
use raykit_lab::measure::timed;
use std::process::ExitCode;

/// Exit status of an evaluation that found a visible triangle removed.
pub const FALSE_REMOVAL_STATUS: u8 = 3;

/// Load, cull, write, report.
pub fn run(args: CullArgs) -> Result<ExitCode> {
    let Some(out_format) = MeshFormat::from_path(&args.output) else {
        bail!(
            "{}: unknown mesh file extension; expected .obj, .ply, .stl, .off, .gltf or .glb (optionally .gz)",
            args.output.display()
        );
    };
    let placed_output =
        out_format.is_gltf() && MeshFormat::from_path(&args.input).is_some_and(MeshFormat::is_gltf);
    if args.shared_meshes && !placed_output {
        bail!("--shared-meshes needs a glTF or GLB input and a .gltf or .glb output");
    }
    // Every output is checked before any work: not an input (the mesh or
    // saved labels), in a folder that takes files, and no two the same.
    let inputs: Vec<&std::path::Path> = std::iter::once(args.input.as_path())
        .chain(args.truth.as_deref())
        .collect();
    crate::paths::ensure_output(&args.output, &inputs)?;
    if let Some(r) = &args.report {
        crate::paths::ensure_output(r, &inputs)?;
        crate::paths::ensure_distinct(&args.output, r, "the output", "--report")?;
    }
    if let Some(t) = &args.save_truth {
        crate::paths::ensure_output(t, &inputs)?;
        crate::paths::ensure_distinct(&args.output, t, "the output", "--save-truth")?;
        if let Some(r) = &args.report {
            crate::paths::ensure_distinct(r, t, "--report", "--save-truth")?;
        }
    }
    let mode = if args.paper {
        ModeArg::Paper
    } else {
        args.mode
    };
    if args.confirm && mode != ModeArg::Conservative {
        bail!("--confirm belongs to --mode conservative");
    }
    let options = match mode {
        ModeArg::Paper => CullOptions::paper(args.resolution as usize),
        _ => CullOptions {
            confirm: args.confirm.then(EvalOptions::confirmation),
            ..CullOptions::conservative(args.resolution as usize)
        },
    };
    let ray_options = RayOptions {
        min_opening: args.min_opening,
        max_rounds: args.rounds as usize,
        ..Default::default()
    };
    let bar = crate::stage::spinner(format!("reading {}", args.input.display()));
    let (mesh, load_s) = timed(|| raykit_io::load_mesh(&args.input));
    let mesh = match mesh {
        Ok(m) => m,
        Err(e) => {
            bar.finish_and_clear();
            return Err(e.into());
        }
    };
    let saved_truth = match (&args.truth, args.evaluate) {
        (Some(path), true) => match load_truth(path, &args.input, &mesh) {
            Ok(t) => Some(t),
            Err(e) => {
                bar.finish_and_clear();
                return Err(e);
            }
        },
        _ => None,
    };
    bar.set_message(match mode {
        ModeArg::Rays => format!("culling {} triangles by rays", mesh.num_triangles()),
        _ => format!(
            "culling {} triangles at resolution {}",
            mesh.num_triangles(),
            args.resolution
        ),
    });
    let (result, cull_s) = timed(|| match mode {
        ModeArg::Rays => cull_by_rays(&mesh, &ray_options),
        _ => cull(&mesh, &options),
    });
    bar.finish_and_clear();
    let result = result.with_context(|| format!("{}", args.input.display()))?;
    let keep = result.keep(&mesh, args.by.into());
    let scene = if placed_output {
        raykit_io::load_gltf_instances_of(&args.input, &mesh)
            .with_context(|| format!("{}: reading its instancing", args.input.display()))?
    } else {
        None
    };
    let keep = match &scene {
        Some(s) if args.shared_meshes => placed::shared_keep(s, &mesh, &keep),
        _ => keep,
    };
    let kept = mesh.retain_triangles(&keep);
    if kept.num_triangles() == 0 {
        bail!(
            "{}: every triangle was found hidden; nothing to write",
            args.input.display()
        );
    }
    // The ground truth first: its labels are written with the mesh, after
    // all the work, so that a failed run leaves no output behind.
    let (ground_truth, evaluation) = if args.evaluate {
        let truth = match saved_truth {
            Some(truth) => truth,
            None => evaluate_input(&mesh, &args),
        };
        let eval = compare(&truth, &keep, &mesh);
        (Some(truth), Some(eval))
    } else {
        (None, None)
    };
    // Every output is written under a temporary name and all are put in
    // place together at the end: a run that fails part way (a full disk on
    // the report, say) leaves the old outputs as they were.
    let mut outputs = raykit_io::OutputSet::new();
    let mut instancing = None;
    let (saved, save_s) = timed(|| match &scene {
        Some(s) => {
            let (meshes, nodes) = placed::placed_meshes(s, &mesh, &keep);
            instancing = Some(Instancing {
                nodes_in: s.instances.len(),
                meshes_in: s.geometries.len(),
                nodes_out: nodes.len(),
                meshes_out: meshes.len(),
                shared: args.shared_meshes,
            });
            raykit_io::stage_gltf_placed(&mut outputs, &args.output, &meshes, &nodes)
        }
        None => raykit_io::stage_mesh(&mut outputs, &args.output, &kept),
    });
    saved.with_context(|| format!("cannot write {}", args.output.display()))?;
    if let (Some(path), Some(truth)) = (&args.save_truth, &ground_truth) {
        save_truth(&mut outputs, path, &args, &mesh, truth)?;
    }
    let stats = &result.stats;
    let parts_out = kept.parts.len().max(1);
    let report = CullReport {
        input: args.input.display().to_string(),
        output: args.output.display().to_string(),
        by: args.by.into(),
        mode: mode.into(),
        confirm: options.confirm.is_some(),
        resolution: args.resolution,
        min_opening: args.min_opening,
        triangles_in: mesh.num_triangles(),
        triangles_out: kept.num_triangles(),
        triangles_removed: mesh.num_triangles() - kept.num_triangles(),
        parts_in: stats.parts,
        parts_out,
        parts_removed: stats.parts - parts_out,
        load_s,
        cull_s,
        save_s,
        stats: stats.clone(),
        instancing,
        ground_truth,
        evaluation,
    };
    let json = serde_json::to_string_pretty(&report)?;
    if let Some(path) = &args.report {
        outputs
            .write(path, |w| {
                w.write_all(json.as_bytes())?;
                w.write_all(b"\n")
            })
            .with_context(|| format!("cannot write {}", path.display()))?;
    }
    outputs
        .commit()
        .context("cannot put the outputs in place")?;
    if args.json {
        println!("{json}");
    } else {
        print!("{}", report.summary(&args.output, args.report.as_deref()));
    }
    match &report.evaluation {
        // Not 2: clap ends a usage error with 2, and a script must tell
        // a false removal from a mistyped option.
        Some(e) if e.false_removals > 0 => Ok(ExitCode::from(FALSE_REMOVAL_STATUS)),
        _ => Ok(ExitCode::SUCCESS),
    }
}

/// The ground truth of `mesh` with the arguments' settings
/// ([`independent_truth`]), with a progress bar.
fn evaluate_input(mesh: &TriangleMesh, args: &CullArgs) -> GroundTruth {
    let eval_options = EvalOptions {
        max_rounds: args.eval_rounds as usize,
        min_opening: args.eval_min_opening,
        ..Default::default()
    };
    let bar = ProgressBar::new(1).with_style(
        ProgressStyle::with_template(
            "ground truth, round {msg} {bar:30} {pos}/{len} [{elapsed}, eta {eta}]",
        )
        .expect("valid template"),
    );
    let truth = independent_truth(mesh, &eval_options, &|p| {
        if p.done == 1 {
            bar.set_length(p.total);
            bar.reset_eta();
            bar.set_message(format!(
                "{} of at most {} ({} triangles visible so far; triangles, then viewpoints)",
                p.round + 1,
                eval_options.max_rounds,
                p.visible
            ));
        }
        bar.set_position(p.done);
    });
    bar.finish_and_clear();
    truth
}
