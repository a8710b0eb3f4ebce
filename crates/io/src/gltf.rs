//! glTF 2.0 (`.gltf` JSON with external or data-URI buffers, and `.glb`).
//!
//! The default scene (or the first scene, or else every root node) is walked
//! from its root nodes; each node's transform (matrix or TRS) is composed with
//! its parents' and applied to positions, and its inverse transpose to
//! normals. Every node with a mesh becomes a [`Part`] (`node: Some(index)`).
//! Primitives of mode TRIANGLES, TRIANGLE_STRIP and TRIANGLE_FAN are loaded;
//! others are skipped with a warning. Primitives over the same vertex
//! accessors share their vertices ([`crate::gltf_shared_vertices`]).
//! Materials take the base colour factor, metallic/roughness, emission
//! (times `KHR_materials_emissive_strength`), transmission, IOR, the
//! base-colour texture URI in `diffuse_texture` (embedded images have no
//! URI and give `None`) and the decoded image in `base_texture`
//! ([`crate::gltf_image`]). Cameras and `KHR_lights_punctual`
//! lights on the walked nodes are collected ([`crate::gltf_scene`]), and
//! unsupported features are named in warnings ([`crate::gltf_support`]).

use crate::error::{ErrorKind, LoadError, Location};
use crate::far_origin::FarOrigin;
use crate::gltf_accessor::{check_fits, read_floats, read_indices};
use crate::gltf_draco::{
    decode_primitive, point_placeholders_at_data, DracoPrimitive, EXTENSION as DRACO_EXTENSION,
};
use crate::gltf_flat_size::FlatSize;
use crate::gltf_glb::{is_glb, split_glb};
use crate::gltf_gpu_instancing::mesh_placements;
use crate::gltf_image::ImageCache;
use crate::gltf_integers::check_integer_range;
use crate::gltf_meshopt::MeshoptViews;
use crate::gltf_node_transforms::local_transforms;
use crate::gltf_scene::{check_scene_indices, SceneCollector};
use crate::gltf_shared_vertices::vertex_key;
use crate::gltf_support::{check_required, unsupported_warnings};
use crate::input::available_memory;
use crate::uri::{data_uri_payload, external_file, read_external};
use crate::validate::finish;
use ::gltf::mesh::Mode;
use ::gltf::{Document, Semantic};
use raykit_core::glam::{DMat4, DVec3, Mat3, Mat4};
use raykit_core::{Camera, Light, Material, Part, Texture, TriangleMesh, Vec2, Vec3};
use std::borrow::Cow;
use std::collections::HashMap;
use std::path::Path;
use std::rc::Rc;
use std::sync::Arc;

/// What a glTF file gives: geometry, lights, camera and warnings.
pub(crate) struct GltfScene {
    /// All mesh instances in world space.
    pub mesh: TriangleMesh,
    /// Lights of the walked nodes, in traversal order.
    pub lights: Vec<Light>,
    /// The first perspective camera.
    pub camera: Option<Camera>,
    /// Things skipped or approximated.
    pub warnings: Vec<String>,
    /// Whether the file was GLB.
    pub glb: bool,
}

/// A parsed glTF document with its buffers loaded.
pub(crate) struct OpenedGltf<'a> {
    pub doc: Document,
    /// Each node's own transform, in `f64` ([`crate::gltf_node_transforms`]).
    pub locals: Vec<DMat4>,
    pub buffers: Vec<Cow<'a, [u8]>>,
    pub warnings: Vec<String>,
    pub glb: bool,
}

/// Split a GLB, parse and validate the JSON and load the buffers of the
/// glTF or GLB file `data` read from `path`.
pub(crate) fn open_gltf<'a>(path: &Path, data: &'a [u8]) -> Result<OpenedGltf<'a>, LoadError> {
    let glb = is_glb(data);
    let (json, bin, mut warnings) = if glb {
        let (g, w) = split_glb(path, data)?;
        (g.json, g.bin, w)
    } else {
        (data, None, Vec::new())
    };
    let (doc, meshopt) = parse_document(path, json, glb)?;
    let locals = local_transforms(&doc, json);
    warnings.extend(unsupported_warnings(doc.as_json()));
    let mut buffers = load_buffers(path, &doc, bin, &meshopt.empty)?;
    meshopt.decode(path, &mut buffers)?;
    Ok(OpenedGltf {
        doc,
        locals,
        buffers,
        warnings,
        glb,
    })
}

/// Parse the glTF or GLB file `data` read from `path`.
/// Vertices, lights and camera are stored relative to the origin that
/// `far` chooses at the first vertex placed.
pub(crate) fn parse_gltf(
    path: &Path,
    data: &[u8],
    far: &mut FarOrigin,
) -> Result<GltfScene, LoadError> {
    let OpenedGltf {
        doc,
        locals,
        buffers,
        mut warnings,
        glb,
    } = open_gltf(path, data)?;
    let mut b = Builder::new(path, &doc, &buffers, data.len(), &mut warnings);
    b.far = *far;
    // Every placement is found and the flattened size checked before any
    // mesh is copied. Cameras and lights are placed once the first vertex
    // has chosen the origin.
    let mut placements = Vec::new();
    let mut walked = Vec::new();
    let mut size = FlatSize::default();
    let mut checked = std::collections::HashSet::new();
    walk_nodes(path, &doc, &locals, &mut |node, world| {
        walked.push((node.index(), *world));
        if let Some(mesh) = node.mesh() {
            if checked.insert(mesh.index()) {
                // A Draco primitive's accessors are sized by its decoded
                // data, not by a buffer view.
                let plain = mesh
                    .primitives()
                    .filter(|p| p.extension_value(DRACO_EXTENSION).is_none());
                for prim in plain {
                    let accessors = [prim.get(&Semantic::Positions), prim.indices()];
                    for acc in accessors.iter().flatten() {
                        check_fits(path, acc, &buffers)?;
                    }
                }
            }
            let placed = mesh_placements(path, &doc, &buffers, data.len(), node, world)?;
            size.add_copies(FlatSize::of_mesh(&mesh), placed.len() as u64);
            placements.extend(placed.into_iter().map(|m| (node.clone(), mesh.clone(), m)));
        }
        Ok(())
    })?;
    size.check(path, placements.len(), available_memory())?;
    for (node, mesh, world) in &placements {
        b.add_instance(node, mesh, world)?;
    }
    *far = b.far;
    let origin = DVec3::from_array(far.origin());
    for (index, world) in &walked {
        b.scene
            .visit(doc.as_json(), *index, &stored_relative(world, origin));
    }
    let (mesh, scene) = b.finish();
    warnings.extend(scene.warnings());
    let mesh = finish(path, mesh, Location::Json("scene".into()))?;
    Ok(GltfScene {
        mesh,
        lights: scene.lights,
        camera: scene.camera,
        warnings,
        glb,
    })
}

/// Walk the default scene (or the first scene, or else every root node)
/// depth first, children in order, calling `visit` with each node and its
/// world transform (its own composed with its parents'). A node reached
/// twice (two parents, listed twice, a cycle) is an error naming it. The
/// transforms are composed in `f64` from `locals`, each node's own
/// ([`OpenedGltf::locals`]).
pub(crate) fn walk_nodes<'a>(
    path: &Path,
    doc: &'a Document,
    locals: &[DMat4],
    visit: &mut dyn FnMut(&::gltf::Node<'a>, &DMat4) -> Result<(), LoadError>,
) -> Result<(), LoadError> {
    let n_nodes = doc.nodes().len();
    let roots: Vec<::gltf::Node<'a>> = match doc.default_scene().or_else(|| doc.scenes().next()) {
        Some(scene) => scene.nodes().collect(),
        None => {
            let mut is_child = vec![false; n_nodes];
            for node in doc.nodes() {
                for c in node.children() {
                    is_child[c.index()] = true;
                }
            }
            doc.nodes().filter(|n| !is_child[n.index()]).collect()
        }
    };
    let mut stack: Vec<(::gltf::Node<'a>, DMat4)> = roots
        .into_iter()
        .rev()
        .map(|n| (n, DMat4::IDENTITY))
        .collect();
    // glTF 2.0's nodes form disjoint trees: a node reached twice (a child
    // of two nodes, listed twice, or in a cycle) is refused, since walking
    // it again could copy a mesh exponentially often.
    let mut reached = vec![false; n_nodes];
    while let Some((node, parent)) = stack.pop() {
        if std::mem::replace(&mut reached[node.index()], true) {
            return Err(LoadError::at_json(
                path,
                format!("nodes[{}]", node.index()),
                "the node is reached twice (a child of two nodes, listed twice in the scene, or in a \
                 cycle); glTF nodes form disjoint trees",
            ));
        }
        let world = parent * locals[node.index()];
        visit(&node, &world)?;
        let children: Vec<_> = node.children().collect();
        for c in children.into_iter().rev() {
            stack.push((c, world));
        }
    }
    Ok(())
}

/// Deserialize and validate the JSON. The `gltf` crate's validation indexes
/// the POSITION accessor without a bounds check, so that index is checked
/// first, as are unsupported required extensions and camera and light
/// indices (for clearer messages); any other panic inside the crate's
/// validation is turned into an error as a last line of defence.
fn parse_document(
    path: &Path,
    json: &[u8],
    glb: bool,
) -> Result<(Document, MeshoptViews), LoadError> {
    let mut root = ::gltf::json::Root::from_slice(json)
        .map_err(|e| json_error(path, ::gltf::Error::Deserialize(e), glb))?;
    check_integer_range(path, json, glb)?;
    check_required(path, &root)?;
    // The gltf crate's validator refuses every required extension it does
    // not know, KHR_mesh_quantization among them, which the loader handles
    // itself (its integer attributes are read by `gltf_accessor`).
    root.extensions_required
        .retain(|e| ::gltf::json::extensions::ENABLED_EXTENSIONS.contains(&e.as_str()));
    point_placeholders_at_data(path, &mut root)?;
    let meshopt = MeshoptViews::plan(path, &mut root, available_memory().unwrap_or(u64::MAX))?;
    check_scene_indices(path, &root)?;
    let positions = ::gltf::json::validation::Checked::Valid(Semantic::Positions);
    for (m, mesh) in root.meshes.iter().enumerate() {
        for (p, prim) in mesh.primitives.iter().enumerate() {
            if let Some(a) = prim.attributes.get(&positions) {
                if a.value() >= root.accessors.len() {
                    return Err(LoadError::at_json(
                        path,
                        format!("meshes[{m}].primitives[{p}].attributes.POSITION"),
                        format!(
                            "accessor index {} is out of range (the file has {} accessors)",
                            a.value(),
                            root.accessors.len()
                        ),
                    ));
                }
            }
        }
    }
    let validated =
        std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| Document::from_json(root)));
    match validated {
        Ok(r) => r
            .map(|d| (d, meshopt))
            .map_err(|e| json_error(path, e, glb)),
        Err(_) => Err(LoadError::at_json(
            path,
            "document",
            "the glTF validator failed on this file",
        )),
    }
}

fn json_error(path: &Path, e: ::gltf::Error, glb: bool) -> LoadError {
    match e {
        ::gltf::Error::Deserialize(e) => {
            let loc = if glb {
                Location::Json(format!(
                    "JSON chunk line {} column {}",
                    e.line(),
                    e.column()
                ))
            } else {
                Location::Line(e.line().max(1))
            };
            LoadError::new(
                path,
                ErrorKind::Malformed,
                loc,
                format!("not valid glTF JSON: {e}"),
            )
        }
        ::gltf::Error::Validation(errs) => {
            let more = match errs.len() {
                0 | 1 => String::new(),
                n => format!(" (and {} more problems)", n - 1),
            };
            let (element, what) = match errs.first() {
                Some((p, e)) => (p.to_string(), e.to_string()),
                None => ("document".to_string(), "invalid".to_string()),
            };
            let kind = match errs.first() {
                Some((_, ::gltf::json::validation::Error::Unsupported)) => ErrorKind::Unsupported,
                _ => ErrorKind::Malformed,
            };
            LoadError::new(
                path,
                kind,
                Location::Json(element),
                format!("invalid glTF: {what}{more}"),
            )
        }
        e => LoadError::new(path, ErrorKind::Malformed, Location::File, e.to_string()),
    }
}

fn load_buffers<'a>(
    path: &Path,
    doc: &Document,
    bin: Option<&'a [u8]>,
    empty: &[bool],
) -> Result<Vec<Cow<'a, [u8]>>, LoadError> {
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut out = Vec::new();
    for buf in doc.buffers() {
        let i = buf.index();
        if empty.get(i) == Some(&true) {
            // A meshopt fallback buffer, or one made for decoded bytes.
            out.push(Cow::Borrowed(&[][..]));
            continue;
        }
        let data: Cow<'a, [u8]> = match buf.source() {
            ::gltf::buffer::Source::Bin => Cow::Borrowed(bin.ok_or_else(|| {
                LoadError::at_json(
                    path,
                    format!("buffers[{i}]"),
                    "refers to the GLB BIN chunk, but there is none",
                )
            })?),
            ::gltf::buffer::Source::Uri(uri) if uri.starts_with("data:") => {
                let payload = data_uri_payload(uri).unwrap_or(Ok(Vec::new()));
                Cow::Owned(payload.map_err(|at| {
                    LoadError::at_json(
                        path,
                        format!("buffers[{i}].uri"),
                        format!("invalid base64 at character {} of the data", at),
                    )
                })?)
            }
            ::gltf::buffer::Source::Uri(uri) => {
                let at = || Location::Json(format!("buffers[{i}].uri"));
                let file = external_file(dir, uri)
                    .map_err(|m| LoadError::new(path, ErrorKind::Malformed, at(), m))?;
                // The buffer is its first byteLength bytes.
                Cow::Owned(
                    read_external(&file, buf.length() as u64)
                        .map_err(|m| LoadError::new(path, ErrorKind::Io, at(), m))?,
                )
            }
        };
        if data.len() < buf.length() {
            return Err(LoadError::at_json(
                path,
                format!("buffers[{i}]"),
                format!(
                    "has {} bytes of data, but byteLength says {} (truncated?)",
                    data.len(),
                    buf.length()
                ),
            ));
        }
        out.push(data);
    }
    Ok(out)
}

/// Collects the triangles of the mesh nodes into one mesh.
pub(crate) struct Builder<'a, 'b> {
    path: &'a Path,
    doc: &'a Document,
    buffers: &'a [Cow<'b, [u8]>],
    limit: usize,
    mesh: TriangleMesh,
    normals: Vec<Vec3>,
    uvs: Vec<Vec2>,
    /// Whether any primitive had normals / texture coordinates: the
    /// vertices of primitives without them hold zeros (a zero normal means
    /// "use the triangle's own", as [`TriangleMesh::append`] fills them).
    any_normals: bool,
    any_uvs: bool,
    /// Our material index per glTF material (last entry: the default material).
    material_of: Vec<Option<u32>>,
    /// Decoded base-colour images.
    images: ImageCache,
    /// Lights and camera met on the walk.
    scene: SceneCollector,
    /// Draco-compressed primitives by (mesh, primitive), decoded once
    /// however many nodes place them.
    draco: HashMap<(usize, usize), Option<Rc<DracoPrimitive>>>,
    /// The origin the vertices are stored relative to, chosen at the first
    /// vertex (zero unless asked to keep the precision of far scenes).
    pub(crate) far: FarOrigin,
    warnings: &'a mut Vec<String>,
}

impl<'a, 'b> Builder<'a, 'b> {
    /// A builder of one mesh from `doc`'s meshes (`limit`: the file size,
    /// bounding accessor reads).
    pub(crate) fn new(
        path: &'a Path,
        doc: &'a Document,
        buffers: &'a [Cow<'b, [u8]>],
        limit: usize,
        warnings: &'a mut Vec<String>,
    ) -> Self {
        Builder {
            path,
            doc,
            buffers,
            limit,
            mesh: TriangleMesh::default(),
            normals: Vec::new(),
            uvs: Vec::new(),
            any_normals: false,
            any_uvs: false,
            material_of: vec![None; doc.materials().len() + 1],
            images: ImageCache::new(doc.images().len()),
            scene: SceneCollector::default(),
            draco: HashMap::new(),
            far: FarOrigin::new(false),
            warnings,
        }
    }

    /// Append the primitives of `mesh`, placed by `node`'s world transform
    /// `world`, as one part, relative to the builder's origin.
    pub(crate) fn add_instance(
        &mut self,
        node: &::gltf::Node<'_>,
        mesh: &::gltf::Mesh<'_>,
        world: &DMat4,
    ) -> Result<(), LoadError> {
        let part = self.mesh.parts.len() as u32;
        self.mesh.parts.push(Part {
            name: node.name().or(mesh.name()).unwrap_or("").to_string(),
            node: Some(node.index() as u32),
        });
        let m3 = Mat3::from_mat4(world.as_mat4());
        let inv_t = m3.inverse().transpose();
        let normal_m = if inv_t.is_finite() { inv_t } else { m3 };
        let flip = m3.determinant() < 0.0;
        let mut shared = HashMap::new();
        for prim in mesh.primitives() {
            let pname = format!("meshes[{}].primitives[{}]", mesh.index(), prim.index());
            let mode = prim.mode();
            if !matches!(
                mode,
                Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan
            ) {
                self.warnings.push(format!(
                    "{pname} (node {}): mode {mode:?} skipped; only triangles, strips and fans are loaded",
                    node.index()
                ));
                continue;
            }
            let Some(pos_acc) = prim.get(&Semantic::Positions) else {
                self.warnings
                    .push(format!("{pname}: no POSITION attribute; skipped"));
                continue;
            };
            let (path, bufs, limit) = (self.path, self.buffers, self.limit);
            // Positions are floats unless the file uses the extension that
            // quantizes them.
            let quantized = self
                .doc
                .extensions_used()
                .any(|e| e == "KHR_mesh_quantization");
            let ty = pos_acc.data_type();
            if ty != ::gltf::accessor::DataType::F32 && !quantized {
                return Err(LoadError::at_json(
                    path,
                    format!("accessors[{}]", pos_acc.index()),
                    format!(
                        "POSITION has component type {ty:?}; without KHR_mesh_quantization in \
                         extensionsUsed it must be F32"
                    ),
                ));
            }
            let key = (mesh.index(), prim.index());
            let draco = match self.draco.get(&key) {
                Some(d) => d.clone(),
                None => {
                    let d = decode_primitive(path, self.doc, bufs, &prim, &pname)?.map(Rc::new);
                    self.draco.insert(key, d.clone());
                    d
                }
            };
            let mode = if draco.is_some() {
                Mode::Triangles
            } else {
                mode
            };
            // Primitives over the vertex arrays of one read earlier in this
            // placement reuse its vertices (`gltf_shared_vertices`).
            let key = draco.as_ref().map_or_else(|| vertex_key(&prim), |_| None);
            let (base, nv, idx) = match key.and_then(|k| shared.get(&k).copied()) {
                Some((base, nv)) => {
                    let idx = match prim.indices() {
                        Some(acc) => read_indices(path, &acc, bufs, limit)?,
                        None => (0..nv as u32).collect(),
                    };
                    (base, nv, idx)
                }
                None => {
                    let (base, nv, idx) =
                        self.read_vertices(&prim, &pos_acc, draco, node, world, normal_m, &pname)?;
                    if let Some(k) = key {
                        shared.insert(k, (base, nv));
                    }
                    (base, nv, idx)
                }
            };
            if let Some((k, &i)) = idx.iter().enumerate().find(|(_, &i)| i as usize >= nv) {
                return Err(LoadError::at_json(
                    path,
                    format!("{pname}.indices"),
                    format!(
                        "index {i} at position {k} is out of range (POSITION has {nv} vertices)"
                    ),
                ));
            }
            let before = self.mesh.indices.len();
            let mut push = |a: u32, b: u32, c: u32| {
                let t = if flip { [a, c, b] } else { [a, b, c] };
                self.mesh.indices.push(t.map(|i| i + base));
            };
            match mode {
                Mode::Triangles => {
                    if idx.len() % 3 != 0 {
                        let what = if prim.indices().is_some() {
                            "indices"
                        } else {
                            "vertices (POSITION)"
                        };
                        self.warnings.push(format!(
                            "{pname}: {} {what}, not a multiple of 3 as TRIANGLES requires; the \
                             last {} ignored",
                            idx.len(),
                            idx.len() % 3
                        ));
                    }
                    for t in idx.chunks_exact(3) {
                        push(t[0], t[1], t[2]);
                    }
                }
                Mode::TriangleStrip => {
                    for k in 0..idx.len().saturating_sub(2) {
                        if k % 2 == 0 {
                            push(idx[k], idx[k + 1], idx[k + 2]);
                        } else {
                            push(idx[k + 1], idx[k], idx[k + 2]);
                        }
                    }
                }
                _ => {
                    for k in 1..idx.len().saturating_sub(1) {
                        push(idx[0], idx[k], idx[k + 1]);
                    }
                }
            }
            let added = self.mesh.indices.len() - before;
            let mat = self.material(&prim.material());
            self.mesh
                .tri_material
                .extend(std::iter::repeat_n(mat, added));
            self.mesh.tri_part.extend(std::iter::repeat_n(part, added));
        }
        Ok(())
    }

    /// Read the vertices of `prim` (decoded from `draco` when compressed),
    /// placed by `world`, and append them to the mesh: returns the index of
    /// the first, their count and the primitive's indices.
    #[allow(clippy::too_many_arguments)]
    fn read_vertices(
        &mut self,
        prim: &::gltf::Primitive<'_>,
        pos_acc: &::gltf::Accessor<'_>,
        draco: Option<Rc<DracoPrimitive>>,
        node: &::gltf::Node<'_>,
        world: &DMat4,
        normal_m: Mat3,
        pname: &str,
    ) -> Result<(u32, usize, Vec<u32>), LoadError> {
        let (path, bufs, limit) = (self.path, self.buffers, self.limit);
        let (pos, normals, uvs, idx) = match draco {
            Some(d) => (
                d.positions.clone(),
                d.normals.clone(),
                d.uvs.clone(),
                d.indices.clone(),
            ),
            None => {
                let pos = read_floats(path, pos_acc, bufs, 3, limit)?;
                let nv = pos.len() / 3;
                let attr = |sem: Semantic,
                            dims: usize,
                            what: &str|
                 -> Result<Option<Vec<f32>>, LoadError> {
                    let Some(acc) = prim.get(&sem) else {
                        return Ok(None);
                    };
                    let v = read_floats(path, &acc, bufs, dims, limit)?;
                    if v.len() != nv * dims {
                        return Err(LoadError::at_json(
                            path,
                            format!("{pname}.attributes.{what}"),
                            format!("has {} elements, but POSITION has {nv}", v.len() / dims),
                        ));
                    }
                    Ok(Some(v))
                };
                let normals = attr(Semantic::Normals, 3, "NORMAL")?;
                let uvs = attr(Semantic::TexCoords(0), 2, "TEXCOORD_0")?;
                let idx = match prim.indices() {
                    Some(acc) => read_indices(path, &acc, bufs, limit)?,
                    None => (0..nv as u32).collect(),
                };
                (pos, normals, uvs, idx)
            }
        };
        let nv = pos.len() / 3;
        let base = self.mesh.positions.len() as u32;
        if let Some(p) = pos.first_chunk::<3>() {
            let first = world.transform_point3(DVec3::from_array(p.map(f64::from)));
            self.far.origin_for(first.to_array());
        }
        let world = stored_relative(world, DVec3::from_array(self.far.origin()));
        for (j, p) in pos.chunks_exact(3).enumerate() {
            let w = world.transform_point3(Vec3::new(p[0], p[1], p[2]));
            if !w.is_finite() {
                return Err(LoadError::at_json(
                    path,
                    format!("accessors[{}]", pos_acc.index()),
                    format!(
                        "vertex {j} is NaN or infinite after the transform of nodes[{}]",
                        node.index()
                    ),
                ));
            }
            self.mesh.positions.push(w);
        }
        match normals {
            Some(n) => {
                self.any_normals = true;
                self.normals.extend(
                    n.chunks_exact(3)
                        .map(|c| (normal_m * Vec3::new(c[0], c[1], c[2])).normalize_or_zero()),
                )
            }
            None => self.normals.resize(self.mesh.positions.len(), Vec3::ZERO),
        }
        match uvs {
            Some(t) => {
                self.any_uvs = true;
                self.uvs
                    .extend(t.chunks_exact(2).map(|c| Vec2::new(c[0], c[1])))
            }
            None => self.uvs.resize(self.mesh.positions.len(), Vec2::ZERO),
        }
        Ok((base, nv, idx))
    }

    /// Our index of the glTF material `m`, converting it on first use.
    fn material(&mut self, m: &::gltf::Material<'_>) -> u32 {
        let slot = m.index().unwrap_or(self.material_of.len() - 1);
        if let Some(i) = self.material_of[slot] {
            return i;
        }
        let i = self.mesh.materials.len() as u32;
        let mat = match m.index() {
            None => Material::default(),
            Some(k) => {
                let texture = self.base_texture(m);
                convert_material(self.doc, m, k, texture)
            }
        };
        self.mesh.materials.push(mat);
        self.material_of[slot] = Some(i);
        i
    }

    /// The decoded base-colour texture of `m`, if it has one using texture
    /// coordinate set 0 and its image can be read.
    fn base_texture(&mut self, m: &::gltf::Material<'_>) -> Option<Arc<Texture>> {
        let info = m.pbr_metallic_roughness().base_color_texture()?;
        if info.tex_coord() != 0 {
            return None; // Named in the unsupported-feature warnings.
        }
        let json = self.doc.as_json();
        let image = json.textures.get(info.texture().index())?.source.value();
        self.images
            .get(self.path, json, self.buffers, image, self.warnings)
    }

    /// The mesh collected and the lights and camera met.
    pub(crate) fn finish(mut self) -> (TriangleMesh, SceneCollector) {
        if self.any_normals && !self.mesh.positions.is_empty() {
            self.mesh.normals = Some(self.normals);
        }
        if self.any_uvs && !self.mesh.positions.is_empty() {
            self.mesh.uvs = Some(self.uvs);
        }
        (self.mesh, self.scene)
    }
}

/// `world` (composed in `f64`) followed by a move by `-origin`, rounded to
/// `f32` once: what places a node's vertices, camera and lights in stored
/// coordinates.
fn stored_relative(world: &DMat4, origin: DVec3) -> Mat4 {
    (DMat4::from_translation(-origin) * *world).as_mat4()
}

fn convert_material(
    doc: &Document,
    m: &::gltf::Material<'_>,
    index: usize,
    base_texture: Option<Arc<Texture>>,
) -> Material {
    let pbr = m.pbr_metallic_roughness();
    // Factors outside the ranges glTF allows are clamped into them (a number
    // beyond f32 reads as infinite): colours and fractions to [0, 1], the
    // index of refraction to [1, 10] (0 to 10, see below), emission to
    // finite non-negative values.
    let unit = |x: f32| if x.is_nan() { 0.0 } else { x.clamp(0.0, 1.0) };
    let [r, g, b, _] = pbr.base_color_factor().map(unit);
    let metallic = pbr.metallic_factor().clamp(0.0, 1.0);
    let rough = pbr.roughness_factor().clamp(0.0, 1.0);
    let lerp = |c: f32| 0.04 + (c - 0.04) * metallic;
    // Blinn-Phong exponent with the same lobe width as GGX roughness.
    let a2 = (rough * rough * rough * rough).max(1e-4);
    let strength = m.emissive_strength().unwrap_or(1.0);
    let strength = if strength.is_finite() {
        strength.max(0.0)
    } else {
        1.0
    };
    let json = doc.as_json();
    let texture = pbr
        .base_color_texture()
        .and_then(|info| json.textures.get(info.texture().index()))
        .and_then(|t| json.images.get(t.source.value()))
        .and_then(|img| img.uri.clone());
    let mut out = Material {
        name: m
            .name()
            .map(str::to_string)
            .unwrap_or_else(|| format!("material{index}")),
        diffuse: [r, g, b],
        specular: [lerp(r), lerp(g), lerp(b)],
        shininess: (2.0 / a2 - 2.0).clamp(0.0, 1e4),
        reflectivity: metallic,
        transmission: m
            .transmission()
            .map(|t| unit(t.transmission_factor()))
            .unwrap_or(0.0),
        // `ior` 0 means an infinite index (a fully reflective Fresnel), read
        // as the largest index kept, 10.
        ior: m.ior().filter(|i| i.is_finite()).map_or(1.5, |i| {
            if i == 0.0 {
                10.0
            } else {
                i.clamp(1.0, 10.0)
            }
        }),
        emission: m
            .emissive_factor()
            .map(|e| (unit(e) * strength).min(f32::MAX)),
        diffuse_texture: texture,
        base_texture,
    };
    apply_phong_extras(&mut out, m);
    out
}

/// Name of the material `extras` member in which raykit keeps its exact
/// Phong parameters, so that its own glTF output reads back unchanged.
pub(crate) const PHONG_EXTRAS: &str = "raykit_phong";

/// Override the metallic-roughness conversion with the exact Phong
/// parameters `extras.raykit_phong` holds (written by raykit's glTF writer):
/// `diffuse` and `specular` as 3 numbers, `shininess` and `reflectivity`.
/// Missing or malformed members keep the converted values.
fn apply_phong_extras(out: &mut Material, m: &::gltf::Material<'_>) {
    let Some(raw) = m.extras() else {
        return;
    };
    let Ok(v) = ::gltf::json::deserialize::from_str::<::gltf::json::Value>(raw.get()) else {
        return;
    };
    let Some(p) = v.get(PHONG_EXTRAS) else {
        return;
    };
    let num = |k: &str| {
        p.get(k)
            .and_then(|x| x.as_f64())
            .map(|x| x as f32)
            .filter(|x| x.is_finite())
    };
    let rgb = |k: &str| -> Option<[f32; 3]> {
        let a = p.get(k)?.as_array()?;
        let c: Vec<f32> = a
            .iter()
            .filter_map(|x| x.as_f64())
            .map(|x| x as f32)
            .collect();
        (c.len() == 3 && c.iter().all(|x| x.is_finite())).then(|| [c[0], c[1], c[2]])
    };
    if let Some(c) = rgb("diffuse") {
        out.diffuse = c.map(|x| x.clamp(0.0, 1.0));
    }
    if let Some(c) = rgb("specular") {
        out.specular = c.map(|x| x.clamp(0.0, 1.0));
    }
    if let Some(x) = num("shininess") {
        out.shininess = x.clamp(0.0, 1e4);
    }
    if let Some(x) = num("reflectivity") {
        out.reflectivity = x.clamp(0.0, 1.0);
    }
}
