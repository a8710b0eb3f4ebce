#!/usr/bin/env bash
# Paper 004's Table 1, paper 003's shadow-map times and the gdal_viewshed
# comparison, in one run: installs gdal-bin (Debian) when gdal_viewshed is
# missing, then runs `raykit experiment terrain` with the given arguments.
set -euo pipefail
cd "$(dirname "$0")/.."
if ! command -v gdal_viewshed >/dev/null; then
  if [ "$(id -u)" = 0 ]; then sudo=; else sudo=sudo; fi
  $sudo apt-get update -qq && $sudo apt-get install -y -qq gdal-bin >/dev/null
fi
cargo build --release -q
./target/release/raykit experiment terrain "$@"
