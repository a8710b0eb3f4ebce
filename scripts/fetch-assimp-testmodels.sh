#!/usr/bin/env bash
# Fetch Debian's assimp-testmodels (assimp's test models, BSD-3-Clause and
# others, see the package's copyright file) into data-cache/ for
# `raykit experiment cull`. Needs apt-get (no root: `apt-get download`).
set -euo pipefail
cd "$(dirname "$0")/.."
dest=data-cache/assimp-testmodels
if [ -d "$dest/usr/share/assimp/models" ]; then
    echo "already there: $dest"
    exit 0
fi
mkdir -p data-cache
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
(cd "$tmp" && apt-get download assimp-testmodels)
rm -rf "$dest.partial"
dpkg-deb -x "$tmp"/assimp-testmodels_*.deb "$dest.partial"
mv "$dest.partial" "$dest"
echo "unpacked into $dest/usr/share/assimp/models"
