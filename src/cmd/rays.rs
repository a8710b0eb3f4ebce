//! `raykit rays`: generate a standard ray set as a binary ray file.

use anyhow::{bail, Result};
use clap::Args;
use raykit_core::accel::{build_accel, AccelKind, BuildOptions};
use raykit_core::raysets::{self, RayKind};
use raykit_core::tri::TestKind;
use raykit_lab::args::scene_arg;
use std::path::PathBuf;
use std::process::ExitCode;

/// Arguments of `raykit rays`.
#[derive(Args)]
#[command(
    after_help = "Ray file format: per ray 8 little-endian f32 `ox oy oz dx dy dz tnear tfar` (32 bytes).\n\
primary:    SIZE x SIZE pinhole rays, camera framing the mesh (40 degree vertical field of view).\n\
shadow:     from each primary hit, offset along the normal, to a point light above the scene\n            (fewer rays than pixels: misses give none).\n\
incoherent: SIZE x SIZE rays from a sphere of radius = box diagonal around the box centre,\n            aimed at random points inside the box."
)]
pub struct RaysArgs {
    /// Mesh file or builtin:NAME.
    #[arg(long)]
    mesh: String,
    /// Which standard set: primary, shadow or incoherent.
    #[arg(long, default_value = "primary", value_parser = ["primary", "shadow", "incoherent"])]
    kind: String,
    /// Image side in pixels (SIZE² rays for primary and incoherent sets).
    #[arg(long, default_value_t = 1024)]
    size: u32,
    /// Seed of the incoherent set.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Output ray file.
    #[arg(long)]
    out: PathBuf,
}

/// Generate and write the ray set.
pub fn run(args: RaysArgs) -> Result<ExitCode> {
    let max = raykit_io::MAX_IMAGE_SIDE;
    if args.size == 0 || args.size > max {
        bail!("--size must be between 1 and {max}, got {}", args.size);
    }
    crate::paths::ensure_output(&args.out, &[std::path::Path::new(&args.mesh)])?;
    let scene = scene_arg::load(&args.mesh)?;
    let mesh = &scene.mesh;
    let bounds = mesh.bounds();
    let kind = RayKind::from_name(&args.kind).expect("clap checked the name");
    let rays = match kind {
        RayKind::Primary => raysets::primary(&raysets::standard_camera(mesh), args.size),
        RayKind::Incoherent => raysets::incoherent(&bounds, (args.size as usize).pow(2), args.seed),
        RayKind::Shadow => {
            let accel = build_accel(
                AccelKind::Bvh2,
                TestKind::Moller,
                mesh,
                &BuildOptions::default(),
            );
            let prim = raysets::primary(&raysets::standard_camera(mesh), args.size);
            let mut hits = vec![None; prim.len()];
            accel.intersect_batch(&prim, &mut hits);
            raysets::shadow(mesh, &prim, &hits, raysets::standard_light(&bounds))
        }
    };
    raykit_io::write_rays(&args.out, &rays)?;
    eprintln!(
        "wrote {} {} rays to {}",
        rays.len(),
        kind.name(),
        args.out.display()
    );
    Ok(ExitCode::SUCCESS)
}
