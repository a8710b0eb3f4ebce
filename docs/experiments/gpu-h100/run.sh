#!/usr/bin/env bash
# The GPU kernels on a real GPU, ready for a machine that has one:
#
#   docs/experiments/gpu-h100/run.sh [OUT_DIR]     (default: docs/experiments/gpu-h100/latest)
#
# Runs `raykit experiment gpu` (kd-stack, kd-ropes, bvh-threaded and the
# compressed wide BVH, each × Plücker and Möller, on shirley6, the bunny, dragon res2 and
# the full dragon) with the honest timing: GPU timestamp queries where the
# adapter has them (the table says which clock was used), two warm-up runs,
# the median of REPS timed runs with their spread, the launch share (a
# one-ray dispatch against the batch), the nodes and bytes each ray fetches,
# and every answer checked against the CPU. Writes results.md, speed.csv,
# results.json and machine.txt (adapter, driver, GPU, CPU, commit, command)
# to OUT_DIR.
#
# Environment:
#   RAYKIT  a built raykit binary (a device machine without network cannot
#           run cargo: build here with `cargo build --release` and carry
#           target/release/raykit); default: target/release/raykit, built if
#           missing and cargo is present.
#   DRAGON  the full Stanford dragon (dragon_vrip.ply.gz, 871,414 triangles);
#           default: data-cache/package/models/dragon_vrip.ply.gz, else
#           /work/data-cache/dragon_vrip.ply, else left out (with a note).
#   SIZE    side of the ray sets (SIZE² primary and incoherent rays; default
#           2048: 4.2M rays, four dispatches of 2^20, enough that a launch
#           costs well under 5% even at 1 Grays/s).
#   REPS    timed runs (default 7).
set -euo pipefail
cd "$(dirname "$0")/../../.."
out=${1:-docs/experiments/gpu-h100/latest}
size=${SIZE:-2048}
reps=${REPS:-7}
raykit=${RAYKIT:-target/release/raykit}
if [ ! -x "$raykit" ]; then
  command -v cargo >/dev/null || { echo "no raykit binary at $raykit and no cargo to build it (set RAYKIT)" >&2; exit 1; }
  cargo build --release
fi
dragon=${DRAGON:-}
for d in data-cache/package/models/dragon_vrip.ply.gz /work/data-cache/dragon_vrip.ply; do
  [ -z "$dragon" ] && [ -f "$d" ] && dragon=$d
done
meshes=(--mesh builtin:shirley6 --mesh data/meshes/bunny_3674.obj --mesh data/meshes/dragon_vrip_res2.ply.gz)
if [ -n "$dragon" ]; then
  meshes+=(--mesh "$dragon")
else
  echo "note: full dragon not found (set DRAGON); measuring without it" >&2
fi
mkdir -p "$out"
# A real GPU: let wgpu take the Vulkan device (never lavapipe's pin).
unset VK_DRIVER_FILES VK_ICD_FILENAMES
export WGPU_BACKEND=${WGPU_BACKEND:-vulkan}
{
  echo "date: $(date -u '+%Y-%m-%d %H:%M UTC')"
  echo "commit: $(git rev-parse --short HEAD 2>/dev/null || echo unknown)"
  echo "command: $raykit experiment gpu --size $size --reps $reps --dem none ${meshes[*]} --out $out"
  command -v nvidia-smi >/dev/null && nvidia-smi --query-gpu=name,driver_version,memory.total,clocks.max.sm,clocks.max.mem --format=csv,noheader | sed 's/^/gpu: /'
  echo "cpu: $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), $(nproc) threads"
} > "$out/machine.txt"
cat "$out/machine.txt"
"$raykit" experiment gpu --size "$size" --reps "$reps" --dem none "${meshes[@]}" --out "$out"
