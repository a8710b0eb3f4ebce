//! Saved wide BVHs ([`super::Bvh4`], [`super::Bvh8`]): a versioned binary
//! file that loads without a build, checked field by field.
//!
//! The file is the tree's own memory — inner nodes and, over
//! [`crate::tri::Moller`], the packs of four precomputed triangles — so a
//! load is one read per array, a checksum pass and an O(n) check of the
//! topology; over the other triangle tests the leaves hold triangle
//! indices and their precomputed triangles are remade from the mesh.
//! [`WideBvh::load`] reads the file into the tree's arrays (huge pages where
//! the system offers them, as a built tree's); [`WideBvh::load_mapped`] maps
//! the leaf packs from the file instead, which saves the copy (see
//! BENCHMARKS.md for both) on the condition that the file is left alone
//! while the tree lives. Every array starts at a multiple of 64 bytes in
//! the file, so that it can be used in place.
//!
//! Layout, every number little-endian (`u32`, `u64`, `f32`, `f64`):
//!
//! | offset | size | field |
//! |-------:|-----:|-------|
//! | 0  | 8 | magic bytes `RAYKITBV` |
//! | 8  | 4 | format version ([`FORMAT_VERSION`]) |
//! | 12 | 4 | byte-order mark `0x01020304` (bytes `04 03 02 01`) |
//! | 16 | 4 | structure: 4 = bvh4, 8 = bvh8 |
//! | 20 | 4 | triangle test: 0 = moller, 1 = plucker, 2 = projection |
//! | 24 | 4 | bytes per inner node (128 or 256) |
//! | 28 | 4 | bytes per leaf unit (192 per pack of four, 4 per index) |
//! | 32 | 4 | leaf form: 1 = packs of four, 2 = triangle indices |
//! | 36 | 4 | reserved, 0 |
//! | 40 | 8 | triangles of the mesh |
//! | 48 | 8 | vertices of the mesh |
//! | 56 | 4 | CRC-32 of the mesh: positions (3 `f32` each), then indices (3 `u32` each) |
//! | 60 | 4 | CRC-32 of the payload (bytes 96 to the end) |
//! | 64 | 8 | inner nodes |
//! | 72 | 8 | leaf units |
//! | 80 | 8 | payload bytes |
//! | 88 | 4 | CRC-32 of bytes 0..88 |
//! | 92 | 4 | reserved, 0 |
//! | 96 | 96 | root reference (index, count: `u32`), root box (min, max: 6 `f32`), SAH cost as built (`f64`), SAH cost now (`f64`), the scale the tree was built at ([`UnitScale`]: its factor as two `f32` powers of two, then the offset as three `f32`; one and zero for a tree over the mesh as given, all zero in files that predate it), 28 bytes 0 |
//! | 192 | nodes × node bytes | inner nodes: per node the slot boxes as six rows (min x, max x, min y, max y, min z, max z) of one `f32` per slot, then per slot the child reference (index, count: `u32`; `u32::MAX, 0` for an unused slot; count 0 for an inner node, else a leaf of count triangles) |
//! | … | units × unit bytes | packs of four triangles (first corners, first edges, second edges as three rows of four `f32` each, the edges' largest components (two rows of four `f32`), the mesh triangle per lane (`u32`, `u32::MAX` unused)), or the mesh triangle of each leaf position (`u32`) |
//!
//! The checksums are CRC-32 (IEEE, `crc32fast`), which detects every error
//! burst of up to 32 bits and all but 2^-32 of the others. A file is
//! refused with a [`PersistError::Invalid`] naming the offset and field
//! when it is truncated or longer than its header says, is not a raykit
//! BVH file, has another version, byte order, structure, triangle test or
//! record size, belongs to another mesh, fails a checksum, or describes a
//! tree that is not one (a child before its parent, a node with two
//! parents, a reference out of range, a tree too deep for the traversal
//! stack). Files are written to a temporary file beside the target and
//! renamed over it.

use super::node_width::NodeWidth;
use super::persist_error::PersistError;
use super::refit::{check_mesh, left_out, stored_sah};
use super::tri4::{never_hit, Tri4, Tri4Leaves, Unhittable};
use super::wide_bvh::WideBvh;
use super::wide_leaf::Leaves;
use super::wide_node::Child4;
use super::wide_parts::{words_of_mut, zeroed, PartsOwned, PartsRef, WideNode, WideParts};
use super::words::{bytes_of, bytes_of_mut, Words};
use crate::accel::leaf::LeafTriangles;
use crate::accel::node_box::NodeBox;
use crate::accel::{AccelKind, AccelStats};
use crate::mesh::TriangleMesh;
use crate::tri::{Moller, TestKind, TriangleTest};
use crate::unit_scale::UnitScale;
use glam::Vec3;
use rayon::prelude::*;
use std::borrow::Cow;
use std::fs::File;
use std::io::{BufWriter, Read, Write};
use std::path::Path;

/// The file's first eight bytes.
pub const MAGIC: [u8; 8] = *b"RAYKITBV";

/// The format version this build writes and reads.
pub const FORMAT_VERSION: u32 = 1;

/// The byte-order mark, written little-endian.
const BYTE_ORDER: u32 = 0x0102_0304;

/// Bytes of the header.
const HEADER: usize = 96;

/// Bytes of the payload's first record (root, root box, SAH costs, then
/// zeros), so that the arrays after it start at byte 192, a multiple of
/// their 64-byte alignment (for [`WideBvh::load_mapped`]).
const META: usize = 96;

/// Leaf form code: packs of four Möller triangles.
const FORM_PACKED: u32 = 1;

/// Leaf form code: triangle indices in leaf order.
const FORM_SINGLE: u32 = 2;

/// Builds [`PersistError::Invalid`] for one file.
struct Fault<'a>(&'a Path);

impl Fault<'_> {
    fn at(&self, offset: u64, field: &'static str, reason: impl Into<String>) -> PersistError {
        PersistError::Invalid {
            path: self.0.to_path_buf(),
            offset,
            field,
            reason: reason.into(),
        }
    }

    fn io(&self, source: std::io::Error) -> PersistError {
        PersistError::Io {
            path: self.0.to_path_buf(),
            source,
        }
    }
}

// SAFETY: glam's `Vec3` is `repr(C)` with three `f32` (12 bytes, checked).
unsafe impl Words for Vec3 {}
const _: () = assert!(std::mem::size_of::<Vec3>() == 12);
// SAFETY: three `u32`.
unsafe impl Words for [u32; 3] {}

/// The little-endian bytes of `v`: its own on little-endian hosts.
fn le_bytes<W: Words>(v: &[W]) -> Cow<'_, [u8]> {
    if cfg!(target_endian = "little") {
        Cow::Borrowed(bytes_of(v))
    } else {
        let mut copy = v.to_vec();
        for w in words_of_mut(&mut copy) {
            *w = w.to_le();
        }
        Cow::Owned(bytes_of(&copy).to_vec())
    }
}

/// Turn words read little-endian into the host's order.
fn from_le<W: Words>(v: &mut [W]) {
    if cfg!(target_endian = "big") {
        for w in words_of_mut(v) {
            *w = u32::from_le(*w);
        }
    }
}

/// CRC-32 of the mesh's positions and indices, as stored in the header.
fn mesh_crc(mesh: &TriangleMesh) -> u32 {
    let mut h = crc32fast::Hasher::new();
    h.update(&le_bytes(&mesh.positions));
    h.update(&le_bytes(&mesh.indices));
    h.finalize()
}

/// The structure code of the header.
fn kind_code(kind: AccelKind) -> u32 {
    match kind {
        AccelKind::Bvh4 => 4,
        AccelKind::Bvh8 => 8,
        _ => 0,
    }
}

/// The triangle test code of the header.
fn test_code<T: TriangleTest>() -> u32 {
    TestKind::ALL
        .iter()
        .position(|k| k.name() == T::NAME)
        .expect("every test is in TestKind::ALL") as u32
}

/// The name behind a structure code, for messages.
fn kind_name(code: u32) -> String {
    match code {
        4 => "bvh4".into(),
        8 => "bvh8".into(),
        c => format!("unknown structure code {c}"),
    }
}

/// The name behind a test code, for messages.
fn test_name(code: u32) -> String {
    match TestKind::ALL.get(code as usize) {
        Some(k) => k.name().into(),
        None => format!("unknown triangle test code {code}"),
    }
}

/// The leaf form, unit size and unit count of a tree's leaves.
fn leaf_layout<T: TriangleTest>(leaves: &Leaves<T>) -> (u32, usize, usize) {
    match leaves {
        Leaves::Packed(p) => (FORM_PACKED, std::mem::size_of::<Tri4>(), p.packs().len()),
        Leaves::Single(t) => (FORM_SINGLE, 4, t.len()),
    }
}

/// The header and payload record of `p`, over a mesh with checksum `mesh`.
fn header_and_meta<N: WideNode, T: TriangleTest>(
    kind: AccelKind,
    p: &PartsRef<'_, N, T>,
    mesh: &TriangleMesh,
    built_sah: f64,
    scale: UnitScale,
) -> ([u8; HEADER], [u8; META], usize) {
    let (form, unit_bytes, units) = leaf_layout(p.leaves);
    let node_bytes = std::mem::size_of::<N>();
    let payload = META + std::mem::size_of_val(p.nodes) + units * unit_bytes;
    let mut meta = [0u8; META];
    let mut m = Cursor(&mut meta, 0);
    m.u32(p.root.index);
    m.u32(p.root.count);
    for v in p.root_box.min.iter().chain(&p.root_box.max) {
        m.u32(v.to_bits());
    }
    m.u64(built_sah.to_bits());
    m.u64(p.stats.sah_cost.to_bits());
    for w in scale.to_words() {
        m.u32(w);
    }
    let mut head = [0u8; HEADER];
    let mut h = Cursor(&mut head, 0);
    h.bytes(&MAGIC);
    h.u32(FORMAT_VERSION);
    h.u32(BYTE_ORDER);
    h.u32(kind_code(kind));
    h.u32(test_code::<T>());
    h.u32(node_bytes as u32);
    h.u32(unit_bytes as u32);
    h.u32(form);
    h.u32(0);
    h.u64(mesh.num_triangles() as u64);
    h.u64(mesh.positions.len() as u64);
    h.u32(mesh_crc(mesh));
    h.u32(0); // the payload's CRC, filled in by the caller
    h.u64(p.nodes.len() as u64);
    h.u64(units as u64);
    h.u64(payload as u64);
    (head, meta, payload)
}

/// Little-endian writes into a fixed buffer.
struct Cursor<'a>(&'a mut [u8], usize);

impl Cursor<'_> {
    fn bytes(&mut self, b: &[u8]) {
        self.0[self.1..self.1 + b.len()].copy_from_slice(b);
        self.1 += b.len();
    }
    fn u32(&mut self, v: u32) {
        self.bytes(&v.to_le_bytes());
    }
    fn u64(&mut self, v: u64) {
        self.bytes(&v.to_le_bytes());
    }
}

/// Little-endian field reads from the header.
fn u32_at(b: &[u8], at: usize) -> u32 {
    u32::from_le_bytes(b[at..at + 4].try_into().expect("four bytes"))
}

fn u64_at(b: &[u8], at: usize) -> u64 {
    u64::from_le_bytes(b[at..at + 8].try_into().expect("eight bytes"))
}

/// Check that the tree's triangles are `mesh`'s (as built over it or last
/// refit to it), so that the mesh checksum stored with it describes it.
fn check_tree_matches_mesh<T: TriangleTest>(
    leaves: &Leaves<T>,
    mesh: &TriangleMesh,
    fault: &Fault<'_>,
) -> Result<(), PersistError> {
    let tris = mesh.num_triangles();
    let bad = match leaves {
        Leaves::Packed(p) => p.packs().par_iter().position_any(|pack| {
            (0..4).any(|lane| {
                let prim = pack.prim[lane];
                if prim == u32::MAX {
                    return false;
                }
                if prim as usize >= tris {
                    return true;
                }
                let [a, b, c] = mesh.triangle(prim as usize);
                let want = Moller::precompute(a, b, c);
                let got = pack.get(lane);
                [want.v0, want.e1, want.e2]
                    .iter()
                    .zip([got.v0, got.e1, got.e2])
                    .any(|(w, g)| w.to_array().map(f32::to_bits) != g.to_array().map(f32::to_bits))
            })
        }),
        Leaves::Single(t) => {
            let prims = t.prims(0, t.len());
            let stored = t.flat().words;
            let w = T::WORDS;
            (0..t.len()).into_par_iter().position_any(|i| {
                let prim = prims[i] as usize;
                if prim >= tris {
                    return true;
                }
                let [a, b, c] = mesh.triangle(prim);
                let mut want = Vec::with_capacity(w);
                T::write_words(&T::precompute(a, b, c), &mut want);
                want[..] != stored[i * w..(i + 1) * w]
            })
        }
    };
    match bad {
        None => Ok(()),
        Some(i) => Err(fault.at(
            0,
            "mesh",
            format!(
                "leaf unit {i} of the tree is not the mesh's triangle: pass the mesh the tree \
                 was built over or last refit to"
            ),
        )),
    }
}

/// Save `bvh`, built over (or last refit to) `mesh`, to `path`; `mesh` is
/// the model at `scale` (see [`UnitScale`]), which the file records.
pub(crate) fn save<B: WideParts>(
    bvh: &B,
    path: &Path,
    mesh: &TriangleMesh,
    scale: UnitScale,
) -> Result<(), PersistError> {
    let fault = Fault(path);
    let p = bvh.parts();
    check_mesh(mesh, p.stats.triangle_refs + left_out(p.leaves)).map_err(|e| {
        let e = e.to_string();
        let detail = e.strip_prefix("refit: ").unwrap_or(&e);
        let hint = "pass the mesh the tree was built over or last refit to";
        fault.at(0, "mesh", format!("saving: {detail}; {hint}"))
    })?;
    check_tree_matches_mesh(p.leaves, mesh, &fault)?;
    let built_sah = p.built_sah.unwrap_or_else(|| stored_sah(&p));
    let (mut head, meta, _) = header_and_meta(B::KIND, &p, mesh, built_sah, scale);
    let nodes = le_bytes(p.nodes);
    let leaves: Cow<'_, [u8]> = match p.leaves {
        Leaves::Packed(packs) => le_bytes(packs.packs()),
        Leaves::Single(t) => Cow::Owned(le_bytes(t.prims(0, t.len())).into_owned()),
    };
    let mut crc = crc32fast::Hasher::new();
    crc.update(&meta);
    crc.update(&nodes);
    crc.update(&leaves);
    head[60..64].copy_from_slice(&crc.finalize().to_le_bytes());
    let header_crc = crc32fast::hash(&head[..88]);
    head[88..92].copy_from_slice(&header_crc.to_le_bytes());

    let name = path
        .file_name()
        .ok_or_else(|| fault.at(0, "path", "the path names no file"))?;
    let mut tmp_name = name.to_os_string();
    tmp_name.push(format!(".tmp{}", std::process::id()));
    let tmp = path.with_file_name(tmp_name);
    let write = || -> std::io::Result<()> {
        let file = File::create(&tmp)?;
        let mut w = BufWriter::with_capacity(1 << 20, file);
        w.write_all(&head)?;
        w.write_all(&meta)?;
        w.write_all(&nodes)?;
        w.write_all(&leaves)?;
        let file = w.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    };
    write().map_err(|e| {
        let _ = std::fs::remove_file(&tmp);
        fault.io(e)
    })
}

/// Load a tree of type `B` over `mesh` from `path` (see the module docs).
///
/// `mapped`: map the leaf packs from the file instead of reading them.
/// `scaled`: `mesh` is the model at the scale the file records, as
/// [`crate::accel::load_accel`] passes it; otherwise a file that records
/// a scale other than one is refused.
///
/// # Safety
/// With `mapped`, the file must not be truncated or written while the
/// tree lives (see [`WideBvh::load_mapped`]).
pub(crate) unsafe fn load<B: WideParts>(
    path: &Path,
    mesh: &TriangleMesh,
    mapped: bool,
    scaled: bool,
) -> Result<B, PersistError> {
    let fault = Fault(path);
    // A tree over the scaled model cannot match the model as given: say so
    // before its mesh checksum does.
    if !scaled && saved_scale(path)?.is_some_and(|s| !s.is_one()) {
        return Err(scaled_elsewhere(&fault));
    }
    let mut file = File::open(path).map_err(|e| fault.io(e))?;
    let len = file.metadata().map_err(|e| fault.io(e))?.len();
    let mut head = [0u8; HEADER];
    if len < HEADER as u64 {
        // Read what there is, to tell a foreign file from a short one.
        let mut some = Vec::new();
        file.read_to_end(&mut some).map_err(|e| fault.io(e))?;
        if some.len() >= 8 && some[..8] != MAGIC {
            return Err(foreign(&fault, &some[..8]));
        }
        return Err(fault.at(
            len,
            "header",
            format!("truncated: the header is {HEADER} bytes, the file has {len}"),
        ));
    }
    file.read_exact(&mut head).map_err(|e| fault.io(e))?;
    let payload = check_header::<B>(&head, len, mesh, &fault)?;
    let nodes_n = u64_at(&head, 64) as usize;
    let units = u64_at(&head, 72) as usize;
    let form = u32_at(&head, 32);

    // The payload, read straight into the tree's arrays a block at a
    // time, each block checksummed (and its leaf units checked) while it
    // is in the cache.
    let mut meta = [0u8; META];
    file.read_exact(&mut meta).map_err(|e| fault.io(e))?;
    let mut crc = crc32fast::Hasher::new();
    crc.update(&meta);
    let mut nodes: Vec<B::Node> = zeroed(nodes_n);
    read_blocks(&mut file, &mut nodes, &mut crc, |_, _| Ok(()), &fault)?;
    let triangles = mesh.num_triangles();
    let units_at = (HEADER + META + nodes_n * std::mem::size_of::<B::Node>()) as u64;
    let unit_fault = |u: usize, bytes: usize| {
        fault.at(
            units_at + (u * bytes) as u64,
            "leaf units",
            format!("leaf unit {u} names a triangle beyond the mesh's {triangles}"),
        )
    };
    let pack_check = |first: usize, block: &[Tri4]| match block.iter().position(|p| {
        p.prim
            .iter()
            .any(|&t| t != u32::MAX && t as usize >= triangles)
    }) {
        None => Ok(()),
        Some(k) => Err(unit_fault(first + k, std::mem::size_of::<Tri4>())),
    };
    let (packs, prims) = if form == FORM_PACKED && mapped && units > 0 {
        #[cfg(all(target_os = "linux", target_endian = "little"))]
        {
            // SAFETY: the caller keeps the file as it is while the tree
            // lives; `units_at` is a multiple of 64 (the layout).
            let map = unsafe { super::mapped::Mapping::<Tri4>::new(&file, units_at, units) }
                .map_err(|e| fault.io(e))?;
            let packs = super::mapped::Store::Mapped(map);
            check_blocks(&packs, &mut crc, pack_check)?;
            (packs, Vec::new())
        }
        #[cfg(not(all(target_os = "linux", target_endian = "little")))]
        {
            let mut packs: Vec<Tri4> = zeroed(units);
            read_blocks(&mut file, &mut packs, &mut crc, pack_check, &fault)?;
            (packs.into(), Vec::new())
        }
    } else if form == FORM_PACKED {
        let mut packs: Vec<Tri4> = zeroed(units);
        read_blocks(&mut file, &mut packs, &mut crc, pack_check, &fault)?;
        (packs.into(), Vec::new())
    } else {
        let mut prims: Vec<u32> = zeroed(units);
        let check =
            |first: usize, block: &[u32]| match block.iter().position(|&t| t as usize >= triangles)
            {
                None => Ok(()),
                Some(k) => Err(unit_fault(first + k, 4)),
            };
        read_blocks(&mut file, &mut prims, &mut crc, check, &fault)?;
        (Vec::<Tri4>::new().into(), prims)
    };
    let (stored, computed) = (u32_at(&head, 60), crc.finalize());
    if stored != computed {
        return Err(fault.at(
            60,
            "payload checksum",
            format!(
                "stored {stored:#010x}, computed {computed:#010x} over bytes {HEADER}..{}: \
                 the file is corrupt",
                HEADER + payload
            ),
        ));
    }
    if meta[68..].iter().any(|&b| b != 0) {
        return Err(fault.at((HEADER + 68) as u64, "reserved", "not zero"));
    }
    match recorded_scale(&meta) {
        Ok(None) => {}
        Ok(Some(s)) if s.is_one() || scaled => {}
        Ok(Some(_)) => return Err(scaled_elsewhere(&fault)),
        Err(()) => return Err(fault.at((HEADER + 48) as u64, "scale", "not a scale")),
    }
    let f32_at = |at: usize| f32::from_bits(u32_at(&meta, at));
    let root = Child4 {
        index: u32_at(&meta, 0),
        count: u32_at(&meta, 4),
    };
    let root_box = NodeBox {
        min: [f32_at(8), f32_at(12), f32_at(16)],
        max: [f32_at(20), f32_at(24), f32_at(28)],
    };
    let built_sah = f64::from_bits(u64_at(&meta, 32));
    let sah_cost = f64::from_bits(u64_at(&meta, 40));

    // Packed leaves leave out the triangles no ray can hit: those in no
    // pack must be such, or the file is not a tree of this mesh.
    let unhittable = if form == FORM_PACKED {
        left_out_of(&packs, mesh, &fault)?
    } else {
        Unhittable::none()
    };
    let in_leaves = triangles - unhittable.prims.len();
    let shape = check_tree::<B>(&mut nodes, root, form, &packs, units, in_leaves, &fault)?;
    let leaves = if form == FORM_PACKED {
        Leaves::Packed(Tri4Leaves::from_packs(packs, unhittable))
    } else {
        if prims.len() != triangles {
            return Err(fault.at(
                72,
                "leaf units",
                format!("{} triangle indices for a mesh of {triangles}", prims.len()),
            ));
        }
        check_mesh(mesh, triangles).map_err(|e| fault.at(40, "mesh", e.to_string()))?;
        Leaves::Single(LeafTriangles::new(mesh, prims))
    };
    let node_bytes = std::mem::size_of_val(&nodes[..]);
    let leaf_bytes = match &leaves {
        Leaves::Packed(p) => p.bytes(),
        Leaves::Single(t) => t.bytes(),
    };
    let stats = AccelStats {
        nodes: nodes.len() + shape.leaves,
        leaves: shape.leaves,
        bytes: node_bytes + leaf_bytes,
        node_bytes,
        depth: shape.depth,
        sah_cost,
        triangle_refs: in_leaves,
    };
    Ok(B::from_parts(PartsOwned {
        nodes,
        root_box,
        root,
        leaves,
        stats,
        stack: shape.stack,
        built_sah: Some(built_sah),
    }))
}

/// The triangles of `mesh` in no pack of `packs`, each checked to be one
/// that no ray can hit ([`Unhittable`]): a tree over packs leaves only
/// those out.
fn left_out_of(
    packs: &[Tri4],
    mesh: &TriangleMesh,
    fault: &Fault<'_>,
) -> Result<Unhittable, PersistError> {
    let mut packed = vec![false; mesh.num_triangles()];
    for p in packs {
        for &t in &p.prim {
            // Checked against the mesh's count as the packs were read.
            if let Some(seen) = packed.get_mut(t as usize) {
                *seen = true;
            }
        }
    }
    let prims: Vec<u32> = (0..packed.len() as u32)
        .filter(|&i| !packed[i as usize])
        .collect();
    if let Some(&i) = prims.iter().find(|&&i| {
        let [a, b, c] = mesh.triangle(i as usize);
        !never_hit(a, b, c)
    }) {
        return Err(fault.at(
            0,
            "leaf units",
            format!(
                "triangle {i} of the mesh is in no leaf, though a ray can hit it: pass the mesh \
                 the tree was built over or last refit to"
            ),
        ));
    }
    Ok(Unhittable::with_prims(prims, mesh))
}

/// The error for a file whose first bytes are not [`MAGIC`].
fn foreign(fault: &Fault<'_>, magic: &[u8]) -> PersistError {
    fault.at(
        0,
        "magic",
        format!(
            "not a raykit BVH file: it starts with {:?}, expected {:?}",
            String::from_utf8_lossy(magic),
            String::from_utf8_lossy(&MAGIC)
        ),
    )
}

/// Check the magic bytes, version, byte-order mark, header checksum and
/// reserved fields.
fn check_preamble(head: &[u8; HEADER], fault: &Fault<'_>) -> Result<(), PersistError> {
    if head[..8] != MAGIC {
        return Err(foreign(fault, &head[..8]));
    }
    let version = u32_at(head, 8);
    if version != FORMAT_VERSION {
        return Err(fault.at(
            8,
            "format version",
            format!("version {version}; this build reads version {FORMAT_VERSION}"),
        ));
    }
    let order = u32_at(head, 12);
    if order != BYTE_ORDER {
        let reason = if order == BYTE_ORDER.swap_bytes() {
            "written in big-endian byte order; the format is little-endian".to_string()
        } else {
            format!("{order:#010x}, expected {BYTE_ORDER:#010x}")
        };
        return Err(fault.at(12, "byte-order mark", reason));
    }
    let (stored, computed) = (u32_at(head, 88), crc32fast::hash(&head[..88]));
    if stored != computed {
        return Err(fault.at(
            88,
            "header checksum",
            format!(
                "stored {stored:#010x}, computed {computed:#010x} over bytes 0..88: the header \
                 is corrupt"
            ),
        ));
    }
    for at in [36, 92] {
        if u32_at(head, at) != 0 {
            return Err(fault.at(at as u64, "reserved", "not zero"));
        }
    }
    Ok(())
}

/// Check the header against the file length, the tree type and the mesh;
/// returns the payload's length.
fn check_header<B: WideParts>(
    head: &[u8; HEADER],
    len: u64,
    mesh: &TriangleMesh,
    fault: &Fault<'_>,
) -> Result<usize, PersistError> {
    check_preamble(head, fault)?;
    let kind = u32_at(head, 16);
    if kind != kind_code(B::KIND) {
        return Err(fault.at(
            16,
            "structure",
            format!("{}, expected {}", kind_name(kind), B::KIND.name()),
        ));
    }
    let test = u32_at(head, 20);
    if test != test_code::<B::Test>() {
        return Err(fault.at(
            20,
            "triangle test",
            format!(
                "{}, expected {}",
                test_name(test),
                <B::Test as TriangleTest>::NAME
            ),
        ));
    }
    let node_bytes = u32_at(head, 24) as usize;
    if node_bytes != std::mem::size_of::<B::Node>() {
        return Err(fault.at(
            24,
            "node bytes",
            format!("{node_bytes}, expected {}", std::mem::size_of::<B::Node>()),
        ));
    }
    let packed = <B::Test as TriangleTest>::PACKS_OF_FOUR;
    let (want_form, want_unit) = match packed {
        true => (FORM_PACKED, std::mem::size_of::<Tri4>()),
        false => (FORM_SINGLE, 4),
    };
    let form = u32_at(head, 32);
    if form != want_form {
        return Err(fault.at(32, "leaf form", format!("{form}, expected {want_form}")));
    }
    let unit_bytes = u32_at(head, 28) as usize;
    if unit_bytes != want_unit {
        return Err(fault.at(
            28,
            "leaf unit bytes",
            format!("{unit_bytes}, expected {want_unit}"),
        ));
    }
    let (tris, verts) = (u64_at(head, 40), u64_at(head, 48));
    if tris != mesh.num_triangles() as u64 || verts != mesh.positions.len() as u64 {
        return Err(fault.at(
            40,
            "mesh size",
            format!(
                "saved for a mesh of {tris} triangles and {verts} vertices; this mesh has {} \
                 and {}",
                mesh.num_triangles(),
                mesh.positions.len()
            ),
        ));
    }
    let (nodes, units, payload) = (u64_at(head, 64), u64_at(head, 72), u64_at(head, 80));
    let want = nodes
        .checked_mul(node_bytes as u64)
        .zip(units.checked_mul(unit_bytes as u64))
        .and_then(|(a, b)| a.checked_add(b))
        .and_then(|s| s.checked_add(META as u64));
    if want != Some(payload) || nodes > u32::MAX as u64 || units > u32::MAX as u64 {
        return Err(fault.at(
            80,
            "payload bytes",
            format!(
                "{payload}, which does not fit {nodes} nodes of {node_bytes} bytes and {units} \
                 leaf units of {unit_bytes}"
            ),
        ));
    }
    let end = HEADER as u64 + payload;
    if len < end {
        return Err(fault.at(
            len,
            "payload",
            format!("truncated: the payload ends at byte {end}, the file has {len} bytes"),
        ));
    }
    if len > end {
        return Err(fault.at(
            end,
            "payload",
            format!("{} bytes after the payload's end", len - end),
        ));
    }
    let (stored, computed) = (u32_at(head, 56), mesh_crc(mesh));
    if stored != computed {
        return Err(fault.at(
            56,
            "mesh checksum",
            format!(
                "stored {stored:#010x}, this mesh's {computed:#010x}: the file was saved for \
                 another mesh (or these vertices moved since: refit after loading)"
            ),
        ));
    }
    Ok(payload as usize)
}

/// Shape figures found by [`check_tree`].
struct Shape {
    leaves: usize,
    depth: u32,
    stack: usize,
}

/// Check that the loaded nodes form a tree the traversal can walk: every
/// inner reference points after its node and in range, every node but the
/// root has exactly one parent, every leaf's units are in range (and in
/// `packs`, the packed form's units, the lanes a leaf's count covers name a
/// triangle: a hit never reports an unused lane's `u32::MAX`), and the
/// deepest stack fits; the boxes of unused slots are reset to the inverted
/// box (no ray enters them).
fn check_tree<B: WideParts>(
    nodes: &mut [B::Node],
    root: Child4,
    form: u32,
    packs: &[Tri4],
    units: usize,
    triangles: usize,
    fault: &Fault<'_>,
) -> Result<Shape, PersistError> {
    let n = nodes.len();
    let node_bytes = std::mem::size_of::<B::Node>();
    let width = <B::Node as super::wide_node::WideSlots>::WIDTH;
    let child_at = |i: usize, slot: usize| {
        (HEADER + META + i * node_bytes + node_bytes - 8 * width + 8 * slot) as u64
    };
    let per_unit = if form == FORM_PACKED { 4 } else { 1 };
    let in_range = |c: Child4| {
        (c.index as usize)
            .checked_add((c.count as usize).div_ceil(per_unit))
            .is_some_and(|end| end <= units)
    };
    let lanes_filled = |c: Child4| {
        let first = c.index as usize;
        form != FORM_PACKED
            || (0..c.count as usize).all(|k| packs[first + k / 4].prim[k % 4] != u32::MAX)
    };
    let leaf_ok = |c: Child4| in_range(c) && lanes_filled(c);
    let leaf_fault = |at: u64, c: Child4| {
        let what = if in_range(c) {
            "has an unused lane among its triangles"
        } else {
            "runs past the leaf units"
        };
        fault.at(
            at,
            "child reference",
            format!(
                "leaf of {} triangles from unit {} {what} ({units} units)",
                c.count, c.index
            ),
        )
    };
    let mut shape = Shape {
        leaves: 0,
        depth: 0,
        stack: 0,
    };
    if root.count > 0 {
        if !leaf_ok(root) {
            return Err(leaf_fault(HEADER as u64, root));
        }
        if n != 0 {
            return Err(fault.at(
                HEADER as u64,
                "root reference",
                format!("a root leaf with {n} inner nodes"),
            ));
        }
        shape.leaves = 1;
        return Ok(shape);
    }
    if root == Child4::EMPTY || n == 0 {
        // An empty tree (the builds give a root of count 0 and no nodes),
        // which traversal skips for a mesh of no triangles, and only then.
        if n == 0 && units == 0 && triangles == 0 {
            return Ok(shape);
        }
        return Err(fault.at(
            HEADER as u64,
            "root reference",
            format!("root {root:?} with {n} nodes and {units} leaf units"),
        ));
    }
    if root.index != 0 {
        return Err(fault.at(
            HEADER as u64,
            "root reference",
            format!("root node {}, expected 0", root.index),
        ));
    }
    // Per node: depth and stack entries pending below its ancestors, set by
    // the parent (`u32::MAX`: no parent yet).
    let mut depth = vec![u32::MAX; n];
    let mut pending = vec![0usize; n];
    depth[0] = 0;
    for i in 0..n {
        if depth[i] == u32::MAX {
            return Err(fault.at(
                child_at(i, 0),
                "node",
                format!("node {i} has no parent: not part of the tree"),
            ));
        }
        let node = &mut nodes[i];
        let kids = node
            .children()
            .iter()
            .filter(|&&c| c != Child4::EMPTY)
            .count();
        if kids == 0 {
            return Err(fault.at(
                child_at(i, 0),
                "child reference",
                format!("node {i} has no children"),
            ));
        }
        let here = pending[i] + kids - 1;
        shape.stack = shape.stack.max(here);
        for slot in 0..width {
            let c = node.children()[slot];
            let at = child_at(i, slot);
            if c == Child4::EMPTY {
                node.clear_box(slot);
            } else if c.count > 0 {
                if !leaf_ok(c) {
                    return Err(leaf_fault(at, c));
                }
                shape.leaves += 1;
                shape.depth = shape.depth.max(depth[i] + 1);
            } else {
                let j = c.index as usize;
                if j <= i || j >= n {
                    return Err(fault.at(
                        at,
                        "child reference",
                        format!(
                            "node {i} slot {slot}: child node {j}, expected one in {}..{n}",
                            i + 1
                        ),
                    ));
                }
                if depth[j] != u32::MAX {
                    return Err(fault.at(
                        at,
                        "child reference",
                        format!("node {i} slot {slot}: node {j} has a second parent"),
                    ));
                }
                depth[j] = depth[i] + 1;
                pending[j] = here;
                shape.depth = shape.depth.max(depth[j]);
            }
        }
    }
    if shape.stack >= B::STACK {
        return Err(fault.at(
            (HEADER + META) as u64,
            "nodes",
            format!(
                "the tree needs {} traversal stack entries, more than the {} there are",
                shape.stack,
                B::STACK - 1
            ),
        ));
    }
    Ok(shape)
}

/// Bytes read, checksummed and checked at a time (within the L2 cache).
const BLOCK: usize = 256 << 10;

/// [`read_blocks`] over values already in memory (mapped from the file,
/// on a little-endian host): blocks checksummed and checked in parallel,
/// the checksums combined in order.
#[cfg(all(target_os = "linux", target_endian = "little"))]
fn check_blocks<W: Words>(
    v: &[W],
    crc: &mut crc32fast::Hasher,
    check: impl Fn(usize, &[W]) -> Result<(), PersistError> + Sync,
) -> Result<(), PersistError> {
    let per_block = (BLOCK / std::mem::size_of::<W>()).max(1);
    let blocks: Vec<Result<crc32fast::Hasher, PersistError>> = v
        .par_chunks(per_block)
        .enumerate()
        .map(|(k, block)| {
            let mut h = crc32fast::Hasher::new();
            h.update(bytes_of(block));
            check(k * per_block, block).map(|()| h)
        })
        .collect();
    for b in blocks {
        crc.combine(&b?);
    }
    Ok(())
}

/// Fill `v` from `file` a block at a time: each block is read, added to
/// `crc` as read (little-endian), put into the host's byte order and
/// passed to `check` with the index of its first element (a unit's
/// checks are written against the values, so a failed check is an error
/// even where the checksum would also have failed).
fn read_blocks<W: Words>(
    file: &mut File,
    v: &mut [W],
    crc: &mut crc32fast::Hasher,
    mut check: impl FnMut(usize, &[W]) -> Result<(), PersistError>,
    fault: &Fault<'_>,
) -> Result<(), PersistError> {
    let per_block = (BLOCK / std::mem::size_of::<W>()).max(1);
    for (k, block) in v.chunks_mut(per_block).enumerate() {
        file.read_exact(bytes_of_mut(block))
            .map_err(|e| fault.io(e))?;
        crc.update(bytes_of(block));
        from_le(block);
        check(k * per_block, block)?;
    }
    Ok(())
}

impl<N: NodeWidth, T: TriangleTest> WideBvh<N, T> {
    /// Save the tree to `path` (see `bvh/persist.rs` for the
    /// format): `mesh` must be the mesh it was built over or last
    /// refit to (checked triangle for triangle), and its checksum is
    /// stored so that a load with another mesh is refused. Written
    /// to a temporary file beside `path`, then renamed over it.
    pub fn save(&self, path: impl AsRef<Path>, mesh: &TriangleMesh) -> Result<(), PersistError> {
        save(self, path.as_ref(), mesh, UnitScale::ONE)
    }

    /// [`Self::save`] of a tree built over the model at `scale` (`mesh` is
    /// the scaled model), recording the scale for
    /// [`crate::accel::load_accel`].
    pub(crate) fn save_scaled(
        &self,
        path: &Path,
        mesh: &TriangleMesh,
        scale: UnitScale,
    ) -> Result<(), PersistError> {
        save(self, path, mesh, scale)
    }

    /// [`Self::load`] of a file whose recorded scale `mesh` is already at.
    pub(crate) fn load_scaled(path: &Path, mesh: &TriangleMesh) -> Result<Self, PersistError> {
        // SAFETY: not mapped.
        unsafe { load(path, mesh, false, true) }
    }

    /// Load a tree saved by [`Self::save`] over `mesh`, without a
    /// build: the file's structure, triangle test, sizes, mesh
    /// checksum, payload checksum and topology are checked, and
    /// anything wrong is an error naming the offset and field.
    pub fn load(path: impl AsRef<Path>, mesh: &TriangleMesh) -> Result<Self, PersistError> {
        // SAFETY: not mapped.
        unsafe { load(path.as_ref(), mesh, false, false) }
    }

    /// [`Self::load`], with the leaf packs (over
    /// [`crate::tri::Moller`], most of the file) mapped from the
    /// file privately instead of read: no copy where the file is in
    /// the page cache (Linux; elsewhere, and for the other tests,
    /// the same as [`Self::load`]). The inner nodes are read and
    /// checked as by [`Self::load`], and a refit writes to private
    /// copies of the pages, never to the file.
    ///
    /// # Safety
    /// The file must not be truncated or written in place while the
    /// tree lives: a shrunk file makes the process fault when the
    /// tree is traced, and values written after the load are used
    /// unchecked. [`Self::save`] replaces a file by renaming a new
    /// one over it, which leaves a mapped tree intact.
    pub unsafe fn load_mapped(
        path: impl AsRef<Path>,
        mesh: &TriangleMesh,
    ) -> Result<Self, PersistError> {
        // SAFETY: the caller's promise.
        unsafe { load(path.as_ref(), mesh, true, false) }
    }
}

/// The error for a tree over a scaled model loaded as if over the model.
fn scaled_elsewhere(fault: &Fault<'_>) -> PersistError {
    fault.at(
        (HEADER + 48) as u64,
        "scale",
        "the tree was built over the mesh scaled to unit size or moved to the origin \
         (as build_accel does for tiny and far meshes): load it with load_accel",
    )
}

/// The scale recorded in a file's `meta` block: `None` when it is all zero
/// (a file that predates the record), an error when it is no scale.
fn recorded_scale(meta: &[u8; META]) -> Result<Option<UnitScale>, ()> {
    let words: [u32; 5] = std::array::from_fn(|i| u32_at(meta, 48 + 4 * i));
    if words == [0; 5] {
        return Ok(None);
    }
    UnitScale::from_words(words).map(Some).ok_or(())
}

/// The scale a saved file records (see [`recorded_scale`]); `None` when it
/// records none, or when the file is too short or the record no scale,
/// which the load itself then reports.
pub(crate) fn saved_scale(path: &Path) -> Result<Option<UnitScale>, PersistError> {
    let fault = Fault(path);
    let mut file = File::open(path).map_err(|e| fault.io(e))?;
    let mut start = Vec::with_capacity(HEADER + META);
    (&mut file)
        .take((HEADER + META) as u64)
        .read_to_end(&mut start)
        .map_err(|e| fault.io(e))?;
    let Some(meta) = start.get(HEADER..HEADER + META) else {
        return Ok(None);
    };
    let meta: &[u8; META] = meta.try_into().expect("the meta block's length");
    Ok(recorded_scale(meta).unwrap_or(None))
}

/// The structure and triangle test a saved file holds, from its header
/// (checked as far as the header goes: magic, version, byte order, header
/// checksum).
pub fn saved_kind(path: &Path) -> Result<(AccelKind, TestKind), PersistError> {
    let fault = Fault(path);
    let mut file = File::open(path).map_err(|e| fault.io(e))?;
    let mut head = Vec::with_capacity(HEADER);
    (&mut file)
        .take(HEADER as u64)
        .read_to_end(&mut head)
        .map_err(|e| fault.io(e))?;
    if head.len() >= 8 && head[..8] != MAGIC {
        return Err(foreign(&fault, &head[..8]));
    }
    if head.len() < HEADER {
        let len = head.len() as u64;
        return Err(fault.at(
            len,
            "header",
            format!("truncated: the header is {HEADER} bytes, the file has {len}"),
        ));
    }
    let head: &[u8; HEADER] = head[..].try_into().expect("the header's length");
    check_preamble(head, &fault)?;
    let kind = match u32_at(head, 16) {
        4 => AccelKind::Bvh4,
        8 => AccelKind::Bvh8,
        code => return Err(fault.at(16, "structure", kind_name(code))),
    };
    let test = u32_at(head, 20);
    let test = *TestKind::ALL
        .get(test as usize)
        .ok_or_else(|| fault.at(20, "triangle test", test_name(test)))?;
    Ok((kind, test))
}
