//! A coordinate system given as WKT, written beside a GeoTIFF in GDAL's
//! persistent auxiliary metadata (PAM) file, `NAME.aux.xml`.
//!
//! An Esri ASCII grid's `.prj` holds its coordinate system as WKT, often in
//! Esri's dialect without EPSG codes, which GeoTIFF's GeoKeys cannot hold
//! without a full WKT-to-GeoKeys translation. GDAL reads the `<SRS>` of a
//! raster's `.aux.xml` when the file itself declares none, and so do the
//! tools built on it (rasterio, QGIS): a mask computed from such a grid
//! lands in the grid's coordinate system there. A GeoTIFF read whose
//! GeoKeys declare no coordinate system takes its sidecar's, so such a mask
//! keeps it through further work.

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

/// Remove the PAM file of the raster at `path`, if any: a raster written
/// anew replaces what its old sidecar said, as GDAL's drivers delete it
/// when they create a file.
pub fn remove_crs_sidecar(path: &Path) -> Result<(), DemError> {
    let sidecar = crs_sidecar_path(path);
    match std::fs::remove_file(&sidecar) {
        Err(e) if e.kind() != std::io::ErrorKind::NotFound => {
            Err(DemError::new(&sidecar, "remove", e.to_string()))
        }
        _ => Ok(()),
    }
}

/// The coordinate system in the PAM file of the raster at `path`: the text
/// of its first `<SRS>` element, unescaped and trimmed; none when there is
/// no such file, it is larger than any PAM file of a raster (1 MiB) or not
/// text, or it holds no non-empty `<SRS>`.
pub fn read_crs_sidecar(path: &Path) -> Option<String> {
    let sidecar = crs_sidecar_path(path);
    let small = std::fs::metadata(&sidecar).is_ok_and(|m| m.len() <= 1 << 20);
    let xml = std::fs::read_to_string(sidecar).ok().filter(|_| small)?;
    let open = xml.find("<SRS")?;
    let after = &xml[open + 4..];
    // `<SRS>` or `<SRS attributes...>`, not `<SRSName>`.
    if !after.starts_with(['>', ' ', '\t', '\n', '\r']) {
        return None;
    }
    let body = &after[after.find('>')? + 1..];
    let wkt = xml_unescaped(&body[..body.find("</SRS>")?]);
    let wkt = wkt.trim();
    (!wkt.is_empty()).then(|| wkt.to_string())
}

/// Whether the coordinate system `wkt` is geographic (longitude and
/// latitude in degrees): WKT 1's `GEOGCS`, WKT 2's `GEOGCRS` or `GEODCRS`.
pub fn wkt_is_geographic(wkt: &str) -> bool {
    let top = wkt.trim_start().to_ascii_uppercase();
    top.starts_with("GEOGCS") || top.starts_with("GEOGCRS") || top.starts_with("GEODCRS")
}

/// `text` with XML's five named entities and numeric character references
/// replaced by their characters; anything else left as it is.
fn xml_unescaped(text: &str) -> String {
    let mut out = String::with_capacity(text.len());
    let mut rest = text;
    while let Some(at) = rest.find('&') {
        out.push_str(&rest[..at]);
        rest = &rest[at..];
        // An entity's name is short; a `;` farther on ends something else.
        let near = &rest.as_bytes()[..rest.len().min(12)];
        let entity = near
            .iter()
            .position(|&b| b == b';')
            .map(|end| (&rest[1..end], end));
        let c = entity.and_then(|(name, _)| match name {
            "amp" => Some('&'),
            "lt" => Some('<'),
            "gt" => Some('>'),
            "quot" => Some('"'),
            "apos" => Some('\''),
            _ => name
                .strip_prefix("#x")
                .map(|h| u32::from_str_radix(h, 16))
                .or_else(|| name.strip_prefix('#').map(str::parse))
                .and_then(Result::ok)
                .and_then(char::from_u32),
        });
        match (c, entity) {
            (Some(c), Some((_, end))) => {
                out.push(c);
                rest = &rest[end + 1..];
            }
            _ => {
                out.push('&');
                rest = &rest[1..];
            }
        }
    }
    out.push_str(rest);
    out
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

    /// What is written is read back, through escaping, beside other PAM
    /// content and with attributes on `<SRS>` as GDAL writes them; files
    /// without a coordinate system give none.
    #[test]
    fn a_written_coordinate_system_reads_back() {
        let dir = std::env::temp_dir().join(format!("raykit-crs-sidecar-{}", std::process::id()));
        std::fs::create_dir_all(&dir).unwrap();
        let tif = dir.join("a.tif");
        let wkt = r#"PROJCS["NAD_1983_UTM_Zone_15N",GEOGCS["GCS_North_American_1983",DATUM["D_North_American_1983",SPHEROID["GRS_1980",6378137.0,298.257222101]],PRIMEM["Greenwich",0.0],UNIT["Degree",0.0174532925199433]],PROJECTION["Transverse_Mercator"],PARAMETER["Scale_Factor",0.9996],UNIT["Meter",1.0]] & <more>"#;
        write_crs_sidecar(&tif, wkt).unwrap();
        assert_eq!(read_crs_sidecar(&tif).as_deref(), Some(wkt));
        assert!(!wkt_is_geographic(wkt));

        let gdal = "<PAMDataset>\n  <SRS dataAxisToSRSAxisMapping=\"2,1\">GEOGCS[&quot;WGS 84&quot;,\
                    DATUM[&#34;x&#x22;]]</SRS>\n  <Metadata><MDI key=\"a\">1</MDI></Metadata>\n</PAMDataset>\n";
        std::fs::write(crs_sidecar_path(&tif), gdal).unwrap();
        let read = read_crs_sidecar(&tif).unwrap();
        assert_eq!(read, r#"GEOGCS["WGS 84",DATUM["x"]]"#);
        assert!(wkt_is_geographic(&read));

        for other in [
            "<PAMDataset><Metadata/></PAMDataset>",
            "<PAMDataset><SRSName>x</SRSName></PAMDataset>",
            "<PAMDataset><SRS>  </SRS></PAMDataset>",
            "<PAMDataset><SRS>unterminated",
        ] {
            std::fs::write(crs_sidecar_path(&tif), other).unwrap();
            assert_eq!(read_crs_sidecar(&tif), None, "{other}");
        }
        remove_crs_sidecar(&tif).unwrap();
        assert!(!crs_sidecar_path(&tif).exists());
        assert_eq!(read_crs_sidecar(&tif), None);
        remove_crs_sidecar(&tif).unwrap();
        std::fs::remove_dir_all(&dir).unwrap();
    }
}
