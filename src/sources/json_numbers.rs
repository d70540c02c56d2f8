//! The numbers of a JSON text, correctly rounded, with where they are.
//!
//! serde_json, as built here, parses floats with a fast method that can be
//! one unit in the last place off for 17-digit numbers (its
//! `float_roundtrip` feature fixes that, but turning it on rebuilds every
//! crate that uses serde_json, Rerun and Arrow included). Plan files and an
//! external law's answers must come in exactly as written, so that a
//! replayed or remote command is bit for bit the command that was logged or
//! computed: their texts are first parsed by serde_json (structure, types,
//! error messages), then [`walk`] reads every number token again with Rust's
//! correctly rounded `f64` parser and the caller overwrites serde's values.

use std::borrow::Cow;

/// One step of the path to a value: an object key or an array index.
#[derive(Debug, Clone, PartialEq)]
pub enum Step<'a> {
    /// Object member.
    Key(Cow<'a, str>),
    /// Array element.
    Index(usize),
}

/// Deepest nesting followed (serde_json refuses deeper documents anyway).
const MAX_DEPTH: usize = 128;

/// Call `f(path, byte_offset, value)` for every number of `text`, in
/// document order. `None` when `text` is not one JSON value (callers parse
/// it with serde_json first, so this only happens for texts serde accepted
/// and this scanner does not, which would be a bug here; they then keep
/// serde's values).
pub fn walk<'a>(text: &'a str, f: &mut dyn FnMut(&[Step<'a>], usize, f64)) -> Option<()> {
    let mut w = Walker {
        text,
        s: text.as_bytes(),
        i: 0,
        path: Vec::new(),
    };
    w.value(f)?;
    w.ws();
    (w.i == w.s.len()).then_some(())
}

/// 1-based line of byte `offset` in `text`, counting from a known
/// (`line`, `from`) so increasing offsets cost one pass in total.
pub(crate) fn line_at(text: &str, from: (usize, usize), offset: usize) -> (usize, usize) {
    let (line, start) = from;
    let end = offset.min(text.len());
    if end < start {
        return line_at(text, (1, 0), offset);
    }
    let n = text.as_bytes()[start..end]
        .iter()
        .filter(|&&b| b == b'\n')
        .count();
    (line + n, end)
}

struct Walker<'a> {
    text: &'a str,
    s: &'a [u8],
    i: usize,
    path: Vec<Step<'a>>,
}

impl<'a> Walker<'a> {
    fn ws(&mut self) {
        while self
            .s
            .get(self.i)
            .is_some_and(|b| matches!(b, b' ' | b'\t' | b'\n' | b'\r'))
        {
            self.i += 1;
        }
    }

    fn peek(&self) -> Option<u8> {
        self.s.get(self.i).copied()
    }

    fn literal(&mut self, word: &str) -> Option<()> {
        let end = self.i + word.len();
        (self.s.get(self.i..end)? == word.as_bytes()).then(|| self.i = end)
    }

    fn string(&mut self) -> Option<Cow<'a, str>> {
        let open = self.i;
        self.i += 1;
        let mut escaped = false;
        loop {
            match self.peek()? {
                b'"' => break,
                b'\\' => {
                    escaped = true;
                    self.i += 2;
                }
                _ => self.i += 1,
            }
        }
        self.i += 1;
        let raw = self.text.get(open..self.i)?;
        if escaped {
            serde_json::from_str::<String>(raw).ok().map(Cow::Owned)
        } else {
            Some(Cow::Borrowed(&raw[1..raw.len() - 1]))
        }
    }

    fn value(&mut self, f: &mut dyn FnMut(&[Step<'a>], usize, f64)) -> Option<()> {
        if self.path.len() > MAX_DEPTH {
            return None;
        }
        self.ws();
        match self.peek()? {
            b'{' => {
                self.i += 1;
                self.ws();
                if self.peek()? == b'}' {
                    self.i += 1;
                    return Some(());
                }
                loop {
                    self.ws();
                    if self.peek()? != b'"' {
                        return None;
                    }
                    let key = self.string()?;
                    self.ws();
                    if self.peek()? != b':' {
                        return None;
                    }
                    self.i += 1;
                    self.path.push(Step::Key(key));
                    self.value(f)?;
                    self.path.pop();
                    self.ws();
                    match self.peek()? {
                        b',' => self.i += 1,
                        b'}' => {
                            self.i += 1;
                            return Some(());
                        }
                        _ => return None,
                    }
                }
            }
            b'[' => {
                self.i += 1;
                self.ws();
                if self.peek()? == b']' {
                    self.i += 1;
                    return Some(());
                }
                let mut k = 0;
                loop {
                    self.path.push(Step::Index(k));
                    self.value(f)?;
                    self.path.pop();
                    k += 1;
                    self.ws();
                    match self.peek()? {
                        b',' => self.i += 1,
                        b']' => {
                            self.i += 1;
                            return Some(());
                        }
                        _ => return None,
                    }
                }
            }
            b'"' => self.string().map(|_| ()),
            b't' => self.literal("true"),
            b'f' => self.literal("false"),
            b'n' => self.literal("null"),
            b'-' | b'0'..=b'9' => {
                let start = self.i;
                while self
                    .peek()
                    .is_some_and(|b| matches!(b, b'-' | b'+' | b'.' | b'e' | b'E' | b'0'..=b'9'))
                {
                    self.i += 1;
                }
                // Rust's parser is correctly rounded (and accepts every JSON number).
                let v: f64 = self.text.get(start..self.i)?.parse().ok()?;
                f(&self.path, start, v);
                Some(())
            }
            _ => None,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn all(text: &str) -> Vec<(String, usize, f64)> {
        let mut out = Vec::new();
        walk(text, &mut |p, at, v| {
            let path: Vec<String> = p
                .iter()
                .map(|s| match s {
                    Step::Key(k) => k.to_string(),
                    Step::Index(i) => i.to_string(),
                })
                .collect();
            out.push((path.join("/"), at, v))
        })
        .unwrap();
        out
    }

    #[test]
    fn paths_offsets_and_values() {
        let text = r#"{"t": [0, 0.5e-1], "u": {"v\"x": [-1.25E2], "w": []}, "label": ["a,[1]"], "done": false, "n": null}"#;
        let got = all(text);
        assert_eq!(
            got,
            vec![
                ("t/0".into(), 7, 0.0),
                ("t/1".into(), 10, 0.05),
                ("u/v\"x/0".into(), 34, -125.0),
            ]
        );
        assert!(walk("{\"a\": 1} x", &mut |_, _, _| {}).is_none());
        assert!(walk("{\"a\" 1}", &mut |_, _, _| {}).is_none());
        assert_eq!(line_at("a\nb\nc", (1, 0), 4), (3, 4));
        assert_eq!(line_at("a\nb\nc", (3, 4), 5), (3, 5));
    }

    /// Numbers serde_json (without `float_roundtrip`) rounds wrongly come in
    /// exactly: the reason this module exists.
    #[test]
    fn seventeen_digit_numbers_are_exact() {
        let mut found_difference = false;
        let mut bits = 0x9E37_79B9_7F4A_7C15u64;
        for _ in 0..20_000 {
            // Random mantissas, binary exponents within 2^±60.
            bits = bits
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            let exp = 1023 - 60 + (bits >> 57) % 120;
            let x = f64::from_bits((exp << 52) | (bits & ((1 << 52) - 1)));
            let text = format!("[{x:?}]");
            let mut got = f64::NAN;
            walk(&text, &mut |_, _, v| got = v).unwrap();
            assert_eq!(got.to_bits(), x.to_bits(), "{text}");
            let serde: Vec<f64> = serde_json::from_str(&text).unwrap();
            found_difference |= serde[0].to_bits() != x.to_bits();
        }
        // If serde_json ever parses exactly here, this module can go.
        assert!(found_difference, "serde_json parsed every number exactly");
    }
}
