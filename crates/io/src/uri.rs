//! The URI forms glTF buffers use: `data:` URIs with base64 payloads and
//! percent-encoded relative file paths. Also base64 encoding for the writer.

use std::io::Read;
use std::path::{Component, Path, PathBuf};

/// Decode standard base64 (padding optional, whitespace ignored).
/// `Err` holds the offset of the first invalid character.
pub(crate) fn base64_decode(s: &[u8]) -> Result<Vec<u8>, usize> {
    let mut out = Vec::with_capacity(s.len() / 4 * 3 + 3);
    let mut acc: u32 = 0;
    let mut bits = 0;
    let mut ended = false;
    for (i, &c) in s.iter().enumerate() {
        let v = match c {
            b'A'..=b'Z' => c - b'A',
            b'a'..=b'z' => c - b'a' + 26,
            b'0'..=b'9' => c - b'0' + 52,
            b'+' | b'-' => 62,
            b'/' | b'_' => 63,
            b'=' => {
                ended = true;
                continue;
            }
            c if c.is_ascii_whitespace() => continue,
            _ => return Err(i),
        };
        if ended {
            return Err(i);
        }
        acc = (acc << 6) | v as u32;
        bits += 6;
        if bits >= 8 {
            bits -= 8;
            out.push((acc >> bits) as u8);
            acc &= (1 << bits) - 1;
        }
    }
    Ok(out)
}

/// The payload of a `data:` URI: base64-decoded when the header ends in
/// `;base64`, percent-decoded otherwise. `None` when `uri` is not a data URI;
/// `Some(Err(at))` gives the offset of the first invalid base64 character
/// within the payload.
pub(crate) fn data_uri_payload(uri: &str) -> Option<Result<Vec<u8>, usize>> {
    if !uri.starts_with("data:") {
        return None;
    }
    let (head, payload) = uri.split_once(',').unwrap_or((uri, ""));
    Some(if head.ends_with(";base64") {
        base64_decode(payload.as_bytes())
    } else {
        Ok(percent_decode(payload).into_bytes())
    })
}

/// Encode as standard base64 with padding.
pub(crate) fn base64_encode(data: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(data.len().div_ceil(3) * 4);
    for c in data.chunks(3) {
        let b = [c[0], *c.get(1).unwrap_or(&0), *c.get(2).unwrap_or(&0)];
        let n = (b[0] as u32) << 16 | (b[1] as u32) << 8 | b[2] as u32;
        for k in 0..4 {
            if k <= c.len() {
                out.push(A[(n >> (18 - 6 * k) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

/// Decode `%XX` escapes in a relative URI (invalid escapes are kept as is).
pub(crate) fn percent_decode(s: &str) -> String {
    let b = s.as_bytes();
    let mut out = Vec::with_capacity(b.len());
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' && i + 2 < b.len() {
            let hex = |c: u8| (c as char).to_digit(16);
            if let (Some(h), Some(l)) = (hex(b[i + 1]), hex(b[i + 2])) {
                out.push((h * 16 + l) as u8);
                i += 3;
                continue;
            }
        }
        out.push(b[i]);
        i += 1;
    }
    String::from_utf8_lossy(&out).into_owned()
}

/// The file that a glTF file's external `uri` names: a relative path,
/// percent-decoded, beside or below `dir` (the glTF file's folder). URIs with a scheme
/// (`http:`, `file:`), absolute paths and paths with `..` are refused, so
/// that a scene file (one a server was handed, say) brings in no file from
/// elsewhere.
pub(crate) fn external_file(dir: &Path, uri: &str) -> Result<PathBuf, String> {
    let rel = percent_decode(uri);
    if rel.is_empty() {
        return Err("the uri is empty".into());
    }
    if let Some((scheme, _)) = rel.split_once(':') {
        if !scheme.contains('/') {
            return Err(format!(
                "\"{uri}\" has a scheme ({scheme}:); only data: URIs and relative file paths are read"
            ));
        }
    }
    file_below(dir, &rel).map_err(|_| {
        format!(
            "\"{uri}\" leaves the folder of the file naming it; only files beside or below it are read"
        )
    })
}

/// `dir` joined with the relative path `rel` when it stays beside or below
/// `dir` (no root, no `..`); `Err` with the same refusal as
/// [`external_file`] otherwise.
fn file_below(dir: &Path, rel: &str) -> Result<PathBuf, String> {
    for part in Path::new(rel).components() {
        if !matches!(part, Component::Normal(_) | Component::CurDir) {
            return Err(format!(
                "\"{rel}\" leaves the folder of the file naming it; only files beside or below it are read"
            ));
        }
    }
    Ok(dir.join(rel))
}

/// At most `max` bytes of `file`, which must be a regular file (not a
/// device, pipe or folder, whose reads need not end).
pub(crate) fn read_external(file: &Path, max: u64) -> Result<Vec<u8>, String> {
    let cannot = |e: std::io::Error| format!("cannot read {}: {e}", file.display());
    let meta = std::fs::metadata(file).map_err(cannot)?;
    if !meta.is_file() {
        return Err(format!(
            "{}: {}",
            file.display(),
            crate::input::not_a_regular_file(&meta)
        ));
    }
    let mut out = Vec::new();
    std::fs::File::open(file)
        .and_then(|f| f.take(max).read_to_end(&mut out))
        .map_err(cannot)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn base64_round_trip_and_errors() {
        for n in 0..20 {
            let data: Vec<u8> = (0..n).map(|i| (i * 37 + 11) as u8).collect();
            let e = base64_encode(&data);
            assert_eq!(e.len() % 4, 0);
            assert_eq!(base64_decode(e.as_bytes()).unwrap(), data);
        }
        assert_eq!(base64_encode(b"Man"), "TWFu");
        assert_eq!(base64_encode(b"Ma"), "TWE=");
        assert_eq!(base64_decode(b"TWE").unwrap(), b"Ma");
        assert_eq!(base64_decode(b"TW!u"), Err(2));
        assert_eq!(base64_decode(b"TW=u"), Err(3));
    }

    #[test]
    fn data_uris() {
        assert_eq!(data_uri_payload("a.bin"), None);
        assert_eq!(
            data_uri_payload("data:application/octet-stream;base64,TWFu"),
            Some(Ok(b"Man".to_vec()))
        );
        assert_eq!(
            data_uri_payload("data:text/plain,a%20b"),
            Some(Ok(b"a b".to_vec()))
        );
        assert_eq!(data_uri_payload("data:x;base64,TW!u"), Some(Err(2)));
    }

    #[test]
    fn percent_escapes() {
        assert_eq!(percent_decode("a%20b.bin"), "a b.bin");
        assert_eq!(percent_decode("100%"), "100%");
        assert_eq!(percent_decode("%zz%4"), "%zz%4");
    }
}
