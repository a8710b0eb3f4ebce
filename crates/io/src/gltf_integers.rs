//! glTF 2.0 indices and enumerations are JSON integers that the `gltf`
//! crate reads as 64-bit and keeps as 32-bit, so `"mesh": 4294967296`
//! becomes mesh 0 and passes validation. Before the document is parsed, the
//! JSON text is scanned for integers beyond `u32::MAX` under any key other
//! than the byte sizes, offsets and counts that glTF allows to be that large;
//! such a file is refused at the integer's line and column.

use crate::error::{ErrorKind, LoadError, Location};
use std::path::Path;

/// Keys whose values the `gltf` crate keeps in 64 bits.
const WIDE_KEYS: &[&str] = &["byteLength", "byteOffset", "count", "byteStride"];

/// Refuse the first integer in `json` (outside strings) that is larger than
/// `u32::MAX` under a key not in [`WIDE_KEYS`]; `glb` says whether the text
/// is a binary glTF's JSON chunk (for the location).
pub(crate) fn check_integer_range(path: &Path, json: &[u8], glb: bool) -> Result<(), LoadError> {
    let mut key: &[u8] = b"";
    let (mut line, mut line_start) = (1usize, 0usize);
    let mut i = 0;
    while i < json.len() {
        match json[i] {
            b'\n' => {
                line += 1;
                line_start = i + 1;
                i += 1;
            }
            b'"' => {
                let start = i + 1;
                let mut j = start;
                while j < json.len() && json[j] != b'"' {
                    j += if json[j] == b'\\' { 2 } else { 1 };
                }
                let end = j.min(json.len());
                let mut k = end + 1;
                while k < json.len() && json[k].is_ascii_whitespace() {
                    k += 1;
                }
                if json.get(k) == Some(&b':') {
                    key = &json[start..end];
                }
                i = end + 1;
            }
            b'0'..=b'9' => {
                let start = i;
                while i < json.len() && json[i].is_ascii_digit() {
                    i += 1;
                }
                let fraction = matches!(json.get(i), Some(b'.' | b'e' | b'E'));
                let digits = &json[start..i];
                let negative = start > 0 && json[start - 1] == b'-';
                let wide = WIDE_KEYS.iter().any(|k| k.as_bytes() == key);
                if !fraction && !negative && !wide && beyond_u32(digits) {
                    let column = start - line_start + 1;
                    let location = if glb {
                        Location::Json(format!("JSON chunk line {line} column {column}"))
                    } else {
                        Location::Line(line)
                    };
                    return Err(LoadError::new(
                        path,
                        ErrorKind::Malformed,
                        location,
                        format!(
                            "\"{}\": {} is beyond any glTF index or enumeration \
                             (at most {}; column {column})",
                            String::from_utf8_lossy(key),
                            String::from_utf8_lossy(digits),
                            u32::MAX
                        ),
                    ));
                }
                // The exponent or fraction of a number is skipped with it.
                while i < json.len()
                    && matches!(json[i], b'0'..=b'9' | b'.' | b'e' | b'E' | b'+' | b'-')
                {
                    i += 1;
                }
            }
            _ => i += 1,
        }
    }
    Ok(())
}

/// Whether the decimal `digits` exceed `u32::MAX`.
fn beyond_u32(digits: &[u8]) -> bool {
    let significant = digits
        .iter()
        .position(|&d| d != b'0')
        .map_or(&digits[..0], |p| &digits[p..]);
    let max = u32::MAX.to_string();
    significant.len() > max.len()
        || (significant.len() == max.len() && significant > max.as_bytes())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn check(json: &str) -> Result<(), LoadError> {
        check_integer_range(Path::new("t.gltf"), json.as_bytes(), false)
    }

    #[test]
    fn indices_beyond_u32_are_refused_and_byte_sizes_are_not() {
        for n in [0u64, 1, 4_294_967_295] {
            assert!(
                check(&format!(r#"{{"nodes":[{{"mesh":{n}}}]}}"#)).is_ok(),
                "{n}"
            );
        }
        for n in [4_294_967_296u64, 8_589_934_592, u64::MAX] {
            let e = check(&format!("{{\n\"nodes\":[{{\"mesh\": {n}}}]}}")).unwrap_err();
            let text = e.to_string();
            assert!(text.starts_with("t.gltf:2: "), "{text}");
            assert!(text.contains(&format!("\"mesh\": {n}")), "{text}");
        }
        let e = check(r#"{"nodes":[{"children":[1, 000004294967296]}]}"#).unwrap_err();
        assert!(e.to_string().contains("\"children\""), "{e}");
        assert!(check(r#"{"buffers":[{"byteLength":8589934592}]}"#).is_ok());
        assert!(check(r#"{"x":{"v":1e300,"w":-99999999999,"s":"99999999999"}}"#).is_ok());
        assert!(check(r#"{"s":"a\"b: 99999999999"}"#).is_ok());
    }
}
