#!/usr/bin/env bash
# The "T-junction elimination alone" table of BENCHMARKS.md (paper 002):
# each mesh cut by the game heuristic's kd planes (raykit tjunctions
# --kd-cut H), then the T-junctions found by the grid finder and by the
# naive O(n²) finder, one thread, median find time of REPS runs. The naive
# finder refuses meshes above 2e9 triangle × point pairs.
#
#   scripts/tjunction-finders.sh [REPS] [H]      (defaults 3 and 8)
#
# Needs a release build (cargo build --release) and python3; prints a
# markdown table.
set -euo pipefail
cd "$(dirname "$0")/.."
reps="${1:-3}"
h="${2:-8}"
bin="${RAYKIT:-target/release/raykit}"
[ -x "$bin" ] || { echo "missing $bin: run cargo build --release (or set RAYKIT)"; exit 1; }
tmp="$(mktemp -d)"
trap 'rm -rf "$tmp"' EXIT
echo "\`scripts/tjunction-finders.sh $reps $h\` — $(grep -m1 'model name' /proc/cpuinfo | cut -d: -f2 | xargs), 1 thread, load $(cut -d' ' -f1 /proc/loadavg) at the start"
echo
echo "| mesh | triangles after the cut (H = $h) | T-junctions | fast find ms | naive find ms | naive / fast |"
echo "|---|--:|--:|--:|--:|--:|"
for mesh in data/meshes/teapot_992.obj data/meshes/bunny_3674.obj data/meshes/dragon_vrip_res4.ply.gz \
            data/meshes/bearing.stl data/meshes/2CylinderEngine.glb data/meshes/dragon_vrip_res2.ply.gz; do
  for method in fast naive; do
    for r in $(seq "$reps"); do
      if ! "$bin" tjunctions "$mesh" "$tmp/out.ply" --kd-cut "$h" --method "$method" --threads 1 --json \
           >"$tmp/$method.$r.json" 2>"$tmp/err"; then
        echo refused >"$tmp/$method.$r.json"
      fi
    done
  done
  python3 - "$mesh" "$tmp" "$reps" <<'PY'
import json, os, statistics, sys
mesh, tmp, reps = sys.argv[1], sys.argv[2], int(sys.argv[3])
def runs(method):
    out = []
    for r in range(1, reps + 1):
        text = open(os.path.join(tmp, f"{method}.{r}.json")).read()
        if text.strip() == "refused":
            return None
        out.append(json.loads(text))
    return out
fast, naive = runs("fast"), runs("naive")
ms = lambda rs: statistics.median(r["find_s"] for r in rs) * 1e3
f = ms(fast)
n = ms(naive) if naive else None
print(f"| {os.path.basename(mesh)} | {fast[0]['triangles_in']:,} | {fast[0]['t_junctions']:,} | {f:.1f} | "
      + (f"{n:.0f} | {n / f:.0f}× |" if n else "refused | – |"))
PY
done
