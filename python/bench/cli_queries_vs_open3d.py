"""`raykit query` (the CLI, one thread) against Open3D's RaycastingScene
(one thread) on the same points, interleaved in one run: closest points
for points uniform in the dragon's box grown by 10% and points near the
surface. raykit's rate is the `per_s` of the query's JSON line (loading and
building excluded, as Open3D's scene is built before its timing).

    python python/bench/cli_queries_vs_open3d.py

Needs numpy and open3d, a release build at target/release/raykit (or
RAYKIT=...), the full dragon at data-cache/dragon_vrip.ply (DRAGON=...),
and it writes its point files (262,144 points each, made as
python/bench/bench_queries_vs_open3d.py makes them, seed 3) to a
temporary folder.
"""
import os
import numpy as np, open3d as o3d, time, json, subprocess, tempfile
DRAGON = os.environ.get('DRAGON', 'data-cache/dragon_vrip.ply')
RAYKIT = os.environ.get('RAYKIT', 'target/release/raykit')
POINTS = tempfile.mkdtemp()
OUT = os.path.join(POINTS, 'out.bin')
m = o3d.io.read_triangle_mesh(DRAGON)
scene = o3d.t.geometry.RaycastingScene(nthreads=1)
scene.add_triangles(o3d.t.geometry.TriangleMesh.from_legacy(m))
v = np.asarray(m.vertices)
lo, hi = v.min(0), v.max(0)
pad, diag, n = 0.1 * (hi - lo), np.linalg.norm(hi - lo), 1 << 18
rng = np.random.default_rng(3)
(lo - pad + rng.random((n, 3)) * (hi - lo + 2 * pad)).astype('<f4').tofile(os.path.join(POINTS, 'pts_uniform.bin'))
step = rng.normal(size=(n, 3))
step *= 0.01 * diag * rng.random((n, 1)) / np.linalg.norm(step, axis=1, keepdims=True)
(v[rng.integers(0, len(v), n)] + step).astype('<f4').tofile(os.path.join(POINTS, 'pts_near.bin'))
for name in ['uniform', 'near']:
    p = np.fromfile(os.path.join(POINTS, f'pts_{name}.bin'), dtype='<f4').reshape(-1, 3)
    small = o3d.core.Tensor(p[:8192])
    scene.compute_closest_points(small[:1], nthreads=1)
    rates = []
    for _ in range(3):
        t = time.perf_counter(); scene.compute_closest_points(small, nthreads=1); rates.append(8192 / (time.perf_counter() - t))
    ours = []
    for _ in range(3):
        out = subprocess.run([RAYKIT, 'query', 'closest', '--mesh', DRAGON,
                              '--points', os.path.join(POINTS, f'pts_{name}.bin'), '--out', OUT, '--threads', '1'], capture_output=True, text=True)
        ours.append(json.loads([l for l in (out.stdout + out.stderr).splitlines() if l.startswith('{')][-1])['per_s'])
        t = time.perf_counter(); scene.compute_closest_points(small, nthreads=1); rates.append(8192 / (time.perf_counter() - t))
    o, r = np.median(rates), np.median(ours)
    print(f"{name}: open3d {o:,.0f} points/s ({min(rates):,.0f}-{max(rates):,.0f}), raykit {r:,.0f} ({min(ours):,.0f}-{max(ours):,.0f}), ratio {r/o:.2f}")
