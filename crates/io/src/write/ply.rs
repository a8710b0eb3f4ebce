//! PLY output (ASCII or binary of either byte order).

use super::check;
use crate::format::PlyEncoding;
use raykit_core::TriangleMesh;
use std::io::{self, Write};

/// Write `mesh` as PLY: float `x y z` (plus `nx ny nz` and `u v` when present)
/// and `list uchar uint vertex_indices` faces.
pub fn write_ply(w: &mut dyn Write, mesh: &TriangleMesh, enc: PlyEncoding) -> io::Result<()> {
    check(mesh)?;
    let name = match enc {
        PlyEncoding::Ascii => "ascii",
        PlyEncoding::BinaryLittleEndian => "binary_little_endian",
        PlyEncoding::BinaryBigEndian => "binary_big_endian",
    };
    write!(
        w,
        "ply\nformat {name} 1.0\ncomment written by raykit-io\nelement vertex {}\n\
         property float x\nproperty float y\nproperty float z\n",
        mesh.positions.len()
    )?;
    if mesh.normals.is_some() {
        w.write_all(b"property float nx\nproperty float ny\nproperty float nz\n")?;
    }
    if mesh.uvs.is_some() {
        w.write_all(b"property float u\nproperty float v\n")?;
    }
    write!(
        w,
        "element face {}\nproperty list uchar uint vertex_indices\nend_header\n",
        mesh.indices.len()
    )?;
    let mut vals: Vec<f32> = Vec::with_capacity(8);
    let mut buf: Vec<u8> = Vec::with_capacity(1 << 16);
    for i in 0..mesh.positions.len() {
        vals.clear();
        vals.extend(mesh.positions[i].to_array());
        if let Some(n) = &mesh.normals {
            vals.extend(n[i].to_array());
        }
        if let Some(t) = &mesh.uvs {
            vals.extend(t[i].to_array());
        }
        match enc {
            PlyEncoding::Ascii => {
                let mut first = true;
                for v in &vals {
                    if !first {
                        buf.push(b' ');
                    }
                    first = false;
                    write!(buf, "{v}")?;
                }
                buf.push(b'\n');
            }
            PlyEncoding::BinaryLittleEndian => {
                vals.iter().for_each(|v| buf.extend(v.to_le_bytes()));
            }
            PlyEncoding::BinaryBigEndian => {
                vals.iter().for_each(|v| buf.extend(v.to_be_bytes()));
            }
        }
        flush_if_full(w, &mut buf)?;
    }
    for t in &mesh.indices {
        match enc {
            PlyEncoding::Ascii => writeln!(buf, "3 {} {} {}", t[0], t[1], t[2])?,
            PlyEncoding::BinaryLittleEndian => {
                buf.push(3);
                t.iter().for_each(|v| buf.extend(v.to_le_bytes()));
            }
            PlyEncoding::BinaryBigEndian => {
                buf.push(3);
                t.iter().for_each(|v| buf.extend(v.to_be_bytes()));
            }
        }
        flush_if_full(w, &mut buf)?;
    }
    w.write_all(&buf)
}

fn flush_if_full(w: &mut dyn Write, buf: &mut Vec<u8>) -> io::Result<()> {
    if buf.len() >= 60_000 {
        w.write_all(buf)?;
        buf.clear();
    }
    Ok(())
}
