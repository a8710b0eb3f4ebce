//! STL output (ASCII or binary). STL has no indices: every triangle stores its
//! three corners.

use super::check;
use crate::format::StlEncoding;
use raykit_core::TriangleMesh;
use std::io::{self, Write};

/// Write `mesh` as STL with unit facet normals. The binary header never starts
/// with `solid`.
pub fn write_stl(w: &mut dyn Write, mesh: &TriangleMesh, enc: StlEncoding) -> io::Result<()> {
    check(mesh)?;
    match enc {
        StlEncoding::Ascii => {
            writeln!(w, "solid raykit")?;
            for i in 0..mesh.num_triangles() {
                let n = mesh.unit_normal(i);
                writeln!(w, " facet normal {} {} {}\n  outer loop", n.x, n.y, n.z)?;
                for p in mesh.triangle(i) {
                    writeln!(w, "   vertex {} {} {}", p.x, p.y, p.z)?;
                }
                writeln!(w, "  endloop\n endfacet")?;
            }
            writeln!(w, "endsolid raykit")
        }
        StlEncoding::Binary => {
            let n = u32::try_from(mesh.num_triangles()).map_err(|_| {
                io::Error::new(io::ErrorKind::InvalidInput, "too many triangles for STL")
            })?;
            let mut header = [b' '; 80];
            let text = b"binary STL written by raykit-io";
            header[..text.len()].copy_from_slice(text);
            w.write_all(&header)?;
            w.write_all(&n.to_le_bytes())?;
            let mut rec = [0u8; 50];
            for i in 0..mesh.num_triangles() {
                let nrm = mesh.unit_normal(i);
                let [a, b, c] = mesh.triangle(i);
                for (k, v) in [nrm, a, b, c].iter().enumerate() {
                    for (j, x) in v.to_array().iter().enumerate() {
                        let o = 12 * k + 4 * j;
                        rec[o..o + 4].copy_from_slice(&x.to_le_bytes());
                    }
                }
                w.write_all(&rec)?;
            }
            Ok(())
        }
    }
}
