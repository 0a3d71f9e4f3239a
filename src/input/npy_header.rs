//! A strict, linear-time check of an `.npy` header before `npyz` parses it.
//!
//! The header is a Python dict literal, `{'descr': '<f8', 'fortran_order': False, 'shape':
//! (2, 3), }`. `npyz` parses any Python literal there, structured dtypes included, and its
//! parser takes time exponential in their nesting: a 256-byte file with a deeply nested
//! `descr = [('a', [('b', [...])])]` runs for minutes. The reader takes plain arrays only, so
//! this check accepts exactly the three keys with plain values (`descr` a type string,
//! `fortran_order` a boolean, `shape` a tuple of integers) and refuses everything else in one
//! pass, naming what it found.

/// The magic string every `.npy` file starts with.
const MAGIC: &[u8] = b"\x93NUMPY";

/// Checks the preamble and header dict of `bytes` (an `.npy` file); `Err` says what is wrong.
pub fn check(bytes: &[u8]) -> Result<(), String> {
    if bytes.len() < 10 || !bytes.starts_with(MAGIC) {
        return Err("no .npy magic string at the start".into());
    }
    let (len, start): (usize, usize) = match bytes[6] {
        1 => (u16::from_le_bytes([bytes[8], bytes[9]]) as usize, 10),
        2 | 3 if bytes.len() >= 12 => (
            u32::from_le_bytes([bytes[8], bytes[9], bytes[10], bytes[11]]) as usize,
            12,
        ),
        v => return Err(format!("format version {v} (expected 1, 2 or 3)")),
    };
    let header = bytes.get(start..start.saturating_add(len)).ok_or_else(|| {
        format!(
            "the header length {len} runs past the end of the file ({} bytes)",
            bytes.len()
        )
    })?;
    let text = std::str::from_utf8(header).map_err(|_| "the header is not text".to_string())?;
    Dict::parse(text)
}

/// The keys of an `.npy` header dict.
const KEYS: [&str; 3] = ["descr", "fortran_order", "shape"];

/// A cursor over the header text.
struct Dict<'a> {
    rest: &'a str,
}

impl<'a> Dict<'a> {
    /// Parses the whole header dict: every key once, plain values, nothing after it but the
    /// padding.
    fn parse(text: &'a str) -> Result<(), String> {
        let mut d = Dict { rest: text };
        d.expect('{')?;
        let mut seen = [false; KEYS.len()];
        loop {
            if d.eat('}') {
                break;
            }
            let key = d.string("a key")?;
            let k = KEYS.iter().position(|&k| k == key).ok_or_else(|| {
                format!("unknown header key '{key}' (expected descr, fortran_order and shape)")
            })?;
            if std::mem::replace(&mut seen[k], true) {
                return Err(format!("header key '{key}' appears twice"));
            }
            d.expect(':')?;
            match key {
                "descr" => d.descr()?,
                "fortran_order" => d.boolean()?,
                _ => d.shape()?,
            }
            if !d.eat(',') {
                d.expect('}')?;
                break;
            }
        }
        if let Some(k) = seen.iter().position(|&s| !s) {
            return Err(format!("header key '{}' is missing", KEYS[k]));
        }
        if !d.rest.trim().is_empty() {
            return Err(format!(
                "unexpected text after the header dict: {:?}",
                d.clip()
            ));
        }
        Ok(())
    }

    /// The next few characters, for messages.
    fn clip(&self) -> String {
        self.rest.trim_start().chars().take(20).collect()
    }

    /// Skips spaces, then consumes `c` if it is next.
    fn eat(&mut self, c: char) -> bool {
        self.rest = self.rest.trim_start();
        match self.rest.strip_prefix(c) {
            Some(r) => {
                self.rest = r;
                true
            }
            None => false,
        }
    }

    fn expect(&mut self, c: char) -> Result<(), String> {
        if self.eat(c) {
            Ok(())
        } else {
            Err(format!("expected '{c}' at {:?}", self.clip()))
        }
    }

    /// A quoted string without escapes.
    fn string(&mut self, what: &str) -> Result<&'a str, String> {
        self.rest = self.rest.trim_start();
        let quote = match self.rest.chars().next() {
            Some(q @ ('\'' | '"')) => q,
            _ => return Err(format!("expected {what} in quotes at {:?}", self.clip())),
        };
        let body = &self.rest[1..];
        let end = body
            .find([quote, '\\'])
            .filter(|&i| body[i..].starts_with(quote))
            .ok_or_else(|| format!("unterminated or escaped string at {:?}", self.clip()))?;
        self.rest = &body[end + 1..];
        Ok(&body[..end])
    }

    /// `descr`: a plain type string such as `'<f8'`; a list is a structured dtype.
    fn descr(&mut self) -> Result<(), String> {
        self.rest = self.rest.trim_start();
        if self.rest.starts_with('[') {
            return Err(
                "descr is a structured dtype (a list of fields): only plain arrays of float64, \
                 float32, int64 or int32 are read"
                    .into(),
            );
        }
        let descr = self.string("descr")?;
        let plain = descr.trim_start_matches(['<', '>', '|', '=']);
        let mut chars = plain.chars();
        if !(chars.next().is_some_and(|c| c.is_ascii_alphabetic())
            && chars.all(|c| c.is_ascii_digit()))
        {
            return Err(format!(
                "descr '{descr}' is not a plain type such as '<f8', '<f4', '<i8' or '<i4'"
            ));
        }
        Ok(())
    }

    /// `fortran_order`: `True` or `False`.
    fn boolean(&mut self) -> Result<(), String> {
        self.rest = self.rest.trim_start();
        for word in ["True", "False"] {
            if let Some(r) = self.rest.strip_prefix(word) {
                self.rest = r;
                return Ok(());
            }
        }
        Err(format!(
            "fortran_order must be True or False, found {:?}",
            self.clip()
        ))
    }

    /// `shape`: a tuple of non-negative integers, `()`, `(n,)` or `(n, m, ...)`.
    fn shape(&mut self) -> Result<(), String> {
        self.expect('(')?;
        loop {
            if self.eat(')') {
                return Ok(());
            }
            self.rest = self.rest.trim_start();
            let digits = self.rest.len()
                - self
                    .rest
                    .trim_start_matches(|c: char| c.is_ascii_digit())
                    .len();
            let (number, r) = self.rest.split_at(digits);
            if number.parse::<u64>().is_err() {
                return Err(format!(
                    "shape: expected a dimension (a non-negative integer below 2^64) at {:?}",
                    self.clip()
                ));
            }
            // Python 2 wrote long integers with an L.
            self.rest = r.strip_prefix('L').unwrap_or(r);
            if !self.eat(',') {
                return self.expect(')');
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn npy(header: &str) -> Vec<u8> {
        let mut b = MAGIC.to_vec();
        b.extend_from_slice(&[1, 0]);
        b.extend_from_slice(&(header.len() as u16).to_le_bytes());
        b.extend_from_slice(header.as_bytes());
        b
    }

    #[test]
    fn plain_headers_pass() {
        for h in [
            "{'descr': '<f8', 'fortran_order': False, 'shape': (2, 3), }   \n",
            "{\"descr\": \">i4\", \"shape\": (5,), \"fortran_order\": True}\n",
            "{'descr': '<f4', 'fortran_order': False, 'shape': ()}",
            "{'descr': '<i8', 'fortran_order': False, 'shape': (3L, 2L), }",
        ] {
            assert_eq!(check(&npy(h)), Ok(()), "{h}");
        }
    }

    #[test]
    fn structured_unknown_duplicate_and_missing_keys_are_named() {
        let cases = [
            (
                "{'descr': [('a', '<f8')], 'fortran_order': False, 'shape': (1,), }",
                "structured dtype",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (1,), 'extra': 1}",
                "unknown header key 'extra'",
            ),
            (
                "{'descr': '<f8', 'descr': '<f4', 'fortran_order': False, 'shape': (1,)}",
                "'descr' appears twice",
            ),
            (
                "{'descr': '<f8', 'shape': (1,)}",
                "'fortran_order' is missing",
            ),
            (
                "{'descr': 'f8\\'', 'fortran_order': False, 'shape': (1,)}",
                "escaped",
            ),
            (
                "{'descr': '<f8', 'fortran_order': 0, 'shape': (1,)}",
                "True or False",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (99999999999999999999999,)}",
                "dimension",
            ),
            (
                "{'descr': '<f8', 'fortran_order': False, 'shape': (1,)} x",
                "after the header",
            ),
        ];
        for (h, needle) in cases {
            let e = check(&npy(h)).unwrap_err();
            assert!(e.contains(needle), "{h}: {e}");
        }
        let mut long = npy("{}");
        long[8] = 200;
        assert!(check(&long).unwrap_err().contains("runs past the end"));
    }
}
