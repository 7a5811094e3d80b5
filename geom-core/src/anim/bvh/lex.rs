//! BVH tokens: whitespace-separated words with 1-based line numbers; `{` and `}` are always
//! tokens of their own. Accepts CRLF, tabs, runs of blanks and a leading UTF-8 BOM.

/// One token and the line it starts on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct Tok<'a> {
    pub text: &'a str,
    pub line: usize,
}

/// A lazy tokenizer over the whole text (no allocation per token).
#[derive(Clone, Debug)]
pub(crate) struct Lexer<'a> {
    rest: &'a str,
    line: usize,
    /// Line of the most recent token (1 before any), for end-of-file errors.
    pub last_line: usize,
}

fn is_space(b: u8) -> bool {
    matches!(b, b' ' | b'\t' | b'\r' | b'\n' | 0x0b | 0x0c)
}

impl<'a> Lexer<'a> {
    pub fn new(text: &'a str) -> Self {
        let rest = text.strip_prefix('\u{feff}').unwrap_or(text);
        Lexer { rest, line: 1, last_line: 1 }
    }

    /// The next token, or `None` at the end of the text.
    pub fn next_tok(&mut self) -> Option<Tok<'a>> {
        let bytes = self.rest.as_bytes();
        let mut i = 0;
        while i < bytes.len() && is_space(bytes[i]) {
            if bytes[i] == b'\n' {
                self.line += 1;
            }
            i += 1;
        }
        if i == bytes.len() {
            self.rest = "";
            return None;
        }
        let start = i;
        if bytes[i] == b'{' || bytes[i] == b'}' {
            i += 1;
        } else {
            while i < bytes.len() && !is_space(bytes[i]) && bytes[i] != b'{' && bytes[i] != b'}' {
                i += 1;
            }
        }
        // Token boundaries are ASCII bytes, so `start..i` is on char boundaries.
        let text = &self.rest[start..i];
        self.rest = &self.rest[i..];
        self.last_line = self.line;
        Some(Tok { text, line: self.line })
    }

    /// The next token without consuming it.
    pub fn peek(&self) -> Option<Tok<'a>> {
        self.clone().next_tok()
    }

    /// The text not yet tokenized.
    pub fn rest(&self) -> &'a str {
        self.rest
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tokens_lines_and_braces() {
        let mut l = Lexer::new("\u{feff}HIERARCHY\r\nROOT Hips{\r\n\tOFFSET 1\t2  3\n}\n\n");
        let toks: Vec<(String, usize)> =
            std::iter::from_fn(|| l.next_tok()).map(|t| (t.text.to_string(), t.line)).collect();
        let want = [
            ("HIERARCHY", 1),
            ("ROOT", 2),
            ("Hips", 2),
            ("{", 2),
            ("OFFSET", 3),
            ("1", 3),
            ("2", 3),
            ("3", 3),
            ("}", 4),
        ];
        assert_eq!(toks.len(), want.len());
        for ((t, ln), (wt, wl)) in toks.iter().zip(want) {
            assert_eq!((t.as_str(), *ln), (wt, wl));
        }
        assert_eq!(l.last_line, 4);
    }

    #[test]
    fn non_ascii_is_part_of_a_token() {
        let mut l = Lexer::new("Jöint\u{a0}x é");
        assert_eq!(l.next_tok().unwrap().text, "Jöint\u{a0}x");
        assert_eq!(l.peek().unwrap().text, "é");
        assert_eq!(l.next_tok().unwrap().text, "é");
        assert!(l.next_tok().is_none());
    }
}
