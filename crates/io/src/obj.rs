//! Wavefront OBJ: `v`, `vt`, `vn`, `f` (all `v`, `v/vt`, `v//vn`, `v/vt/vn`
//! forms, negative relative indices, polygons cut into triangles by
//! `polygon.rs`), `o`/`g` (parts), `usemtl`/`mtllib` (materials from MTL
//! files; a missing MTL file falls back to default materials). Other
//! statements are ignored.
//!
//! Positions are kept as in the file when faces use no `vt`/`vn`; otherwise
//! each distinct `(v, vt, vn)` triple becomes one vertex so that normals and
//! texture coordinates are per vertex.

use crate::error::{show, LoadError, Location};
use crate::far_origin::{out_of_range, FarOrigin};
use crate::hashing::{key3_map, Key3};
use crate::mtl::{parse_mtl, TextureCache, MAX_LIBRARY_FILE};
use crate::polygon::Triangulator;
use crate::text::{parse_i64, Coordinate, Lines, Tokens};
use crate::uri::read_external;
use crate::validate::finish;
use raykit_core::{Material, Part, TriangleMesh, Vec2, Vec3};
use std::collections::HashMap;
use std::path::Path;

const NONE: u32 = u32::MAX;

/// Parse the OBJ file `data` read from `path` (MTL libraries are looked up
/// next to `path`). Returns the mesh and warnings.
pub(crate) fn parse_obj(
    path: &Path,
    data: &[u8],
    far: &mut FarOrigin,
) -> Result<(TriangleMesh, Vec<String>), LoadError> {
    let mut st = ObjState::new(path, *far);
    let mut lines = Lines::new(data, 1);
    for (line, text) in &mut lines {
        st.statement(line, text)?;
    }
    let last = lines.line().max(1);
    *far = st.far;
    st.finish(last)
}

struct ObjState<'p> {
    path: &'p Path,
    /// Where positions are stored relative to.
    far: FarOrigin,
    positions: Vec<Vec3>,
    uvs: Vec<Vec2>,
    normals: Vec<Vec3>,
    /// Corners `(v, vt, vn)` of the triangles, three per triangle.
    corners: Vec<[u32; 3]>,
    /// Scratch polygon.
    poly: Vec<[u32; 3]>,
    /// Cuts polygons into triangles.
    faces: Triangulator,
    any_vt: bool,
    all_vt: bool,
    any_vn: bool,
    all_vn: bool,
    materials: Vec<Material>,
    /// Materials created for `usemtl` names no MTL file defined.
    placeholder: Vec<bool>,
    mat_index: HashMap<String, u32>,
    cur_mat: u32,
    used_mtl: bool,
    tri_material: Vec<u32>,
    parts: Vec<Part>,
    part_index: HashMap<String, u32>,
    object: String,
    group: String,
    cur_part: u32,
    part_pending: bool,
    used_parts: bool,
    tri_part: Vec<u32>,
    /// Warnings from the MTL libraries.
    warnings: Vec<String>,
    /// The libraries read so far (canonical paths), each read once.
    libraries: std::collections::HashSet<std::path::PathBuf>,
    /// The libraries' decoded textures.
    textures: TextureCache,
}

/// Whether `token` is a decimal integer, with an optional minus sign.
fn is_integer(token: &[u8]) -> bool {
    let digits = token.strip_prefix(b"-").unwrap_or(token);
    !digits.is_empty() && digits.iter().all(u8::is_ascii_digit)
}

impl<'p> ObjState<'p> {
    fn new(path: &'p Path, far: FarOrigin) -> Self {
        ObjState {
            path,
            far,
            positions: Vec::new(),
            uvs: Vec::new(),
            normals: Vec::new(),
            corners: Vec::new(),
            poly: Vec::new(),
            faces: Triangulator::default(),
            any_vt: false,
            all_vt: true,
            any_vn: false,
            all_vn: true,
            materials: Vec::new(),
            placeholder: Vec::new(),
            mat_index: HashMap::new(),
            cur_mat: NONE,
            used_mtl: false,
            tri_material: Vec::new(),
            parts: Vec::new(),
            part_index: HashMap::new(),
            object: String::new(),
            group: String::new(),
            cur_part: NONE,
            part_pending: false,
            used_parts: false,
            tri_part: Vec::new(),
            warnings: Vec::new(),
            libraries: Default::default(),
            textures: TextureCache::new(),
        }
    }

    fn err(&self, line: usize, msg: String) -> LoadError {
        LoadError::at_line(self.path, line, msg)
    }

    #[inline]
    fn statement(&mut self, line: usize, text: &[u8]) -> Result<(), LoadError> {
        let mut toks = Tokens::new(text);
        let Some(key) = toks.next() else {
            return Ok(());
        };
        match key {
            b"v" => {
                let (read, p) = if self.far.keeps_precision() {
                    let p = self.numbers::<f64, 3>(line, "v", &mut toks)?;
                    (p, self.far.place(p))
                } else {
                    let p = Vec3::from_array(self.numbers(line, "v", &mut toks)?);
                    (p.as_dvec3().to_array(), p)
                };
                if let Some(e) = out_of_range(read, p) {
                    return Err(self.err(line, e));
                }
                self.positions.push(p);
            }
            b"vn" => {
                let n = self.numbers::<f32, 3>(line, "vn", &mut toks)?;
                self.normals.push(Vec3::from_array(n));
            }
            b"vt" => {
                let u = self.numbers::<f32, 1>(line, "vt", &mut toks)?[0];
                let v = match toks.next() {
                    None => 0.0,
                    Some(t) => self.finite(line, "vt", 2, Some(t))?,
                };
                self.uvs.push(Vec2::new(u, v));
            }
            b"f" => self.face(line, toks)?,
            b"o" => {
                self.object = String::from_utf8_lossy(toks.rest()).into_owned();
                self.group.clear();
                self.set_part();
            }
            b"g" => {
                self.group = String::from_utf8_lossy(toks.rest()).into_owned();
                self.set_part();
            }
            b"usemtl" => self.use_material(toks.rest()),
            b"mtllib" => self.material_library(line, toks.rest())?,
            _ => {}
        }
        Ok(())
    }

    fn finite<T: Coordinate>(
        &self,
        line: usize,
        key: &str,
        n: usize,
        t: Option<&[u8]>,
    ) -> Result<T, LoadError> {
        match t.and_then(T::parse) {
            Some(x) if x.is_finite() => Ok(x),
            Some(_) => Err(self.err(
                line,
                format!(
                    "expected {n} finite numbers after '{key}', found {}",
                    show(t)
                ),
            )),
            None => Err(self.err(
                line,
                format!("expected {n} numbers after '{key}', found {}", show(t)),
            )),
        }
    }

    #[inline]
    fn numbers<T: Coordinate, const N: usize>(
        &self,
        line: usize,
        key: &str,
        toks: &mut Tokens<'_>,
    ) -> Result<[T; N], LoadError> {
        let mut out = [T::default(); N];
        for o in &mut out {
            *o = self.finite(line, key, N, toks.next())?;
        }
        Ok(out)
    }

    fn face(&mut self, line: usize, toks: Tokens<'_>) -> Result<(), LoadError> {
        let mut poly = std::mem::take(&mut self.poly);
        poly.clear();
        for tok in toks {
            poly.push(self.corner(line, tok)?);
        }
        if poly.len() < 3 {
            return Err(self.err(
                line,
                format!(
                    "expected at least 3 vertices after 'f', found {}",
                    poly.len()
                ),
            ));
        }
        for c in &poly {
            let (vt, vn) = (c[1] != NONE, c[2] != NONE);
            self.any_vt |= vt;
            self.all_vt &= vt;
            self.any_vn |= vn;
            self.all_vn &= vn;
        }
        let part = self.current_part();
        let positions = &self.positions;
        let corners = poly.iter().map(|c| positions.get(c[0] as usize).copied());
        for t in self.faces.cut(corners) {
            self.corners.extend(t.map(|k| poly[k]));
            self.tri_material.push(self.cur_mat);
            self.tri_part.push(part);
        }
        self.poly = poly;
        Ok(())
    }

    #[inline]
    fn corner(&self, line: usize, tok: &[u8]) -> Result<[u32; 3], LoadError> {
        let mut it = tok.splitn(3, |&b| b == b'/');
        let v = it.next().unwrap_or_default();
        let vt = it.next().filter(|s| !s.is_empty());
        let vn = it.next().filter(|s| !s.is_empty());
        let v = self.resolve(line, tok, v, self.positions.len(), "vertex", "v")?;
        let vt = match vt {
            Some(s) => self.resolve(line, tok, s, self.uvs.len(), "texture coordinate", "vt")?,
            None => NONE,
        };
        let vn = match vn {
            Some(s) => self.resolve(line, tok, s, self.normals.len(), "normal", "vn")?,
            None => NONE,
        };
        Ok([v, vt, vn])
    }

    #[inline]
    fn resolve(
        &self,
        line: usize,
        tok: &[u8],
        part: &[u8],
        count: usize,
        what: &str,
        key: &str,
    ) -> Result<u32, LoadError> {
        let resolved = match parse_i64(part) {
            Some(0) => {
                return Err(self.err(
                    line,
                    format!("{what} index 0 is invalid (OBJ indices start at 1)"),
                ))
            }
            Some(i) if i > 0 => (i as u64 <= count as u64).then(|| i - 1),
            Some(i) => {
                let j = count as i64 + i;
                (j >= 0).then_some(j)
            }
            // An integer beyond i64 is out of range like any other.
            None if is_integer(part) => None,
            None => {
                return Err(self.err(
                    line,
                    format!(
                        "expected vertex indices (v, v/vt, v//vn or v/vt/vn) after 'f', found {}",
                        show(Some(tok))
                    ),
                ))
            }
        };
        match resolved.and_then(|j| u32::try_from(j).ok()).filter(|&j| j != NONE) {
            Some(j) => Ok(j),
            None => Err(self.err(
                line,
                format!(
                    "{}{what} index {} is out of range: only {count} '{key}' are defined before this line",
                    if part.starts_with(b"-") { "relative " } else { "" },
                    String::from_utf8_lossy(part)
                ),
            )),
        }
    }

    /// Start a new part name; the part is created by its first face.
    fn set_part(&mut self) {
        self.used_parts = true;
        self.cur_part = NONE;
        self.part_pending = true;
    }

    /// The index of the current part, creating it on first use.
    fn current_part(&mut self) -> u32 {
        if self.cur_part != NONE || !self.part_pending {
            return self.cur_part;
        }
        let name = match (self.object.is_empty(), self.group.is_empty()) {
            (_, true) => self.object.clone(),
            (true, false) => self.group.clone(),
            (false, false) if self.object == self.group => self.group.clone(),
            (false, false) => format!("{}/{}", self.object, self.group),
        };
        self.cur_part = match self.part_index.get(&name) {
            Some(&i) => i,
            None => {
                let i = self.parts.len() as u32;
                self.parts.push(Part {
                    name: name.clone(),
                    node: None,
                });
                self.part_index.insert(name, i);
                i
            }
        };
        self.cur_part
    }

    fn use_material(&mut self, name: &[u8]) {
        self.used_mtl = true;
        let name = String::from_utf8_lossy(name);
        self.cur_mat = match self.mat_index.get(name.as_ref()) {
            Some(&i) => i,
            None => {
                let i = self.materials.len() as u32;
                self.materials.push(Material {
                    name: name.to_string(),
                    ..Material::default()
                });
                self.placeholder.push(true);
                self.mat_index.insert(name.into_owned(), i);
                i
            }
        };
    }

    fn material_library(&mut self, line: usize, rest: &[u8]) -> Result<(), LoadError> {
        let dir = self.path.parent().unwrap_or(Path::new(""));
        for name in library_names(dir, rest) {
            let file = dir.join(&name);
            if !self
                .libraries
                .insert(std::fs::canonicalize(&file).unwrap_or(file.clone()))
            {
                continue;
            }
            // A missing or unreadable library (or one that is not a regular
            // file, whose reads need not end) falls back to default
            // materials, with a warning.
            let bytes = match read_external(&file, MAX_LIBRARY_FILE) {
                Ok(bytes) => bytes,
                Err(why) => {
                    self.warnings.push(format!(
                        "line {line}: mtllib {name}: {why}; its materials get default colours"
                    ));
                    continue;
                }
            };
            let (materials, warnings) = parse_mtl(&file, &bytes, &mut self.textures)?;
            self.warnings.extend(warnings);
            for m in materials {
                match self.mat_index.get(&m.name) {
                    Some(&i) if self.placeholder[i as usize] => {
                        self.placeholder[i as usize] = false;
                        self.materials[i as usize] = m;
                    }
                    Some(_) => {}
                    None => {
                        self.mat_index
                            .insert(m.name.clone(), self.materials.len() as u32);
                        self.materials.push(m);
                        self.placeholder.push(false);
                    }
                }
            }
        }
        Ok(())
    }

    fn finish(mut self, last_line: usize) -> Result<(TriangleMesh, Vec<String>), LoadError> {
        let mut warnings = std::mem::take(&mut self.warnings);
        let keep_uv = self.any_vt && self.all_vt;
        let keep_n = self.any_vn && self.all_vn;
        if self.any_vt && !keep_uv {
            warnings.push(
                "some faces have no texture coordinates ('vt'): texture coordinates dropped"
                    .to_string(),
            );
        }
        if self.any_vn && !keep_n {
            warnings.push("some faces have no normals ('vn'): normals dropped".to_string());
        }
        let mut mesh = TriangleMesh::default();
        if !keep_uv && !keep_n {
            mesh.indices = self
                .corners
                .chunks_exact(3)
                .map(|c| [c[0][0], c[1][0], c[2][0]])
                .collect();
            mesh.positions = std::mem::take(&mut self.positions);
        } else {
            let mut map = key3_map(self.positions.len());
            let mut positions = Vec::with_capacity(self.positions.len());
            let mut uvs = Vec::new();
            let mut normals = Vec::new();
            let mut flat = Vec::with_capacity(self.corners.len());
            for c in &self.corners {
                let key = [
                    c[0],
                    if keep_uv { c[1] } else { NONE },
                    if keep_n { c[2] } else { NONE },
                ];
                let next = positions.len() as u32;
                let idx = *map.entry(Key3(key)).or_insert(next);
                if idx == next {
                    positions.push(self.positions[key[0] as usize]);
                    if keep_uv {
                        uvs.push(self.uvs[key[1] as usize]);
                    }
                    if keep_n {
                        normals.push(self.normals[key[2] as usize]);
                    }
                }
                flat.push(idx);
            }
            mesh.indices = flat.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
            mesh.positions = positions;
            mesh.uvs = keep_uv.then_some(uvs);
            mesh.normals = keep_n.then_some(normals);
        }
        if self.used_mtl {
            fill_unassigned(&mut self.tri_material, self.materials.len() as u32, || {
                self.materials.push(Material::default())
            });
            mesh.materials = self.materials;
            mesh.tri_material = self.tri_material;
        }
        if self.used_parts {
            fill_unassigned(&mut self.tri_part, self.parts.len() as u32, || {
                self.parts.push(Part {
                    name: String::new(),
                    node: None,
                })
            });
            mesh.parts = self.parts;
            mesh.tri_part = self.tri_part;
        }
        let mesh = finish(self.path, mesh, Location::Line(last_line))?;
        Ok((mesh, warnings))
    }
}

/// Replace the `NONE` entries of `v` by `new_index`, calling `add` once if any.
/// The MTL libraries an `mtllib` statement names, its text after the keyword
/// being `rest`: the whole text when a file of that name exists in `dir`
/// (a name with spaces), otherwise each whitespace-separated token.
pub(crate) fn library_names(dir: &Path, rest: &[u8]) -> Vec<String> {
    let whole = String::from_utf8_lossy(rest).into_owned();
    if dir.join(&whole).is_file() {
        vec![whole]
    } else {
        Tokens::new(rest)
            .map(|t| String::from_utf8_lossy(t).into_owned())
            .collect()
    }
}

fn fill_unassigned(v: &mut [u32], new_index: u32, add: impl FnOnce()) {
    let mut any = false;
    for x in v.iter_mut().filter(|x| **x == NONE) {
        *x = new_index;
        any = true;
    }
    if any {
        add();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<TriangleMesh, LoadError> {
        parse_obj(Path::new("t.obj"), s.as_bytes(), &mut FarOrigin::new(false)).map(|r| r.0)
    }

    #[test]
    fn quad_with_negative_indices_is_fanned() {
        let m = parse("v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf -4 -3 -2 -1\n").unwrap();
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.positions.len(), 4);
        assert!(m.normals.is_none() && m.uvs.is_none());
        assert!(m.parts.is_empty() && m.tri_part.is_empty());
    }

    #[test]
    fn triples_are_deduplicated_into_vertices() {
        let src = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvt 0 0\nvt 1 0\nvt 0 1\nvn 0 0 1\n\
                   f 1/1/1 2/2/1 3/3/1\nf 1/1/1 3/3/1 2/1/1\n";
        let m = parse(src).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.uvs.as_ref().unwrap()[3], Vec2::new(0.0, 0.0));
        assert_eq!(m.positions[3], Vec3::X);
        assert_eq!(m.normals.as_ref().unwrap(), &vec![Vec3::Z; 4]);
    }

    #[test]
    fn groups_become_parts_and_usemtl_materials() {
        let src = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 3\ng a\nusemtl m\nf 1 2 3\no b\nf 1 2 3\ng a\nf 3 2 1\no unused\ng\n";
        let m = parse(src).unwrap();
        let names: Vec<_> = m.parts.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, vec!["a", "b", "b/a", ""]);
        assert_eq!(m.tri_part, vec![3, 0, 1, 2]);
        let names: Vec<_> = m.materials.iter().map(|p| p.name.as_str()).collect();
        assert_eq!(names, vec!["m", "default"]);
        assert_eq!(m.tri_material, vec![1, 0, 0, 0]);
    }

    #[test]
    fn errors_name_line_and_expectation() {
        let e = parse("v 1 2 3\nv 1 abc 3\n").unwrap_err().to_string();
        assert_eq!(e, "t.obj:2: expected 3 numbers after 'v', found 'abc'");
        let e = parse("v 1 2\n").unwrap_err().to_string();
        assert_eq!(
            e,
            "t.obj:1: expected 3 numbers after 'v', found end of line"
        );
        let e = parse("v 1 2 nan\n").unwrap_err().to_string();
        assert!(e.starts_with("t.obj:1: expected 3 finite numbers"), "{e}");
        let e = parse("v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 4\n")
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "t.obj:4: vertex index 4 is out of range: only 3 'v' are defined before this line"
        );
        let e = parse("v 0 0 0\nf 1 -2 1\n").unwrap_err().to_string();
        assert!(e.starts_with("t.obj:2: relative vertex index -2"), "{e}");
        let e = parse("v 0 0 0\nf 1 0 1\n").unwrap_err().to_string();
        assert!(e.contains("index 0 is invalid"), "{e}");
        let e = parse("v 0 0 0\nf 1 1\n").unwrap_err().to_string();
        assert!(e.starts_with("t.obj:2: expected at least 3"), "{e}");
        let e = parse("v 0 0 0\n\n").unwrap_err().to_string();
        assert!(e.starts_with("t.obj:2: the file has no triangles"), "{e}");
        let e = parse("v 0 0 0\nf 1/x 1 1\n").unwrap_err().to_string();
        assert!(e.contains("found '1/x'"), "{e}");
    }
}
