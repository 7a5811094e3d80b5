//! Small byte-text helpers shared by the text readers (OBJ, OFF, ASCII PLY).

/// At most 40 characters of a token, lossily decoded, for error messages (a token of a damaged
/// file can be megabytes of binary garbage).
pub(crate) fn show(t: &[u8]) -> String {
    let s = String::from_utf8_lossy(t);
    if s.chars().count() > 40 {
        format!("{}…", s.chars().take(40).collect::<String>())
    } else {
        s.into_owned()
    }
}

/// Whitespace-separated tokens (space, tab, CR, form feed, vertical tab).
pub(crate) fn tokens(l: &[u8]) -> impl Iterator<Item = &[u8]> {
    l.split(|b| b.is_ascii_whitespace() || *b == 0x0b).filter(|t| !t.is_empty())
}

/// Lines split at LF, each without a trailing CR, numbered from 1. A final LF ends the last
/// line (it does not start an empty one), so "end of file" errors name the last real line.
pub(crate) fn lines(data: &[u8]) -> impl Iterator<Item = (usize, &[u8])> {
    let data = data.strip_suffix(b"\n").unwrap_or(data);
    data.split(|&b| b == b'\n').enumerate().map(|(i, l)| (i + 1, l.strip_suffix(b"\r").unwrap_or(l)))
}

/// `data` without a leading UTF-8 byte-order mark (written by some Windows tools).
pub(crate) fn strip_bom(data: &[u8]) -> &[u8] {
    data.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(data)
}

/// A token as `&str` when it is UTF-8.
pub(crate) fn as_str(t: &[u8]) -> Option<&str> {
    std::str::from_utf8(t).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn show_truncates_long_tokens() {
        let long = vec![b'x'; 100];
        assert_eq!(show(&long).chars().count(), 41);
        assert_eq!(show(b"abc"), "abc");
    }

    #[test]
    fn tokens_and_lines_handle_tabs_and_crlf() {
        let t: Vec<&[u8]> = tokens(b" v\t1  2\r").collect();
        assert_eq!(t, vec![&b"v"[..], b"1", b"2"]);
        let l: Vec<(usize, &[u8])> = lines(b"a\r\nb\nc").collect();
        assert_eq!(l, vec![(1, &b"a"[..]), (2, b"b"), (3, b"c")]);
        assert_eq!(lines(b"a\n").count(), 1);
        assert_eq!(lines(b"a\n\n").count(), 2);
    }
}
