#!/usr/bin/env python3
"""Removal by connected component: what share of an assembly's pieces a cull
removes whole (paper 003 counts removed scene-graph nodes, not triangles).

    python scripts/cull-components.py INPUT.glb CULLED.glb [CULLED2.glb ...]

Each CULLED.glb is `raykit cull INPUT.glb CULLED.glb ... --report CULLED.json`
output (the report gives the part counts). Components are the connected
pieces of INPUT after welding corners within 1e-4; a triangle of INPUT is
kept when CULLED has a triangle with its centroid within 1e-5 of the
diagonal. Needs numpy, scipy and trimesh.
"""
import json
import sys

import numpy as np
import trimesh
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree


def triangles(path):
    m = trimesh.load(path, force="mesh", process=False)
    return np.asarray(m.vertices)[np.asarray(m.faces)]


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__)
    src = triangles(sys.argv[1])
    corners, index = np.unique(np.round(src.reshape(-1, 3), 4), axis=0, return_inverse=True)
    faces = index.reshape(-1, 3)
    n = len(corners)
    rows = np.concatenate([faces[:, 0], faces[:, 1]])
    cols = np.concatenate([faces[:, 1], faces[:, 2]])
    graph = coo_matrix((np.ones(len(rows)), (rows, cols)), shape=(n, n))
    count, label = connected_components(graph, directed=False)
    component = label[faces[:, 0]]
    pts = src.reshape(-1, 3)
    diag = np.linalg.norm(pts.max(0) - pts.min(0))
    print("| culled | triangles removed % | components removed | parts removed |")
    print("|---|--:|--:|--:|")
    for out in sys.argv[2:]:
        dist, _ = cKDTree(triangles(out).mean(1)).query(src.mean(1), k=1)
        alive = dist <= 1e-5 * diag
        kept_components = np.unique(component[alive])
        gone = count - len(kept_components)
        report = json.load(open(out.rsplit(".", 1)[0] + ".json"))
        print(f"| {out} | {100 * (~alive).mean():.1f} | {gone} / {count} ({100 * gone / count:.1f}%) "
              f"| {report['parts_removed']} / {report['parts_in']} |")


if __name__ == "__main__":
    main()
