//! Stanford PLY bodies (ASCII, binary little- and big-endian).
//!
//! Reads element `vertex` (`x`, `y`, `z` of any numeric type; optional
//! `nx`/`ny`/`nz`; texture coordinates `u`/`v`, `s`/`t`, `texture_u`/`texture_v`
//! or `texture_s`/`texture_t`) and element `face` (list `vertex_indices` or
//! `vertex_index` of any count and index types, polygons cut into
//! triangles by `polygon.rs`).
//! Other elements and properties, lists included, are skipped.

use crate::error::{show, LoadError, Location};
use crate::far_origin::{out_of_range, FarOrigin};
use crate::format::PlyEncoding;
use crate::ply_header::{parse_header, Element, Header, PropKind, Scalar};
use crate::polygon::Triangulator;
use crate::text::{parse_f32, parse_f64, parse_i64, TokenStream};
use crate::validate::finish;
use raykit_core::{TriangleMesh, Vec2, Vec3};
use std::path::Path;

/// Parse the PLY file `data` read from `path`: mesh, warnings and encoding.
pub(crate) fn parse_ply(
    path: &Path,
    data: &[u8],
    far: &mut FarOrigin,
) -> Result<(TriangleMesh, Vec<String>, PlyEncoding), LoadError> {
    let header = parse_header(path, data)?;
    let body = &data[header.body_start..];
    let enc = header.encoding;
    let (mesh, warnings) = match enc {
        PlyEncoding::Ascii => read_body(
            path,
            &header,
            &mut Ascii {
                ts: TokenStream::new(body, header.body_line),
                wide: false,
            },
            far,
        )?,
        PlyEncoding::BinaryLittleEndian => read_body(
            path,
            &header,
            &mut Binary::<false> {
                data,
                pos: header.body_start,
            },
            far,
        )?,
        PlyEncoding::BinaryBigEndian => read_body(
            path,
            &header,
            &mut Binary::<true> {
                data,
                pos: header.body_start,
            },
            far,
        )?,
    };
    Ok((mesh, warnings, enc))
}

/// Why a value could not be read.
enum Fail<'a> {
    /// The data ended.
    Eof,
    /// A token that is not a number of the expected type (ASCII only).
    Bad(&'a [u8]),
}

/// A source of property values: ASCII tokens or binary bytes.
trait Body<'a> {
    /// A value of type `ty` as f64.
    fn f64(&mut self, ty: Scalar) -> Result<f64, Fail<'a>>;
    /// A value of integer type `ty`.
    fn int(&mut self, ty: Scalar) -> Result<i64, Fail<'a>>;
    /// Skip `n` values of type `ty`.
    fn skip(&mut self, ty: Scalar, n: u64) -> Result<(), Fail<'a>>;
    /// The current position (byte or line), to report later.
    fn mark(&self) -> u64;
    /// The location of a mark (binary) or of the last token read (ASCII).
    fn location_of(&self, mark: u64) -> Location;
    /// Bytes left.
    fn remaining(&self) -> usize;
    /// A sentence about data left after the last element, if any.
    fn trailing(&mut self) -> Option<String>;
    /// Read `float` properties to the digits the text has, where the
    /// encoding is text.
    fn read_wide(&mut self, _wide: bool) {}
    /// Where the next record starts, for [`Body::end_record`].
    fn begin_record(&mut self) -> usize {
        0
    }
    /// Why the record begun at `begin` (its [`Body::begin_record`]) does
    /// not end where it should: ASCII PLY holds one element per line, so a
    /// line with fewer values than the element's properties (which would
    /// take values from the next line) or more is malformed.
    fn end_record(&mut self, _begin: usize) -> Option<String> {
        None
    }
}

struct Ascii<'a> {
    ts: TokenStream<'a>,
    /// Whether `float` properties are read to the digits the text has
    /// (as `double`), for [`FarOrigin`]'s precision.
    wide: bool,
}

impl<'a> Body<'a> for Ascii<'a> {
    fn read_wide(&mut self, wide: bool) {
        self.wide = wide;
    }

    #[inline]
    fn f64(&mut self, ty: Scalar) -> Result<f64, Fail<'a>> {
        let t = self.ts.next_token().ok_or(Fail::Eof)?;
        let v = match ty {
            Scalar::F32 if !self.wide => parse_f32(t).map(f64::from),
            Scalar::F32 | Scalar::F64 => parse_f64(t),
            _ => parse_i64(t).map(|i| i as f64),
        };
        v.ok_or(Fail::Bad(t))
    }

    #[inline]
    fn int(&mut self, _ty: Scalar) -> Result<i64, Fail<'a>> {
        let t = self.ts.next_token().ok_or(Fail::Eof)?;
        parse_i64(t).ok_or(Fail::Bad(t))
    }

    fn skip(&mut self, _ty: Scalar, n: u64) -> Result<(), Fail<'a>> {
        for _ in 0..n {
            self.ts.next_token().ok_or(Fail::Eof)?;
        }
        Ok(())
    }

    fn mark(&self) -> u64 {
        self.ts.line() as u64
    }

    fn begin_record(&mut self) -> usize {
        self.ts.line_of_next()
    }

    fn end_record(&mut self, begin: usize) -> Option<String> {
        if self.ts.line() != begin {
            return Some(format!(
                "has fewer values than its properties: they run on to line {} (ASCII PLY holds \
                 one element per line)",
                self.ts.line()
            ));
        }
        let rest = self.ts.rest_of_line();
        (!rest.is_empty()).then(|| {
            format!(
                "has more values than its properties: {:?} is left on the line",
                String::from_utf8_lossy(rest)
            )
        })
    }

    /// ASCII reports the line of the last token read, which lies inside the
    /// record being read.
    fn location_of(&self, _mark: u64) -> Location {
        Location::Line(self.ts.line())
    }

    fn remaining(&self) -> usize {
        self.ts.remaining()
    }

    fn trailing(&mut self) -> Option<String> {
        self.ts.next_token()?;
        Some(format!(
            "data after the last element (line {}) ignored",
            self.ts.line()
        ))
    }
}

struct Binary<'a, const BE: bool> {
    data: &'a [u8],
    pos: usize,
}

impl<'a, const BE: bool> Binary<'a, BE> {
    #[inline]
    fn take<const N: usize>(&mut self) -> Result<[u8; N], Fail<'a>> {
        let s = self.data.get(self.pos..self.pos + N).ok_or(Fail::Eof)?;
        self.pos += N;
        let mut a = [0u8; N];
        a.copy_from_slice(s);
        if BE {
            a.reverse();
        }
        Ok(a)
    }
}

impl<'a, const BE: bool> Body<'a> for Binary<'a, BE> {
    #[inline]
    fn f64(&mut self, ty: Scalar) -> Result<f64, Fail<'a>> {
        Ok(match ty {
            Scalar::F32 => f32::from_le_bytes(self.take()?) as f64,
            Scalar::F64 => f64::from_le_bytes(self.take()?),
            _ => self.int(ty)? as f64,
        })
    }

    #[inline]
    fn int(&mut self, ty: Scalar) -> Result<i64, Fail<'a>> {
        Ok(match ty {
            Scalar::I8 => i8::from_le_bytes(self.take()?) as i64,
            Scalar::U8 => u8::from_le_bytes(self.take()?) as i64,
            Scalar::I16 => i16::from_le_bytes(self.take()?) as i64,
            Scalar::U16 => u16::from_le_bytes(self.take()?) as i64,
            Scalar::I32 => i32::from_le_bytes(self.take()?) as i64,
            Scalar::U32 => u32::from_le_bytes(self.take()?) as i64,
            // Floats in an integer role: truncated (the header check rejects
            // float list counts and indices, so this is not reached for them).
            Scalar::F32 => f32::from_le_bytes(self.take()?) as i64,
            Scalar::F64 => f64::from_le_bytes(self.take()?) as i64,
        })
    }

    fn skip(&mut self, ty: Scalar, n: u64) -> Result<(), Fail<'a>> {
        let bytes = (ty.size() as u64).saturating_mul(n);
        if bytes > (self.data.len() - self.pos) as u64 {
            self.pos = self.data.len();
            return Err(Fail::Eof);
        }
        self.pos += bytes as usize;
        Ok(())
    }

    fn mark(&self) -> u64 {
        self.pos as u64
    }

    fn location_of(&self, mark: u64) -> Location {
        Location::Byte(mark)
    }

    fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    fn trailing(&mut self) -> Option<String> {
        let n = self.remaining();
        (n > 0).then(|| format!("{n} bytes after the last element ignored"))
    }
}

/// What a vertex property is read into.
const X: usize = 0;
const NX: usize = 3;
const UV: usize = 6;
const SKIP: usize = usize::MAX;

/// Vertex property roles, and whether normals and uvs are present.
fn vertex_roles(path: &Path, el: &Element) -> Result<(Vec<usize>, bool, bool), LoadError> {
    let mut roles = vec![SKIP; el.props.len()];
    let mut set = |names: &[&str], slot: usize| -> Result<bool, LoadError> {
        let found: Vec<Option<usize>> = names.iter().map(|n| el.find(n)).collect();
        if found.iter().any(|f| f.is_none()) {
            return Ok(false);
        }
        for (k, f) in found.into_iter().flatten().enumerate() {
            let p = &el.props[f];
            if !matches!(p.kind, PropKind::Scalar(_)) {
                return Err(LoadError::at_line(
                    path,
                    p.line,
                    format!(
                        "property '{}' of element 'vertex' must not be a list",
                        p.name
                    ),
                ));
            }
            roles[f] = slot + k;
        }
        Ok(true)
    };
    if !set(&["x", "y", "z"], X)? {
        return Err(LoadError::at_line(
            path,
            el.line,
            "element 'vertex' lacks one of the properties 'x', 'y', 'z'",
        ));
    }
    let normals = set(&["nx", "ny", "nz"], NX)?;
    let mut uvs = false;
    for pair in [
        ["u", "v"],
        ["s", "t"],
        ["texture_u", "texture_v"],
        ["texture_s", "texture_t"],
    ] {
        if set(&pair, UV)? {
            uvs = true;
            break;
        }
    }
    Ok((roles, normals, uvs))
}

/// The face index list property and its types.
fn face_list(path: &Path, el: &Element) -> Result<(usize, Scalar, Scalar), LoadError> {
    let k = el
        .find("vertex_indices")
        .or_else(|| el.find("vertex_index"))
        .ok_or_else(|| {
            LoadError::at_line(
                path,
                el.line,
                "element 'face' has no list property 'vertex_indices' or 'vertex_index'",
            )
        })?;
    let p = &el.props[k];
    match p.kind {
        PropKind::List { count, item } if item.is_int() => Ok((k, count, item)),
        _ => Err(LoadError::at_line(
            path,
            p.line,
            format!("property '{}' must be a list of an integer type", p.name),
        )),
    }
}

fn fail_message(f: Fail<'_>, what: &str, i: u64, count: u64, prop: &str, ty: Scalar) -> String {
    match f {
        Fail::Eof => format!("file ends inside {what} {i} of {count} (truncated?)"),
        Fail::Bad(t) => format!(
            "expected a {} for property '{prop}' of {what} {i} of {count}, found {}",
            ty.name(),
            show(Some(t))
        ),
    }
}

fn read_body<'a, B: Body<'a>>(
    path: &Path,
    header: &Header,
    b: &mut B,
    far: &mut FarOrigin,
) -> Result<(TriangleMesh, Vec<String>), LoadError> {
    let enc = header.encoding;
    let mut warnings = Vec::new();
    let vertex_el = header.elements.iter().find(|e| e.name == "vertex");
    let Some(vertex_el) = vertex_el else {
        return Err(LoadError::at_line(
            path,
            header.body_line.saturating_sub(1).max(1),
            "the header declares no element 'vertex'",
        ));
    };
    let nverts = vertex_el.count;
    if nverts > u32::MAX as u64 {
        return Err(LoadError::at_line(
            path,
            vertex_el.line,
            format!("{nverts} vertices is more than 32-bit indices can address"),
        ));
    }
    let mut mesh = TriangleMesh::default();
    let mut normals = Vec::new();
    let mut uvs = Vec::new();
    let mut has_normals = false;
    let mut has_uvs = false;
    let mut poly: Vec<u32> = Vec::new();
    let mut faces = Triangulator::default();
    for el in &header.elements {
        // Cap pre-allocation by what the remaining data can hold.
        let cap = (el.count as usize).min(b.remaining() / el.min_record_size(enc));
        let err = |b: &B, msg: String| {
            LoadError::new(
                path,
                crate::error::ErrorKind::Malformed,
                b.location_of(b.mark()),
                msg,
            )
        };
        let err_at = |_: &B, line: usize, msg: String| {
            LoadError::new(
                path,
                crate::error::ErrorKind::Malformed,
                Location::Line(line),
                msg,
            )
        };
        if el.name == "vertex" && std::ptr::eq(el, vertex_el) {
            let (roles, hn, hu) = vertex_roles(path, el)?;
            has_normals = hn;
            has_uvs = hu;
            mesh.positions.reserve(cap);
            if hn {
                normals.reserve(cap);
            }
            if hu {
                uvs.reserve(cap);
            }
            let mut v = [0.0f64; 8];
            for i in 0..el.count {
                let line = b.begin_record();
                let start = b.mark();
                b.read_wide(far.keeps_precision());
                for (p, &role) in el.props.iter().zip(&roles) {
                    let r = match (role, p.kind) {
                        (SKIP, kind) => skip_prop(b, kind),
                        (slot, PropKind::Scalar(ty)) => b.f64(ty).map(|x| v[slot] = x),
                        (_, PropKind::List { .. }) => Ok(()),
                    };
                    if let Err(f) = r {
                        let ty = match p.kind {
                            PropKind::Scalar(t) => t,
                            PropKind::List { count, .. } => count,
                        };
                        return Err(err(b, fail_message(f, "vertex", i, el.count, &p.name, ty)));
                    }
                }
                let pos = if far.keeps_precision() {
                    far.place([v[0], v[1], v[2]])
                } else {
                    Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
                };
                let why = if !v[..3].iter().all(|c| c.is_finite()) {
                    Some(format!(
                        " has a NaN or infinite coordinate ({}, {}, {})",
                        v[0], v[1], v[2]
                    ))
                } else {
                    out_of_range([v[0], v[1], v[2]], pos).map(|e| format!(": {e}"))
                };
                if let Some(why) = why {
                    return Err(LoadError::new(
                        path,
                        crate::error::ErrorKind::Malformed,
                        b.location_of(start),
                        format!("vertex {i} of {}{why}", el.count),
                    ));
                }
                if let Some(why) = b.end_record(line) {
                    return Err(err_at(b, line, format!("vertex {i} of {} {why}", el.count)));
                }
                mesh.positions.push(pos);
                if hn {
                    normals.push(Vec3::new(v[3] as f32, v[4] as f32, v[5] as f32));
                }
                if hu {
                    uvs.push(Vec2::new(v[6] as f32, v[7] as f32));
                }
            }
        } else if el.name == "face" && !el.props.is_empty() {
            let (list, count_ty, item_ty) = face_list(path, el)?;
            mesh.indices.reserve(cap);
            for i in 0..el.count {
                let line = b.begin_record();
                for (k, p) in el.props.iter().enumerate() {
                    if k != list {
                        if let Err(f) = skip_prop(b, p.kind) {
                            let ty = match p.kind {
                                PropKind::Scalar(t) => t,
                                PropKind::List { count, .. } => count,
                            };
                            return Err(err(b, fail_message(f, "face", i, el.count, &p.name, ty)));
                        }
                        continue;
                    }
                    let n = b.int(count_ty).map_err(|f| {
                        err(b, fail_message(f, "face", i, el.count, &p.name, count_ty))
                    })?;
                    if n < 3 {
                        return Err(err(
                            b,
                            format!(
                                "face {i} of {} has {n} vertices; expected at least 3",
                                el.count
                            ),
                        ));
                    }
                    poly.clear();
                    for _ in 0..n {
                        let idx = b.int(item_ty).map_err(|f| {
                            err(b, fail_message(f, "face", i, el.count, &p.name, item_ty))
                        })?;
                        if idx < 0 || idx as u64 >= nverts {
                            return Err(err(
                                b,
                                format!(
                                    "face {i} of {}: vertex index {idx} is out of range \
                                     (the file has {nverts} vertices)",
                                    el.count
                                ),
                            ));
                        }
                        poly.push(idx as u32);
                    }
                }
                if let Some(why) = b.end_record(line) {
                    return Err(err_at(b, line, format!("face {i} of {} {why}", el.count)));
                }
                faces.cut_face(&poly, &mesh.positions, &mut mesh.indices);
            }
        } else if !el.props.is_empty() {
            if el.name == "tristrips" {
                warnings.push("element 'tristrips' skipped: triangle strips are not read".into());
            }
            for i in 0..el.count {
                let line = b.begin_record();
                for p in &el.props {
                    if let Err(f) = skip_prop(b, p.kind) {
                        let ty = match p.kind {
                            PropKind::Scalar(t) => t,
                            PropKind::List { count, .. } => count,
                        };
                        return Err(err(b, fail_message(f, &el.name, i, el.count, &p.name, ty)));
                    }
                }
                if let Some(why) = b.end_record(line) {
                    return Err(err_at(
                        b,
                        line,
                        format!("{} {i} of {} {why}", el.name, el.count),
                    ));
                }
            }
        }
    }
    let end = b.location_of(b.mark());
    if let Some(w) = b.trailing() {
        warnings.push(w);
    }
    if has_normals {
        mesh.normals = Some(normals);
    }
    if has_uvs {
        mesh.uvs = Some(uvs);
    }
    Ok((finish(path, mesh, end)?, warnings))
}

#[inline]
fn skip_prop<'a, B: Body<'a>>(b: &mut B, kind: PropKind) -> Result<(), Fail<'a>> {
    match kind {
        PropKind::Scalar(ty) => b.skip(ty, 1),
        PropKind::List { count, item } => {
            let n = b.int(count)?;
            // A negative count cannot be skipped: treat it as the data ending.
            let n = u64::try_from(n).map_err(|_| Fail::Eof)?;
            b.skip(item, n)
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(src: &[u8]) -> Result<TriangleMesh, LoadError> {
        parse_ply(Path::new("t.ply"), src, &mut FarOrigin::new(false)).map(|r| r.0)
    }

    const ASCII: &str = "ply\nformat ascii 1.0\nelement vertex 4\nproperty float x\n\
property float y\nproperty list uchar int junk\nproperty float z\nproperty float nx\n\
property float ny\nproperty float nz\nelement edge 1\nproperty int a\nproperty list int int b\n\
element face 1\nproperty uchar flags\nproperty list uchar uint vertex_indices\nend_header\n\
0 0 2 7 7 0 0 0 1\n1 0 0 0 0 0 1\n1 1 1 9 0 0 0 1\n0 1 0 0 0 0 1\n5 2 1 2\n3 4 0 1 2 3\n";

    #[test]
    fn ascii_with_unknown_properties_lists_and_elements() {
        let m = parse(ASCII.as_bytes()).unwrap();
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.positions[2], Vec3::new(1.0, 1.0, 0.0));
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert_eq!(m.normals.as_ref().unwrap()[3], Vec3::Z);
    }

    #[test]
    fn ascii_errors_name_the_line() {
        let bad = ASCII.replace("1 1 1 9", "1 x 1 9");
        let e = parse(bad.as_bytes()).unwrap_err().to_string();
        assert_eq!(
            e,
            "t.ply:20: expected a float for property 'y' of vertex 2 of 4, found 'x'"
        );
        let bad = ASCII.replace("3 4 0 1 2 3", "3 4 0 1 2 4");
        let e = parse(bad.as_bytes()).unwrap_err().to_string();
        assert!(
            e.starts_with("t.ply:23: face 0 of 1: vertex index 4 is out of range"),
            "{e}"
        );
        let cut = &ASCII.as_bytes()[..ASCII.len() - 6];
        let e = parse(cut).unwrap_err().to_string();
        assert!(
            e.contains("file ends inside face 0 of 1 (truncated?)"),
            "{e}"
        );
        let bad = ASCII.replace("0 1 0 0 0 0 1", "0 nan 0 0 0 0 1");
        let e = parse(bad.as_bytes()).unwrap_err().to_string();
        assert!(e.starts_with("t.ply:21: vertex 3 of 4 has a NaN"), "{e}");
    }

    fn binary(be: bool, count: u32) -> Vec<u8> {
        let fmt = if be {
            "binary_big_endian"
        } else {
            "binary_little_endian"
        };
        let mut v = format!(
            "ply\nformat {fmt} 1.0\nelement vertex {count}\nproperty double x\nproperty short y\n\
property list ushort float junk\nproperty float z\nelement face 1\n\
property list uint short vertex_index\nend_header\n"
        )
        .into_bytes();
        let w = |v: &mut Vec<u8>, b: &[u8]| {
            let mut b = b.to_vec();
            if be {
                b.reverse();
            }
            v.extend_from_slice(&b);
        };
        for (x, y, z) in [(0.0f64, 0i16, 0.5f32), (1.0, 0, 0.5), (0.0, 1, 0.5)] {
            w(&mut v, &x.to_le_bytes());
            w(&mut v, &y.to_le_bytes());
            w(&mut v, &2u16.to_le_bytes());
            w(&mut v, &1.0f32.to_le_bytes());
            w(&mut v, &2.0f32.to_le_bytes());
            w(&mut v, &z.to_le_bytes());
        }
        w(&mut v, &3u32.to_le_bytes());
        for i in [0i16, 1, 2] {
            w(&mut v, &i.to_le_bytes());
        }
        v
    }

    #[test]
    fn binary_both_endians_any_types() {
        for be in [false, true] {
            let (m, w, enc) = parse_ply(
                Path::new("t.ply"),
                &binary(be, 3),
                &mut FarOrigin::new(false),
            )
            .unwrap();
            assert!(w.is_empty());
            assert_eq!(enc == PlyEncoding::BinaryBigEndian, be);
            assert_eq!(
                m.positions,
                vec![
                    Vec3::new(0.0, 0.0, 0.5),
                    Vec3::new(1.0, 0.0, 0.5),
                    Vec3::new(0.0, 1.0, 0.5)
                ]
            );
            assert_eq!(m.indices, vec![[0, 1, 2]]);
        }
    }

    #[test]
    fn binary_truncation_and_counts_give_byte_offsets() {
        let full = binary(false, 3);
        let header_len = full.len() - 3 * 24 - 10;
        let e = parse(&full[..header_len + 30]).unwrap_err().to_string();
        assert!(
            e.contains(&format!(
                "t.ply: byte {}: file ends inside vertex 1 of 3",
                header_len + 24
            )),
            "{e}"
        );
        let e = parse(&binary(false, 4_000_000_000))
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("more than 32-bit") || e.contains("file ends inside vertex"),
            "{e}"
        );
        let e = parse(&binary(false, 2_000_000_000))
            .unwrap_err()
            .to_string();
        assert!(e.contains("file ends inside vertex 3 of 2000000000"), "{e}");
    }
}
