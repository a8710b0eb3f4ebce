//! The band scale and offset GDAL keeps in its GDAL_METADATA tag (42112),
//! an XML list of items such as
//! `<Item name="SCALE" sample="0" role="scale">0.01</Item>`: a DEM stored
//! as integers in centimetres, or as Terragen's raw units, reads as heights
//! only with them applied (`height = raw × scale + offset`, GDAL's
//! unscaling).

/// TIFF tag GDAL_METADATA (ASCII XML).
pub const TAG_GDAL_METADATA: u16 = 42112;

/// The first band's scale and offset in GDAL_METADATA `xml`: (1, 0) where
/// an item is missing; an item whose value is not a finite number is
/// returned as its text, for the caller's error.
pub fn band_scale_offset(xml: &str) -> Result<(f64, f64), String> {
    let mut out = (1.0, 0.0);
    for item in xml.split("<Item").skip(1) {
        let Some((attrs, rest)) = item.split_once('>') else {
            continue;
        };
        let value = rest.split('<').next().unwrap_or("").trim();
        let attr = |name: &str| {
            let key = format!("{name}=\"");
            attrs
                .find(&key)
                .map(|i| &attrs[i + key.len()..])
                .and_then(|v| v.split('"').next())
        };
        if attr("sample").is_some_and(|s| s != "0") {
            continue;
        }
        let slot = match attr("role") {
            Some("scale") => &mut out.0,
            Some("offset") => &mut out.1,
            _ => continue,
        };
        *slot = value
            .parse::<f64>()
            .ok()
            .filter(|v| v.is_finite())
            .ok_or_else(|| value.to_string())?;
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gdal_items_give_the_first_bands_scale_and_offset() {
        let xml = "<GDALMetadata>\n  <Item name=\"DataType\">Generic</Item>\n  \
                   <Item name=\"OFFSET\" sample=\"0\" role=\"offset\">468.75</Item>\n  \
                   <Item name=\"SCALE\" sample=\"0\" role=\"scale\">0.0214600000000000002</Item>\n  \
                   <Item name=\"SCALE\" sample=\"1\" role=\"scale\">7</Item>\n</GDALMetadata>";
        assert_eq!(band_scale_offset(xml), Ok((0.02146, 468.75)));
        assert_eq!(
            band_scale_offset("<GDALMetadata></GDALMetadata>"),
            Ok((1.0, 0.0))
        );
        assert_eq!(
            band_scale_offset("<Item name=\"SCALE\" sample=\"0\" role=\"scale\">x</Item>"),
            Err("x".to_string())
        );
    }
}
