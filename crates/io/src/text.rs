//! Allocation-free scanning of text formats: lines, whitespace-separated
//! tokens and numbers, all as byte slices of the file.

/// Lines of a byte buffer with their 1-based numbers, without the line end
/// (`\n`, `\r\n`, or a lone `\r` as classic Mac OS wrote).
pub(crate) struct Lines<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> Lines<'a> {
    /// Lines of `data`, the first numbered `first_line`.
    pub(crate) fn new(data: &'a [u8], first_line: usize) -> Self {
        Lines {
            data,
            pos: 0,
            line: first_line.saturating_sub(1),
        }
    }

    /// Number of the last line returned (or of the line before the first).
    pub(crate) fn line(&self) -> usize {
        self.line
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a [u8]);

    #[inline]
    fn next(&mut self) -> Option<Self::Item> {
        if self.pos >= self.data.len() {
            return None;
        }
        let rest = &self.data[self.pos..];
        let (line, advance) = match memchr::memchr2(b'\n', b'\r', rest) {
            Some(i) if rest[i] == b'\r' && rest.get(i + 1) == Some(&b'\n') => (&rest[..i], i + 2),
            Some(i) => (&rest[..i], i + 1),
            None => (rest, rest.len()),
        };
        self.pos += advance;
        self.line += 1;
        Some((self.line, line))
    }
}

/// Whitespace-separated tokens of one line.
#[derive(Clone)]
pub(crate) struct Tokens<'a> {
    rest: &'a [u8],
}

impl<'a> Tokens<'a> {
    /// Tokens of `line`.
    pub(crate) fn new(line: &'a [u8]) -> Self {
        Tokens { rest: line }
    }

    /// What is left of the line after the tokens returned so far, trimmed.
    pub(crate) fn rest(&self) -> &'a [u8] {
        self.rest.trim_ascii()
    }
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a [u8];

    #[inline]
    fn next(&mut self) -> Option<&'a [u8]> {
        let start = self.rest.iter().position(|b| !b.is_ascii_whitespace())?;
        let rest = &self.rest[start..];
        let end = rest
            .iter()
            .position(|b| b.is_ascii_whitespace())
            .unwrap_or(rest.len());
        self.rest = &rest[end..];
        Some(&rest[..end])
    }
}

/// Whitespace-separated tokens across lines, tracking the line of each token.
pub(crate) struct TokenStream<'a> {
    data: &'a [u8],
    pos: usize,
    line: usize,
}

impl<'a> TokenStream<'a> {
    /// Tokens of `data`, whose first byte lies on line `first_line`.
    pub(crate) fn new(data: &'a [u8], first_line: usize) -> Self {
        TokenStream {
            data,
            pos: 0,
            line: first_line,
        }
    }

    /// Line of the last token returned (or where scanning stopped).
    pub(crate) fn line(&self) -> usize {
        self.line
    }

    /// Bytes not yet scanned.
    pub(crate) fn remaining(&self) -> usize {
        self.data.len() - self.pos
    }

    /// Next token, or `None` at the end of the data.
    #[inline]
    pub(crate) fn next_token(&mut self) -> Option<&'a [u8]> {
        self.line_of_next();
        let d = self.data;
        let mut i = self.pos;
        if i >= d.len() {
            return None;
        }
        let start = i;
        while i < d.len() && !d[i].is_ascii_whitespace() {
            i += 1;
        }
        self.pos = i;
        Some(&d[start..i])
    }

    /// Skip white space up to the next token (or the end); the line it is on.
    #[inline]
    pub(crate) fn line_of_next(&mut self) -> usize {
        let d = self.data;
        let mut i = self.pos;
        while i < d.len() && d[i].is_ascii_whitespace() {
            if d[i] == b'\n' || (d[i] == b'\r' && d.get(i + 1) != Some(&b'\n')) {
                self.line += 1;
            }
            i += 1;
        }
        self.pos = i;
        self.line
    }

    /// The rest of the current line (trimmed), consuming it but not its line end.
    pub(crate) fn rest_of_line(&mut self) -> &'a [u8] {
        let d = &self.data[self.pos..];
        let end = memchr::memchr2(b'\n', b'\r', d).unwrap_or(d.len());
        self.pos += end;
        d[..end].trim_ascii()
    }
}

/// Parse a decimal or scientific number (also `inf`/`nan`, rejected later) as f32.
#[inline]
pub(crate) fn parse_f32(token: &[u8]) -> Option<f32> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// Parse a number as f64.
#[inline]
pub(crate) fn parse_f64(token: &[u8]) -> Option<f64> {
    std::str::from_utf8(token).ok()?.parse().ok()
}

/// A floating-point type that coordinates are read as.
pub(crate) trait Coordinate: Copy + Default {
    /// The number in `token`, as [`parse_f32`] or [`parse_f64`] reads it.
    fn parse(token: &[u8]) -> Option<Self>;
    /// Neither NaN nor infinite.
    fn is_finite(self) -> bool;
}

impl Coordinate for f32 {
    #[inline]
    fn parse(token: &[u8]) -> Option<Self> {
        parse_f32(token)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f32::is_finite(self)
    }
}

impl Coordinate for f64 {
    #[inline]
    fn parse(token: &[u8]) -> Option<Self> {
        parse_f64(token)
    }
    #[inline]
    fn is_finite(self) -> bool {
        f64::is_finite(self)
    }
}

/// Parse a signed decimal integer (optional `+`/`-`), without overflow.
#[inline]
pub(crate) fn parse_i64(token: &[u8]) -> Option<i64> {
    let (neg, digits) = match token.first()? {
        b'-' => (true, &token[1..]),
        b'+' => (false, &token[1..]),
        _ => (false, token),
    };
    if digits.is_empty() || digits.len() > 19 {
        return None;
    }
    let mut v: u64 = 0;
    for &c in digits {
        let d = c.wrapping_sub(b'0');
        if d > 9 {
            return None;
        }
        v = v.checked_mul(10)?.checked_add(d as u64)?;
    }
    if neg {
        // `i64::MIN` has no positive counterpart, so it is negated in u64.
        (v <= 1 << 63).then(|| (v as i64).wrapping_neg())
    } else {
        i64::try_from(v).ok()
    }
}

/// Parse an unsigned decimal integer.
#[inline]
pub(crate) fn parse_u64(token: &[u8]) -> Option<u64> {
    let v = parse_i64(token)?;
    u64::try_from(v).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lines_strip_crlf_and_count_from_one() {
        let v: Vec<_> = Lines::new(b"a\r\nbb\n\nc", 1).collect();
        assert_eq!(
            v,
            vec![
                (1, &b"a"[..]),
                (2, &b"bb"[..]),
                (3, &b""[..]),
                (4, &b"c"[..])
            ]
        );
    }

    #[test]
    fn tokens_split_on_any_whitespace() {
        let mut t = Tokens::new(b"  v 1.5\t-2  3 ");
        assert_eq!(t.next(), Some(&b"v"[..]));
        assert_eq!(t.rest(), b"1.5\t-2  3");
        let rest: Vec<_> = t.collect();
        assert_eq!(rest, vec![&b"1.5"[..], b"-2", b"3"]);
    }

    #[test]
    fn every_line_end_ends_a_line() {
        let data = b"a\nb\r\nc\rd\r\re";
        let got: Vec<_> = Lines::new(data, 1).collect();
        let want: Vec<(usize, &[u8])> = vec![
            (1, b"a"),
            (2, b"b"),
            (3, b"c"),
            (4, b"d"),
            (5, b""),
            (6, b"e"),
        ];
        assert_eq!(got, want);
        let mut s = TokenStream::new(data, 1);
        let tokens: Vec<_> = std::iter::from_fn(|| s.next_token().map(|t| (t, s.line()))).collect();
        let lines: Vec<usize> = tokens.iter().map(|&(_, l)| l).collect();
        assert_eq!(lines, [1, 2, 3, 4, 6]);
        let mut s = TokenStream::new(b"x rest\ry", 1);
        s.next_token();
        assert_eq!(s.rest_of_line(), b"rest");
    }

    #[test]
    fn token_stream_tracks_lines() {
        let mut s = TokenStream::new(b"a b\n\n c\nd rest of line\ne", 1);
        assert_eq!(s.next_token(), Some(&b"a"[..]));
        assert_eq!(s.next_token(), Some(&b"b"[..]));
        assert_eq!(s.line(), 1);
        assert_eq!(s.next_token(), Some(&b"c"[..]));
        assert_eq!(s.line(), 3);
        assert_eq!(s.next_token(), Some(&b"d"[..]));
        assert_eq!(s.rest_of_line(), b"rest of line");
        assert_eq!(s.next_token(), Some(&b"e"[..]));
        assert_eq!(s.line(), 5);
        assert_eq!(s.next_token(), None);
    }

    #[test]
    fn numbers_parse_like_std() {
        for s in ["0", "-1.5", "3e-7", "+2.25", "1E10", ".5", "5."] {
            assert_eq!(parse_f32(s.as_bytes()), s.parse::<f32>().ok(), "{s}");
        }
        assert_eq!(parse_f32(b"abc"), None);
        assert_eq!(parse_i64(b"-42"), Some(-42));
        assert_eq!(parse_i64(b"+7"), Some(7));
        assert_eq!(parse_i64(b"9223372036854775807"), Some(i64::MAX));
        assert_eq!(parse_i64(b"9223372036854775808"), None);
        assert_eq!(parse_i64(b"-9223372036854775808"), Some(i64::MIN));
        assert_eq!(parse_i64(b"-9223372036854775809"), None);
        assert_eq!(parse_i64(b"1.0"), None);
        assert_eq!(parse_i64(b"-"), None);
        assert_eq!(parse_u64(b"-1"), None);
        assert_eq!(parse_u64(b"17"), Some(17));
    }
}
