//! The text header of a PLY file: encoding, elements and their properties.

use crate::error::{show, LoadError};
use crate::format::PlyEncoding;
use crate::text::{parse_u64, Tokens};
use std::path::Path;

/// A PLY scalar type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Scalar {
    I8,
    U8,
    I16,
    U16,
    I32,
    U32,
    F32,
    F64,
}

impl Scalar {
    fn parse(t: &[u8]) -> Option<Scalar> {
        Some(match t {
            b"char" | b"int8" => Scalar::I8,
            b"uchar" | b"uint8" => Scalar::U8,
            b"short" | b"int16" => Scalar::I16,
            b"ushort" | b"uint16" => Scalar::U16,
            b"int" | b"int32" => Scalar::I32,
            b"uint" | b"uint32" => Scalar::U32,
            b"float" | b"float32" => Scalar::F32,
            b"double" | b"float64" => Scalar::F64,
            _ => return None,
        })
    }

    /// Size in bytes in binary files.
    pub(crate) fn size(self) -> usize {
        match self {
            Scalar::I8 | Scalar::U8 => 1,
            Scalar::I16 | Scalar::U16 => 2,
            Scalar::I32 | Scalar::U32 | Scalar::F32 => 4,
            Scalar::F64 => 8,
        }
    }

    /// True for the integer types.
    pub(crate) fn is_int(self) -> bool {
        !matches!(self, Scalar::F32 | Scalar::F64)
    }

    /// The PLY name.
    pub(crate) fn name(self) -> &'static str {
        match self {
            Scalar::I8 => "char",
            Scalar::U8 => "uchar",
            Scalar::I16 => "short",
            Scalar::U16 => "ushort",
            Scalar::I32 => "int",
            Scalar::U32 => "uint",
            Scalar::F32 => "float",
            Scalar::F64 => "double",
        }
    }
}

/// A property: a scalar, or a list with a count type and an item type.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PropKind {
    Scalar(Scalar),
    List { count: Scalar, item: Scalar },
}

/// One `property` line.
#[derive(Clone, Debug)]
pub(crate) struct Property {
    pub name: String,
    pub kind: PropKind,
    /// Header line, for errors about the property.
    pub line: usize,
}

/// One `element` line and its properties.
#[derive(Clone, Debug)]
pub(crate) struct Element {
    pub name: String,
    pub count: u64,
    pub props: Vec<Property>,
    pub line: usize,
}

impl Element {
    /// Smallest possible size of one record: bytes in binary, and in ASCII at
    /// least two characters per value.
    pub(crate) fn min_record_size(&self, encoding: PlyEncoding) -> usize {
        let s: usize = self
            .props
            .iter()
            .map(|p| match (encoding, p.kind) {
                (PlyEncoding::Ascii, _) => 2,
                (_, PropKind::Scalar(s)) => s.size(),
                (_, PropKind::List { count, .. }) => count.size(),
            })
            .sum();
        s.max(1)
    }

    /// Index of the property named `name`.
    pub(crate) fn find(&self, name: &str) -> Option<usize> {
        self.props.iter().position(|p| p.name == name)
    }
}

/// A parsed header.
#[derive(Clone, Debug)]
pub(crate) struct Header {
    pub encoding: PlyEncoding,
    pub elements: Vec<Element>,
    /// Byte offset of the body.
    pub body_start: usize,
    /// Line number of the first body line (for ASCII).
    pub body_line: usize,
}

/// Parse the header at the start of `data`.
pub(crate) fn parse_header(path: &Path, data: &[u8]) -> Result<Header, LoadError> {
    let err = |line: usize, msg: String| LoadError::at_line(path, line, msg);
    let mut pos = 0usize;
    let mut line = 0usize;
    let mut encoding = None;
    let mut elements: Vec<Element> = Vec::new();
    loop {
        if pos >= data.len() {
            return Err(err(
                line.max(1),
                "the header never ends: missing 'end_header' (truncated?)".into(),
            ));
        }
        let rest = &data[pos..];
        let (text, advance) = match rest.iter().position(|&b| b == b'\n') {
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        line += 1;
        pos += advance;
        let text = text.strip_suffix(b"\r").unwrap_or(text);
        if line == 1 {
            if text.trim_ascii_end() != b"ply" {
                return Err(err(
                    1,
                    format!(
                        "not a PLY file: expected 'ply' on the first line, found {}",
                        show(Some(text))
                    ),
                ));
            }
            continue;
        }
        let mut toks = Tokens::new(text);
        let Some(key) = toks.next() else { continue };
        match key {
            b"comment" | b"obj_info" => {}
            b"format" => {
                let t = toks.next();
                encoding = Some(match t {
                    Some(b"ascii") => PlyEncoding::Ascii,
                    Some(b"binary_little_endian") => PlyEncoding::BinaryLittleEndian,
                    Some(b"binary_big_endian") => PlyEncoding::BinaryBigEndian,
                    _ => {
                        return Err(err(
                            line,
                            format!(
                                "expected 'ascii', 'binary_little_endian' or \
                                 'binary_big_endian' after 'format', found {}",
                                show(t)
                            ),
                        ))
                    }
                });
            }
            b"element" => {
                let name = toks.next();
                let count_tok = toks.next();
                let (Some(name), Some(count)) = (name, count_tok.and_then(parse_u64)) else {
                    return Err(err(
                        line,
                        format!(
                            "expected a name and a count after 'element', found {}",
                            show(count_tok.or(name))
                        ),
                    ));
                };
                elements.push(Element {
                    name: String::from_utf8_lossy(name).into_owned(),
                    count,
                    props: Vec::new(),
                    line,
                });
            }
            b"property" => {
                let Some(el) = elements.last_mut() else {
                    return Err(err(line, "'property' before the first 'element'".into()));
                };
                let t = toks.next();
                let kind = if t == Some(b"list") {
                    let c = toks.next();
                    let i = toks.next();
                    match (c.and_then(Scalar::parse), i.and_then(Scalar::parse)) {
                        (Some(count), Some(item)) if count.is_int() => {
                            PropKind::List { count, item }
                        }
                        _ => {
                            return Err(err(
                                line,
                                format!(
                                    "expected an integer count type and an item type after \
                                     'property list', found {} {}",
                                    show(c),
                                    show(i)
                                ),
                            ))
                        }
                    }
                } else {
                    match t.and_then(Scalar::parse) {
                        Some(s) => PropKind::Scalar(s),
                        None => {
                            return Err(err(
                                line,
                                format!(
                                    "expected a type (char, uchar, short, ushort, int, uint, \
                                     float, double or list) after 'property', found {}",
                                    show(t)
                                ),
                            ))
                        }
                    }
                };
                let Some(name) = toks.next() else {
                    return Err(err(line, "expected a property name".into()));
                };
                el.props.push(Property {
                    name: String::from_utf8_lossy(name).into_owned(),
                    kind,
                    line,
                });
            }
            b"end_header" => break,
            _ => {
                return Err(err(
                    line,
                    format!(
                        "expected 'format', 'element', 'property', 'comment' or 'end_header', \
                         found {}",
                        show(Some(key))
                    ),
                ))
            }
        }
    }
    let Some(encoding) = encoding else {
        return Err(err(line, "the header has no 'format' line".into()));
    };
    Ok(Header {
        encoding,
        elements,
        body_start: pos,
        body_line: line + 1,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parses_elements_properties_and_body_start() {
        let src = b"ply\r\nformat binary_big_endian 1.0\r\ncomment hi\r\nelement vertex 3\r\n\
property double x\r\nproperty list uint8 int32 idx\r\nelement face 0\r\nend_header\r\nBODY";
        let h = parse_header(Path::new("a.ply"), src).unwrap();
        assert_eq!(h.encoding, PlyEncoding::BinaryBigEndian);
        assert_eq!(h.elements.len(), 2);
        assert_eq!(h.elements[0].count, 3);
        assert_eq!(h.elements[0].props[0].kind, PropKind::Scalar(Scalar::F64));
        assert_eq!(
            h.elements[0].props[1].kind,
            PropKind::List {
                count: Scalar::U8,
                item: Scalar::I32
            }
        );
        assert_eq!(&src[h.body_start..], b"BODY");
        assert_eq!(h.body_line, 9);
    }

    #[test]
    fn header_errors_name_the_line() {
        let p = Path::new("a.ply");
        let e = parse_header(p, b"plx\n").unwrap_err().to_string();
        assert!(e.starts_with("a.ply:1: not a PLY file"), "{e}");
        let e = parse_header(p, b"ply\nformat ascii 1.0\nelement vertex\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("a.ply:3: expected a name and a count"), "{e}");
        let e = parse_header(p, b"ply\nformat ascii 1.0\nelement v 1\nproperty flt x\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("a.ply:4: expected a type"), "{e}");
        let e = parse_header(p, b"ply\nformat ascii 1.0\n")
            .unwrap_err()
            .to_string();
        assert!(e.contains("missing 'end_header'"), "{e}");
        let e = parse_header(p, b"ply\nelement v 1\nend_header\n")
            .unwrap_err()
            .to_string();
        assert!(e.starts_with("a.ply:3: the header has no 'format'"), "{e}");
    }
}
