//! OBJ and MTL output.

use super::check;
use raykit_core::{Material, TriangleMesh};
use std::io::{self, Write};

/// Write `mesh` as OBJ: positions, texture coordinates and normals when
/// present, parts as `g` groups, materials as `usemtl` (with `mtllib` when
/// given). Numbers are written with the shortest text that reads back exactly.
pub fn write_obj(w: &mut dyn Write, mesh: &TriangleMesh, mtllib: Option<&str>) -> io::Result<()> {
    check(mesh)?;
    writeln!(w, "# written by raykit-io")?;
    if let Some(lib) = mtllib {
        writeln!(w, "mtllib {lib}")?;
    }
    for p in &mesh.positions {
        writeln!(w, "v {} {} {}", p.x, p.y, p.z)?;
    }
    if let Some(uvs) = &mesh.uvs {
        for t in uvs {
            writeln!(w, "vt {} {}", t.x, t.y)?;
        }
    }
    if let Some(ns) = &mesh.normals {
        for n in ns {
            writeln!(w, "vn {} {} {}", n.x, n.y, n.z)?;
        }
    }
    let (uv, nr) = (mesh.uvs.is_some(), mesh.normals.is_some());
    let mut part = u32::MAX;
    let mut mat = u32::MAX;
    for (i, t) in mesh.indices.iter().enumerate() {
        if !mesh.parts.is_empty() && mesh.part_of(i) != part {
            part = mesh.part_of(i);
            let name = mesh
                .parts
                .get(part as usize)
                .map_or("", |p| p.name.as_str());
            writeln!(w, "g {name}")?;
        }
        if !mesh.materials.is_empty() && mesh.material_of(i) != mat {
            mat = mesh.material_of(i);
            let name = mesh
                .materials
                .get(mat as usize)
                .map_or("default", |m| m.name.as_str());
            writeln!(w, "usemtl {name}")?;
        }
        w.write_all(b"f")?;
        for &v in t {
            let v = v + 1;
            match (uv, nr) {
                (false, false) => write!(w, " {v}")?,
                (true, false) => write!(w, " {v}/{v}")?,
                (false, true) => write!(w, " {v}//{v}")?,
                (true, true) => write!(w, " {v}/{v}/{v}")?,
            }
        }
        w.write_all(b"\n")?;
    }
    Ok(())
}

/// Write `materials` as an MTL library (the fields [`crate::load_mesh`] reads).
pub fn write_mtl(w: &mut dyn Write, materials: &[Material]) -> io::Result<()> {
    writeln!(w, "# written by raykit-io")?;
    for m in materials {
        let [r, g, b] = m.diffuse;
        writeln!(w, "newmtl {}", m.name)?;
        writeln!(w, "Kd {r} {g} {b}")?;
        let [r, g, b] = m.specular;
        writeln!(w, "Ks {r} {g} {b}")?;
        let [r, g, b] = m.emission;
        writeln!(w, "Ke {r} {g} {b}")?;
        writeln!(w, "Ns {}", m.shininess)?;
        writeln!(w, "Ni {}", m.ior)?;
        writeln!(w, "d {}", 1.0 - m.transmission)?;
        writeln!(w, "illum {}", if m.reflectivity > 0.0 { 3 } else { 2 })?;
        if let Some(t) = &m.diffuse_texture {
            writeln!(w, "map_Kd {t}")?;
        }
    }
    Ok(())
}
