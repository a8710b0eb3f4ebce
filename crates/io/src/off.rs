//! Object File Format (OFF): header keyword `OFF` with optional prefixes
//! (`ST`, `C`, `N`, `4`, `n`: `NOFF`, `COFF`, `CNOFF`, …; also tolerated when the
//! keyword is missing), `#` comments, counts `V F E` (on the keyword line or
//! the next), one vertex per line (`x y z`, further values such as colours are
//! ignored; `NOFF` normals are read), one face per line (`n i1 … in`, then an
//! optional colour). Binary OFF is not read.

use crate::error::{show, ErrorKind, LoadError, Location};
use crate::far_origin::{out_of_range, FarOrigin};
use crate::polygon::Triangulator;
use crate::text::{parse_f32, parse_f64, parse_u64, Lines, Tokens};
use crate::validate::finish;
use raykit_core::{TriangleMesh, Vec3};
use std::path::Path;

/// Parse the OFF file `data` read from `path`.
pub(crate) fn parse_off(
    path: &Path,
    data: &[u8],
    far: &mut FarOrigin,
) -> Result<(TriangleMesh, Vec<String>), LoadError> {
    let err = |line: usize, msg: String| LoadError::at_line(path, line, msg);
    // Non-blank lines with comments removed.
    let mut lines = Lines::new(data, 1).filter_map(|(n, l)| {
        let l = match l.iter().position(|&b| b == b'#') {
            Some(i) => &l[..i],
            None => l,
        };
        let l = l.trim_ascii();
        (!l.is_empty()).then_some((n, l))
    });
    let Some((first_line, first)) = lines.next() else {
        return Err(LoadError::new(
            path,
            ErrorKind::Empty,
            Location::Line(1),
            "the file is empty: expected 'OFF'",
        ));
    };
    let mut toks = Tokens::new(first);
    let mut normals = false;
    let mut counts_toks = toks.clone();
    if let Some(kw) = toks.next() {
        if let Some(prefix) = kw.strip_suffix(b"OFF") {
            if !prefix
                .iter()
                .all(|b| matches!(b, b'S' | b'T' | b'C' | b'N' | b'4' | b'n'))
            {
                return Err(err(
                    first_line,
                    format!(
                        "expected 'OFF' (or NOFF, COFF, …), found {}",
                        show(Some(kw))
                    ),
                ));
            }
            if prefix.contains(&b'4') || prefix.contains(&b'n') {
                return Err(LoadError::new(
                    path,
                    ErrorKind::Unsupported,
                    Location::Line(first_line),
                    "4OFF and nOFF (other than 3 dimensions) are not supported",
                ));
            }
            normals = prefix.contains(&b'N');
            if toks.clone().next() == Some(b"BINARY") {
                return Err(LoadError::new(
                    path,
                    ErrorKind::Unsupported,
                    Location::Line(first_line),
                    "binary OFF is not supported",
                ));
            }
            counts_toks = toks;
        } else if parse_u64(kw).is_none() {
            return Err(err(
                first_line,
                format!(
                    "expected 'OFF' (or NOFF, COFF, …), found {}",
                    show(Some(kw))
                ),
            ));
        }
    }
    // Counts: on the keyword line, or the next line.
    let (count_line, mut counts_toks) = if counts_toks.clone().next().is_some() {
        (first_line, counts_toks)
    } else {
        match lines.next() {
            Some((n, l)) => (n, Tokens::new(l)),
            None => {
                return Err(err(
                    first_line,
                    "file ends before the vertex and face counts (truncated?)".into(),
                ))
            }
        }
    };
    let mut count = |what: &str| {
        let t = counts_toks.next();
        t.and_then(parse_u64).ok_or_else(|| {
            err(
                count_line,
                format!("expected the {what} count, found {}", show(t)),
            )
        })
    };
    let nv = count("vertex")?;
    let nf = count("face")?;
    if nv > u32::MAX as u64 {
        return Err(err(
            count_line,
            format!("{nv} vertices is more than 32-bit indices can address"),
        ));
    }
    // Each vertex line takes at least 6 bytes ("0 0 0\n").
    let cap = (nv as usize).min(data.len() / 6);
    let mut positions = Vec::with_capacity(cap);
    let mut nrm = Vec::with_capacity(if normals { cap } else { 0 });
    let mut last = count_line;
    for i in 0..nv {
        let Some((n, l)) = lines.next() else {
            return Err(err(
                last,
                format!("file ends inside vertex {i} of {nv} (truncated?)"),
            ));
        };
        last = n;
        let mut toks = Tokens::new(l);
        // Read as f32 (widened exactly), or to the text's digits when the
        // origin may move to keep them.
        let wide = far.keeps_precision();
        let mut read3 = |what: &str| -> Result<[f64; 3], LoadError> {
            let mut c = [0.0f64; 3];
            for x in &mut c {
                let t = toks.next();
                let parsed = if wide {
                    t.and_then(parse_f64)
                } else {
                    t.and_then(parse_f32).map(f64::from)
                };
                match parsed {
                    Some(v) if v.is_finite() => *x = v,
                    Some(_) => {
                        return Err(err(
                            n,
                            format!(
                                "{what} {i} of {nv}: expected 3 finite numbers, found {}",
                                show(t)
                            ),
                        ))
                    }
                    None => {
                        return Err(err(
                            n,
                            format!("{what} {i} of {nv}: expected 3 numbers, found {}", show(t)),
                        ))
                    }
                }
            }
            Ok(c)
        };
        let p = read3("vertex")?;
        let stored = if wide {
            far.place(p)
        } else {
            Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32)
        };
        if let Some(e) = out_of_range(p, stored) {
            return Err(err(n, format!("vertex {i} of {nv}: {e}")));
        }
        positions.push(stored);
        if normals {
            let n = read3("normal of vertex")?;
            nrm.push(Vec3::new(n[0] as f32, n[1] as f32, n[2] as f32));
        }
    }
    let mut indices = Vec::with_capacity((nf as usize).min(data.len() / 8));
    let mut poly: Vec<u32> = Vec::new();
    let mut faces = Triangulator::default();
    for i in 0..nf {
        let Some((n, l)) = lines.next() else {
            return Err(err(
                last,
                format!("file ends inside face {i} of {nf} (truncated?)"),
            ));
        };
        last = n;
        let mut toks = Tokens::new(l);
        let t = toks.next();
        let k = t.and_then(parse_u64).ok_or_else(|| {
            err(
                n,
                format!(
                    "face {i} of {nf}: expected the vertex count, found {}",
                    show(t)
                ),
            )
        })?;
        if k < 3 {
            return Err(err(
                n,
                format!("face {i} of {nf} has {k} vertices; expected at least 3"),
            ));
        }
        poly.clear();
        for _ in 0..k {
            let t = toks.next();
            let idx = t.and_then(parse_u64).ok_or_else(|| {
                err(
                    n,
                    format!(
                        "face {i} of {nf}: expected {k} vertex indices, found {}",
                        show(t)
                    ),
                )
            })?;
            if idx >= nv {
                return Err(err(
                    n,
                    format!(
                        "face {i} of {nf}: vertex index {idx} is out of range (the file has {nv} vertices)"
                    ),
                ));
            }
            poly.push(idx as u32);
        }
        faces.cut_face(&poly, &positions, &mut indices);
    }
    let mut warnings = Vec::new();
    if let Some((n, _)) = lines.next() {
        warnings.push(format!("data after the last face (line {n}) ignored"));
    }
    let mut mesh = TriangleMesh::new(positions, indices);
    if normals {
        mesh.normals = Some(nrm);
    }
    Ok((finish(path, mesh, Location::Line(last))?, warnings))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn parse(s: &str) -> Result<TriangleMesh, LoadError> {
        parse_off(Path::new("a.off"), s.as_bytes(), &mut FarOrigin::new(false)).map(|r| r.0)
    }

    #[test]
    fn variants_comments_and_quads() {
        let m =
            parse("OFF\n# c\n4 1 0\n0 0 0\n1 0 0 # x\n1 1 0\n0 1 0\n4 0 1 2 3 255 0 0\n").unwrap();
        assert_eq!(m.indices, vec![[0, 1, 2], [0, 2, 3]]);
        let m =
            parse("COFF 3 1 0\n0 0 0 1 1 1 1\n1 0 0 1 1 1 1\n0 1 0 1 1 1 1\n3 0 1 2\n").unwrap();
        assert_eq!(m.positions[1], Vec3::X);
        let m = parse("NOFF\n3 1 0\n0 0 0 0 0 1\n1 0 0 0 0 1\n0 1 0 0 0 1\n3 0 1 2\n").unwrap();
        assert_eq!(m.normals.unwrap(), vec![Vec3::Z; 3]);
        let m = parse("3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 2\n").unwrap();
        assert_eq!(m.num_triangles(), 1);
    }

    #[test]
    fn errors_name_lines() {
        let e = parse("OFF\n3 1 0\n0 0 0\n1 0 0\n").unwrap_err().to_string();
        assert_eq!(e, "a.off:4: file ends inside vertex 2 of 3 (truncated?)");
        let e = parse("OFF\n3 1 0\n0 0 0\n1 0 0\n0 1 0\n3 0 1 3\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("a.off:6: face 0 of 1: vertex index 3 is out of range"),
            "{e}"
        );
        let e = parse("OFF\n3 1 0\n0 0 0\n1 0 0\n0 inf 0\n3 0 1 2\n")
            .unwrap_err()
            .to_string();
        assert!(
            e.starts_with("a.off:5: vertex 2 of 3: expected 3 finite"),
            "{e}"
        );
        let e = parse("OFX\n").unwrap_err().to_string();
        assert!(e.starts_with("a.off:1: expected 'OFF'"), "{e}");
        let e = parse("OFF\n0 0 0\n").unwrap_err().to_string();
        assert!(e.starts_with("a.off:2: the file has no triangles"), "{e}");
    }
}
