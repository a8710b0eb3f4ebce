//! OFF output.

use super::check;
use raykit_core::TriangleMesh;
use std::io::{self, Write};

/// Write `mesh` as OFF (`OFF`, counts, `x y z` lines, `3 a b c` lines), or
/// as `NOFF` with `x y z nx ny nz` lines when the mesh has normals. Texture
/// coordinates are not written.
pub fn write_off(w: &mut dyn Write, mesh: &TriangleMesh) -> io::Result<()> {
    check(mesh)?;
    let kw = if mesh.normals.is_some() {
        "NOFF"
    } else {
        "OFF"
    };
    writeln!(w, "{kw}\n{} {} 0", mesh.positions.len(), mesh.indices.len())?;
    for (i, p) in mesh.positions.iter().enumerate() {
        match &mesh.normals {
            Some(n) => {
                let n = n[i];
                writeln!(w, "{} {} {} {} {} {}", p.x, p.y, p.z, n.x, n.y, n.z)?
            }
            None => writeln!(w, "{} {} {}", p.x, p.y, p.z)?,
        }
    }
    for t in &mesh.indices {
        writeln!(w, "3 {} {} {}", t[0], t[1], t[2])?;
    }
    Ok(())
}
