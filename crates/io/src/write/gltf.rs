//! glTF 2.0 output: one scene with one node and one mesh per [`Part`] of the
//! mesh that has triangles (parts with none are dropped), each node and mesh
//! named after its part, each mesh one triangle primitive (positions, normals
//! and texture coordinates when present, u32 indices) holding only its part's
//! vertices, one primitive per run of triangles with the same material. A
//! mesh with a single part is written with its vertex arrays unchanged.
//! Materials, a camera and lights are written as [`write_gltf_scene`]'s
//! module `gltf_scene` describes.
//!
//! [`Part`]: raykit_core::Part

use super::check;
use super::gltf_scene::scene_extras;
use super::json::json_string;
use crate::uri::base64_encode;
use raykit_core::{Camera, Light, TriangleMesh, Vec2, Vec3};
use std::io::{self, Write};

/// The buffer, buffer views and accessors being written.
#[derive(Default)]
pub(super) struct Buffers {
    bin: Vec<u8>,
    views: Vec<String>,
    accessors: Vec<String>,
}

impl Buffers {
    /// Append one buffer view with `bytes` and an accessor over it; returns
    /// the accessor index.
    fn add(&mut self, bytes: &[u8], target: u32, accessor: impl FnOnce(usize) -> String) -> usize {
        let offset = self.bin.len();
        self.bin.extend_from_slice(bytes);
        let v = self.views.len();
        self.views.push(format!(
            r#"{{"buffer":0,"byteOffset":{offset},"byteLength":{},"target":{target}}}"#,
            bytes.len()
        ));
        self.accessors.push(accessor(v));
        self.accessors.len() - 1
    }

    /// Append f32 vectors of `dims` components; `extra` is added to the accessor.
    fn add_floats(&mut self, data: &[f32], dims: usize, extra: &str) -> usize {
        let bytes: Vec<u8> = data.iter().flat_map(|x| x.to_le_bytes()).collect();
        let ty = ["SCALAR", "VEC2", "VEC3"][dims - 1];
        let count = data.len() / dims;
        self.add(&bytes, 34962, |v| {
            format!(
                r#"{{"bufferView":{v},"componentType":5126,"count":{count},"type":"{ty}"{extra}}}"#
            )
        })
    }

    /// Triangle primitives over the given vertex arrays and triangles, one
    /// per material run (`runs`: material and range of `tris`), sharing the
    /// vertex accessors; returns their JSON, comma-separated.
    pub(super) fn primitive(
        &mut self,
        positions: &[Vec3],
        normals: Option<&[Vec3]>,
        uvs: Option<&[Vec2]>,
        tris: &[[u32; 3]],
        runs: Vec<(Option<usize>, std::ops::Range<usize>)>,
    ) -> String {
        let (lo, hi) = positions
            .iter()
            .fold((positions[0], positions[0]), |(l, h), &p| {
                (l.min(p), h.max(p))
            });
        let pos: Vec<f32> = positions.iter().flat_map(|p| p.to_array()).collect();
        let minmax = format!(
            r#","min":[{},{},{}],"max":[{},{},{}]"#,
            lo.x, lo.y, lo.z, hi.x, hi.y, hi.z
        );
        let mut attributes = vec![format!(
            r#""POSITION":{}"#,
            self.add_floats(&pos, 3, &minmax)
        )];
        // glTF's normals are unit vectors; a primitive some of whose
        // vertices carry none (zeros) is written without them, and readers
        // shade it by its triangles' own normals, as we do.
        if let Some(n) = normals.filter(|n| n.iter().all(|v| v.length_squared() > 0.25)) {
            let d: Vec<f32> = n.iter().flat_map(|p| p.to_array()).collect();
            attributes.push(format!(r#""NORMAL":{}"#, self.add_floats(&d, 3, "")));
        }
        if let Some(t) = uvs {
            let d: Vec<f32> = t.iter().flat_map(|p| p.to_array()).collect();
            attributes.push(format!(r#""TEXCOORD_0":{}"#, self.add_floats(&d, 2, "")));
        }
        let attributes = attributes.join(",");
        let mut prims = Vec::new();
        for (material, run) in runs {
            let bytes: Vec<u8> = tris[run.clone()]
                .iter()
                .flatten()
                .flat_map(|i| i.to_le_bytes())
                .collect();
            let count = run.len() * 3;
            let ia = self.add(&bytes, 34963, |v| {
                format!(
                    r#"{{"bufferView":{v},"componentType":5125,"count":{count},"type":"SCALAR"}}"#
                )
            });
            let m = material
                .map(|m| format!(r#","material":{m}"#))
                .unwrap_or_default();
            prims.push(format!(
                r#"{{"attributes":{{{attributes}}},"indices":{ia},"mode":4{m}}}"#
            ));
        }
        prims.join(",")
    }
}

/// Runs of consecutive triangles (indices into `tris` of one part) with the
/// same material, and that material's index (`None` when the mesh has no
/// materials).
pub(super) fn material_runs(
    mesh: &TriangleMesh,
    tris: &[usize],
) -> Vec<(Option<usize>, std::ops::Range<usize>)> {
    let mut runs: Vec<(Option<usize>, std::ops::Range<usize>)> = Vec::new();
    for (k, &t) in tris.iter().enumerate() {
        let m = (!mesh.materials.is_empty())
            .then(|| (mesh.material_of(t) as usize).min(mesh.materials.len() - 1));
        match runs.last_mut() {
            Some((last, r)) if *last == m => r.end = k + 1,
            _ => runs.push((m, k..k + 1)),
        }
    }
    runs
}

/// The triangles of each part that has any, in part order (triangles in mesh
/// order within a part), with the part's index.
fn part_triangles(mesh: &TriangleMesh) -> Vec<(usize, Vec<usize>)> {
    let n_parts = (0..mesh.num_triangles())
        .map(|t| mesh.part_of(t) as usize + 1)
        .max()
        .unwrap_or(0)
        .max(mesh.parts.len());
    let mut groups = vec![Vec::new(); n_parts];
    for t in 0..mesh.num_triangles() {
        groups[mesh.part_of(t) as usize].push(t);
    }
    groups
        .into_iter()
        .enumerate()
        .filter(|(_, g)| !g.is_empty())
        .collect()
}

/// Write `mesh` as GLB (`binary`) or as `.gltf` JSON with the buffer embedded
/// as a base64 data URI.
pub fn write_gltf(w: &mut dyn Write, mesh: &TriangleMesh, binary: bool) -> io::Result<()> {
    write_gltf_scene(w, mesh, None, &[], binary)
}

/// Write `mesh` with a camera and lights (`KHR_lights_punctual`) as GLB
/// (`binary`) or `.gltf`: what `raykit render` reads back as a whole scene.
pub fn write_gltf_scene(
    w: &mut dyn Write,
    mesh: &TriangleMesh,
    camera: Option<&Camera>,
    lights: &[Light],
    binary: bool,
) -> io::Result<()> {
    check(mesh)?;
    let mut buf = Buffers::default();
    let groups = part_triangles(mesh);
    let mut nodes = Vec::with_capacity(groups.len());
    let mut meshes = Vec::with_capacity(groups.len());
    // Old vertex index → index within the part being written; entries are
    // set for a part's vertices before they are read.
    let mut local = Vec::new();
    for (part, tris) in &groups {
        let prim = if groups.len() == 1 {
            buf.primitive(
                &mesh.positions,
                mesh.normals.as_deref(),
                mesh.uvs.as_deref(),
                &mesh.indices,
                material_runs(mesh, tris),
            )
        } else {
            let mut used: Vec<u32> = tris.iter().flat_map(|&t| mesh.indices[t]).collect();
            used.sort_unstable();
            used.dedup();
            local.resize(mesh.positions.len(), 0u32);
            for (k, &v) in used.iter().enumerate() {
                local[v as usize] = k as u32;
            }
            let pick = |a: &[Vec3]| -> Vec<Vec3> { used.iter().map(|&v| a[v as usize]).collect() };
            let positions = pick(&mesh.positions);
            let normals = mesh.normals.as_deref().map(pick);
            let uvs: Option<Vec<Vec2>> = mesh
                .uvs
                .as_ref()
                .map(|a| used.iter().map(|&v| a[v as usize]).collect());
            let local_tris: Vec<[u32; 3]> = tris
                .iter()
                .map(|&t| mesh.indices[t].map(|v| local[v as usize]))
                .collect();
            let runs = material_runs(mesh, tris);
            buf.primitive(
                &positions,
                normals.as_deref(),
                uvs.as_deref(),
                &local_tris,
                runs,
            )
        };
        let name = mesh
            .parts
            .get(*part)
            .map(|p| p.name.as_str())
            .filter(|n| !n.is_empty())
            .map(|n| format!(r#","name":{}"#, json_string(n)))
            .unwrap_or_default();
        nodes.push(format!(r#"{{"mesh":{}{name}}}"#, meshes.len()));
        meshes.push(format!(r#"{{"primitives":[{prim}]{name}}}"#));
    }
    let extras = scene_extras(
        &mesh.materials,
        camera.map(|c| (c, mesh.bounds())),
        lights,
        &mut nodes,
    );
    let roots: Vec<usize> = (0..nodes.len()).collect();
    document(w, buf, &extras, &roots, &nodes, &meshes, binary)
}

/// Write the glTF document: `extras` (from `scene_extras`), the scene of
/// the `roots` nodes, `nodes` and `meshes` as JSON objects, and the
/// accessors, views and buffer of `buf`, as GLB (`binary`) or `.gltf`
/// with the buffer embedded as a base64 data URI.
pub(super) fn document(
    w: &mut dyn Write,
    buf: Buffers,
    extras: &str,
    roots: &[usize],
    nodes: &[String],
    meshes: &[String],
    binary: bool,
) -> io::Result<()> {
    let Buffers {
        mut bin,
        views,
        accessors,
    } = buf;
    let uri = if binary {
        String::new()
    } else {
        format!(
            r#","uri":"data:application/octet-stream;base64,{}""#,
            base64_encode(&bin)
        )
    };
    let roots: Vec<String> = roots.iter().map(|i| i.to_string()).collect();
    let json = format!(
        r#"{{"asset":{{"version":"2.0","generator":"raykit-io"}}{}"scene":0,"scenes":[{{"nodes":[{}]}}],"nodes":[{}],"meshes":[{}],"accessors":[{}],"bufferViews":[{}],"buffers":[{{"byteLength":{}{uri}}}]}}"#,
        extras,
        roots.join(","),
        nodes.join(","),
        meshes.join(","),
        accessors.join(","),
        views.join(","),
        bin.len()
    );
    if !binary {
        return w.write_all(json.as_bytes());
    }
    let mut json = json.into_bytes();
    while !json.len().is_multiple_of(4) {
        json.push(b' ');
    }
    while !bin.len().is_multiple_of(4) {
        bin.push(0);
    }
    let total = 12 + 8 + json.len() + 8 + bin.len();
    let total = u32::try_from(total)
        .map_err(|_| io::Error::new(io::ErrorKind::InvalidInput, "mesh too large for GLB"))?;
    w.write_all(b"glTF")?;
    w.write_all(&2u32.to_le_bytes())?;
    w.write_all(&total.to_le_bytes())?;
    w.write_all(&(json.len() as u32).to_le_bytes())?;
    w.write_all(b"JSON")?;
    w.write_all(&json)?;
    w.write_all(&(bin.len() as u32).to_le_bytes())?;
    w.write_all(b"BIN\0")?;
    w.write_all(&bin)
}
