//! STL, ASCII and binary. Binary is recognised by its size (84 + 50 × the
//! triangle count), so binary files whose header starts with `solid` load
//! correctly; identical vertices are welded so the mesh is indexed. Every
//! `solid` of an ASCII file with several becomes a part.

use crate::error::{show, LoadError, Location};
use crate::format::StlEncoding;
use crate::hashing::Welder;
use crate::text::{parse_f32, TokenStream};
use crate::validate::finish;
use raykit_core::{Part, TriangleMesh, Vec3};
use std::path::Path;

/// Parse the STL file `data` read from `path`.
pub(crate) fn parse_stl(
    path: &Path,
    data: &[u8],
) -> Result<(TriangleMesh, StlEncoding), LoadError> {
    if data.len() >= 84 {
        let n = u32::from_le_bytes([data[80], data[81], data[82], data[83]]) as u64;
        let expected = 84 + 50 * n;
        if expected == data.len() as u64 || !looks_ascii(data) {
            if expected != data.len() as u64 {
                return Err(LoadError::at_byte(
                    path,
                    80,
                    format!(
                        "binary STL header says {n} triangles, which take {expected} bytes, \
                         but the file has {} bytes (truncated or not an STL file?)",
                        data.len()
                    ),
                ));
            }
            return Ok((parse_binary(path, data, n as usize)?, StlEncoding::Binary));
        }
    } else if !looks_ascii(data) {
        return Err(LoadError::at_byte(
            path,
            data.len() as u64,
            format!(
                "file ends after {} bytes: too short for a binary STL (84-byte header) \
                 and not ASCII STL ('solid …')",
                data.len()
            ),
        ));
    }
    Ok((parse_ascii(path, data)?, StlEncoding::Ascii))
}

/// Whether the token `t` is the keyword `word`, in any case: the format's
/// keywords are lower case, but some CAD tools write them in capitals.
fn is(t: Option<&[u8]>, word: &[u8]) -> bool {
    t.is_some_and(|t| t.eq_ignore_ascii_case(word))
}

/// True when `data` starts with `solid` (in any case) and its first
/// kilobyte is text.
fn looks_ascii(data: &[u8]) -> bool {
    let start = data.trim_ascii_start();
    is(start.get(..5), b"solid")
        && data
            .iter()
            .take(1024)
            .all(|&b| b == b'\n' || b == b'\r' || b == b'\t' || (32..127).contains(&b))
}

fn parse_binary(path: &Path, data: &[u8], n: usize) -> Result<TriangleMesh, LoadError> {
    let mut weld = Welder::with_capacity(n / 2 + 3);
    let mut indices = Vec::with_capacity(n);
    for (t, rec) in data[84..].chunks_exact(50).enumerate() {
        let mut tri = [0u32; 3];
        for (k, corner) in tri.iter_mut().enumerate() {
            let mut c = [0.0f32; 3];
            for (a, x) in c.iter_mut().enumerate() {
                let o = 12 + 12 * k + 4 * a;
                *x = f32::from_le_bytes([rec[o], rec[o + 1], rec[o + 2], rec[o + 3]]);
            }
            let p = Vec3::from_array(c);
            let offset = 84 + 50 * t as u64 + 12 + 12 * k as u64;
            if !p.is_finite() {
                return Err(LoadError::at_byte(
                    path,
                    offset,
                    format!("vertex {k} of triangle {t} has a NaN or infinite coordinate {c:?}"),
                ));
            }
            *corner = weld.insert(p).ok_or_else(|| {
                LoadError::at_byte(
                    path,
                    offset,
                    "more vertices than 32-bit indices can address",
                )
            })?;
        }
        indices.push(tri);
    }
    let mesh = TriangleMesh::new(weld.positions, indices);
    finish(path, mesh, Location::Byte(data.len() as u64))
}

fn parse_ascii(path: &Path, data: &[u8]) -> Result<TriangleMesh, LoadError> {
    let mut ts = TokenStream::new(data, 1);
    let mut weld = Welder::with_capacity(data.len() / 400 + 3);
    let mut indices = Vec::with_capacity(data.len() / 250);
    let mut parts: Vec<Part> = Vec::new();
    let mut tri_part: Vec<u32> = Vec::new();
    let mut poly: Vec<u32> = Vec::new();
    let mut end_line = 1;
    let err = |ts: &TokenStream<'_>, msg: String| LoadError::at_line(path, ts.line(), msg);
    let expect = |ts: &mut TokenStream<'_>, word: &[u8], context: &str| {
        let t = ts.next_token();
        if is(t, word) {
            Ok(())
        } else {
            Err(err(
                ts,
                format!(
                    "expected '{}' {context}, found {}",
                    String::from_utf8_lossy(word),
                    found(t)
                ),
            ))
        }
    };
    while let Some(t) = ts.next_token() {
        if !is(Some(t), b"solid") {
            return Err(err(
                &ts,
                format!("expected 'solid', found {}", show(Some(t))),
            ));
        }
        let name = String::from_utf8_lossy(ts.rest_of_line()).into_owned();
        parts.push(Part { name, node: None });
        let part = parts.len() as u32 - 1;
        loop {
            let t = ts.next_token();
            if is(t, b"endsolid") {
                ts.rest_of_line();
                end_line = ts.line();
                break;
            }
            if !is(t, b"facet") {
                return Err(err(
                    &ts,
                    format!("expected 'facet' or 'endsolid', found {}", found(t)),
                ));
            }
            expect(&mut ts, b"normal", "after 'facet'")?;
            for _ in 0..3 {
                let t = ts.next_token();
                if t.and_then(parse_f32).is_none() {
                    return Err(err(
                        &ts,
                        format!(
                            "expected 3 numbers after 'facet normal', found {}",
                            found(t)
                        ),
                    ));
                }
            }
            expect(&mut ts, b"outer", "after the facet normal")?;
            expect(&mut ts, b"loop", "after 'outer'")?;
            poly.clear();
            loop {
                let t = ts.next_token();
                if is(t, b"endloop") {
                    break;
                }
                if !is(t, b"vertex") {
                    return Err(err(
                        &ts,
                        format!("expected 'vertex' or 'endloop', found {}", found(t)),
                    ));
                }
                let mut c = [0.0f32; 3];
                for x in &mut c {
                    let t = ts.next_token();
                    match t.and_then(parse_f32) {
                        Some(v) if v.is_finite() => *x = v,
                        Some(_) => {
                            return Err(err(
                                &ts,
                                format!(
                                    "expected 3 finite numbers after 'vertex', found {}",
                                    found(t)
                                ),
                            ))
                        }
                        None => {
                            return Err(err(
                                &ts,
                                format!("expected 3 numbers after 'vertex', found {}", found(t)),
                            ))
                        }
                    }
                }
                let i = weld.insert(Vec3::from_array(c)).ok_or_else(|| {
                    err(&ts, "more vertices than 32-bit indices can address".into())
                })?;
                poly.push(i);
            }
            if poly.len() < 3 {
                return Err(err(
                    &ts,
                    format!("facet has {} vertices; expected at least 3", poly.len()),
                ));
            }
            for k in 1..poly.len() - 1 {
                indices.push([poly[0], poly[k], poly[k + 1]]);
                tri_part.push(part);
            }
            expect(&mut ts, b"endfacet", "after 'endloop'")?;
        }
    }
    let mut mesh = TriangleMesh::new(weld.positions, indices);
    if parts.len() > 1 {
        mesh.parts = parts;
        mesh.tri_part = tri_part;
    }
    finish(path, mesh, Location::Line(end_line))
}

/// A token for messages, where the end of the data is "end of file".
fn found(t: Option<&[u8]>) -> String {
    match t {
        None => "end of file (truncated?)".into(),
        t => show(t),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    const ASCII: &str = "solid cube part\n facet normal 0 0 1\n  outer loop\n   vertex 0 0 0\n\
   vertex 1 0 0\n   vertex 1 1 0\n  endloop\n endfacet\n facet normal 0 0 1\n  outer loop\n\
   vertex 0 0 0\n   vertex 1 1 0\n   vertex 0 1 0\n  endloop\n endfacet\nendsolid cube part\n";

    fn binary(tris: &[[[f32; 3]; 3]], header: &[u8]) -> Vec<u8> {
        let mut v = header.to_vec();
        v.resize(80, b' ');
        v.extend_from_slice(&(tris.len() as u32).to_le_bytes());
        for t in tris {
            v.extend_from_slice(&[0u8; 12]);
            for c in t {
                for x in c {
                    v.extend_from_slice(&x.to_le_bytes());
                }
            }
            v.extend_from_slice(&[0, 0]);
        }
        v
    }

    #[test]
    fn ascii_is_welded_into_an_indexed_mesh() {
        let (m, enc) = parse_stl(Path::new("a.stl"), ASCII.as_bytes()).unwrap();
        assert_eq!(enc, StlEncoding::Ascii);
        assert_eq!(m.positions.len(), 4);
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        assert!(m.parts.is_empty());
        // Keywords in capitals, as some CAD tools write them, give the same
        // mesh; the solid's name keeps its case.
        let upper = ASCII
            .to_uppercase()
            .replace("SOLID CUBE PART", "SOLID cube part");
        let (u, enc) = parse_stl(Path::new("a.stl"), upper.as_bytes()).unwrap();
        assert_eq!(enc, StlEncoding::Ascii);
        assert_eq!((u.positions, u.indices), (m.positions, m.indices));
    }

    #[test]
    fn binary_starting_with_solid_is_binary() {
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let data = binary(&[tri, tri], b"solid but binary");
        let (m, enc) = parse_stl(Path::new("a.stl"), &data).unwrap();
        assert_eq!(enc, StlEncoding::Binary);
        assert_eq!(m.positions.len(), 3);
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 1, 2]]);
    }

    #[test]
    fn errors() {
        let p = Path::new("a.stl");
        let tri = [[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]];
        let mut data = binary(&[tri, tri], b"x");
        data[80] = 3;
        let e = parse_stl(p, &data).unwrap_err().to_string();
        assert!(
            e.starts_with("a.stl: byte 80: binary STL header says 3 triangles"),
            "{e}"
        );
        let data = binary(&[tri, [[0.0, f32::NAN, 0.0], tri[1], tri[2]]], b"x");
        let e = parse_stl(p, &data).unwrap_err().to_string();
        assert!(
            e.starts_with("a.stl: byte 146: vertex 0 of triangle 1 has a NaN"),
            "{e}"
        );
        let cut = ASCII.find("vertex 1 0 0").unwrap() + 9;
        let e = parse_stl(p, &ASCII.as_bytes()[..cut])
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            "a.stl:5: expected 3 numbers after 'vertex', found end of file (truncated?)"
        );
        let bad = ASCII.replace("vertex 1 1 0\n  endloop", "vertex 1 inf 0\n  endloop");
        let e = parse_stl(p, bad.as_bytes()).unwrap_err().to_string();
        assert!(e.starts_with("a.stl:6: expected 3 finite numbers"), "{e}");
        let e = parse_stl(p, b"solid x\nendsolid x\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("no triangles"), "{e}");
        let e = parse_stl(p, b"\x01\x02").unwrap_err().to_string();
        assert!(
            e.starts_with("a.stl: byte 2: file ends after 2 bytes"),
            "{e}"
        );
    }
}
