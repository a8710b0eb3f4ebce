#!/usr/bin/env bash
# Renders the README gallery into docs/images/gallery/ from the example
# scenes and the test data (data/, or $RAYKIT_SHARED_DATA).
# Builds the release binary first. Each line is a command a user can run.
set -euo pipefail
cd "$(dirname "$0")/.."
data=${RAYKIT_SHARED_DATA:-data}
out=docs/images/gallery
mkdir -p "$out"
cargo build --release -q
r() { ./target/release/raykit render "$@"; }

# Glass and mirror in the Cornell box: a glTF scene with its own camera and light.
r --scene examples/whitted-cornell.gltf --width 640 --height 480 --spp 4 --out "$out/whitted-cornell.png"
# The same with shadow maps (paper 001) instead of shadow rays.
r --scene examples/whitted-cornell.gltf --width 640 --height 480 --spp 4 --shadows maps --out "$out/whitted-cornell-maps.png"
# The glass dragon in an HDR environment, inside paper 001's environment box.
r --scene "$data/meshes/dragon_vrip_res2.ply.gz" --material glass --env "$data/envmaps/courtyard.exr" --env-box \
  --width 640 --height 480 --spp 4 --depth 8 --out "$out/dragon-glass-courtyard.png"
# A gold dragon: plain direction lookup against the environment box.
r --scene "$data/meshes/dragon_vrip_res2.ply.gz" --material gold --env "$data/envmaps/sunset.exr" \
  --width 480 --height 360 --spp 4 --out "$out/dragon-gold-map.png"
r --scene "$data/meshes/dragon_vrip_res2.ply.gz" --material gold --env "$data/envmaps/sunset.exr" --env-box \
  --width 480 --height 360 --spp 4 --out "$out/dragon-gold-box.png"
# The engine assembly (glTF, 121k triangles) under a key and a fill light in the studio map.
r --scene "$data/meshes/2CylinderEngine.glb" --env "$data/envmaps/studio.exr" \
  --light dir:-0.3,-1,-0.6:0.9,0.9,0.85 --light dir:0.6,-0.4,0.7:0.3,0.3,0.35 \
  --width 640 --height 480 --spp 4 --out "$out/engine-studio.png"
echo "gallery written to $out"
