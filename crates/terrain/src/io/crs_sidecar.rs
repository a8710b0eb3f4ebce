//! A coordinate system given as WKT, written beside a GeoTIFF in GDAL's
//! persistent auxiliary metadata (PAM) file, `NAME.aux.xml`.
//!
//! An Esri ASCII grid's `.prj` holds its coordinate system as WKT, often in
//! Esri's dialect without EPSG codes, which GeoTIFF's GeoKeys cannot hold
//! without a full WKT-to-GeoKeys translation. GDAL reads the `<SRS>` of a
//! raster's `.aux.xml` when the file itself declares none, and so do the
//! tools built on it (rasterio, QGIS): a mask computed from such a grid
//! lands in the grid's coordinate system there.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::DemError;

/// The PAM file of the raster at `path`: `path` with `.aux.xml` appended.
pub fn crs_sidecar_path(path: &Path) -> PathBuf {
    let mut name = path.as_os_str().to_owned();
    name.push(".aux.xml");
    PathBuf::from(name)
}

/// Write `wkt` as the coordinate system of the raster at `path` into its
/// PAM file ([`crs_sidecar_path`]), atomically, replacing any there.
pub fn write_crs_sidecar(path: &Path, wkt: &str) -> Result<(), DemError> {
    let sidecar = crs_sidecar_path(path);
    let xml = format!(
        "<PAMDataset>\n  <SRS>{}</SRS>\n</PAMDataset>\n",
        xml_escaped(wkt)
    );
    let error = |e: std::io::Error| DemError::new(&sidecar, "write", e.to_string());
    raykit_io::write_atomic_file(
        &sidecar,
        |w| w.write_all(xml.as_bytes()).map_err(error),
        error,
    )
}

/// `text` with XML's five special characters escaped.
fn xml_escaped(text: &str) -> String {
    let mut out = String::with_capacity(text.len() + text.len() / 8);
    for c in text.chars() {
        match c {
            '&' => out.push_str("&amp;"),
            '<' => out.push_str("&lt;"),
            '>' => out.push_str("&gt;"),
            '"' => out.push_str("&quot;"),
            '\'' => out.push_str("&apos;"),
            c => out.push(c),
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn special_characters_are_escaped_and_the_name_appended() {
        assert_eq!(
            xml_escaped(r#"PROJCS["a<b>&'c"]"#),
            "PROJCS[&quot;a&lt;b&gt;&amp;&apos;c&quot;]"
        );
        assert_eq!(
            crs_sidecar_path(Path::new("out/mask.tif")),
            PathBuf::from("out/mask.tif.aux.xml")
        );
    }
}
