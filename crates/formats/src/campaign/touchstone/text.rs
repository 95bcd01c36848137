//! The text of a Touchstone file as the reader takes it apart: lines split at LF, CRLF or
//! CR ([`Lines`]), a data line's tokens up to its comment ([`Tokens`]), a line without its
//! comment ([`strip_comment`]), an HFSS `! Port Impedance` block ([`hfss_block`]), the
//! option line's frequency unit ([`unit_scale`]) and complex numbers ([`parse_complex`]).
//!
//! Takes the text (or one line, one token); gives its lines, tokens and numbers.

use num_complex::Complex64;

/// The scale to Hz of the option line's frequency unit (`Hz`, `kHz`, `MHz`, `GHz`, any
/// case).
pub(super) fn unit_scale(tok: &str) -> Option<f64> {
    match tok.to_ascii_lowercase().as_str() {
        "hz" => Some(1.0),
        "khz" => Some(1e3),
        "mhz" => Some(1e6),
        "ghz" => Some(1e9),
        _ => None,
    }
}

/// Parse a real or complex number as scikit-rf's option line takes it (`50`, `(10+10j)`,
/// `10-5j`, `5j`).
pub(super) fn parse_complex(tok: &str) -> Option<Complex64> {
    let t = tok.trim_start_matches('(').trim_end_matches(')');
    if let Ok(v) = t.parse::<f64>() {
        return Some(Complex64::new(v, 0.0));
    }
    let body = t.strip_suffix(['j', 'J', 'i', 'I'])?;
    // the sign that starts the imaginary part: the last + or - not at the start and not
    // after an exponent marker
    let b = body.as_bytes();
    let split = (1..b.len())
        .rev()
        .find(|&i| (b[i] == b'+' || b[i] == b'-') && !matches!(b[i - 1], b'e' | b'E'));
    match split {
        Some(i) => {
            let re = body[..i].parse::<f64>().ok()?;
            let im = match &body[i..] {
                "+" => 1.0,
                "-" => -1.0,
                s => s.parse::<f64>().ok()?,
            };
            Some(Complex64::new(re, im))
        }
        None => Some(Complex64::new(0.0, body.parse::<f64>().ok()?)),
    }
}

/// Lines split at LF, CRLF or CR, numbered from 1; `Clone` gives a look-ahead.
///
/// A text with any LF splits at LF (memchr-fast `str::find`) and drops a CR before it, as
/// `str::lines`; a text with CR only (classic Mac) splits at CR.
#[derive(Clone)]
pub(super) struct Lines<'a> {
    rest: &'a str,
    lineno: usize,
    sep: char,
}

impl<'a> Lines<'a> {
    pub(super) fn new(text: &'a str) -> Lines<'a> {
        let b = text.as_bytes();
        let sep = if !b.contains(&b'\n') && b.contains(&b'\r') {
            '\r'
        } else {
            '\n'
        };
        Lines {
            rest: text,
            lineno: 0,
            sep,
        }
    }
}

impl<'a> Iterator for Lines<'a> {
    type Item = (usize, &'a str);
    fn next(&mut self) -> Option<(usize, &'a str)> {
        if self.rest.is_empty() {
            return None;
        }
        self.lineno += 1;
        let line = match self.rest.find(self.sep) {
            Some(i) => {
                let line = &self.rest[..i];
                self.rest = &self.rest[i + 1..];
                line
            }
            None => std::mem::take(&mut self.rest),
        };
        Some((self.lineno, line.strip_suffix('\r').unwrap_or(line)))
    }
}

/// Whitespace-separated tokens of a data line, up to a `!` comment (bytes ≤ space
/// separate; a non-ASCII byte stays in its token, which then fails to parse).
pub(super) struct Tokens<'a> {
    s: &'a str,
    pos: usize,
}

impl<'a> Tokens<'a> {
    pub(super) fn new(s: &'a str) -> Tokens<'a> {
        Tokens { s, pos: 0 }
    }
}

impl<'a> Iterator for Tokens<'a> {
    type Item = &'a str;
    #[inline]
    fn next(&mut self) -> Option<&'a str> {
        let b = self.s.as_bytes();
        let mut i = self.pos;
        while i < b.len() && b[i] <= b' ' {
            i += 1;
        }
        if i >= b.len() || b[i] == b'!' {
            self.pos = b.len();
            return None;
        }
        let start = i;
        while i < b.len() && b[i] > b' ' && b[i] != b'!' {
            i += 1;
        }
        self.pos = i;
        // split at ASCII bytes only: char boundaries
        Some(&self.s[start..i])
    }
}

/// A line without its `!` comment, trimmed.
pub(super) fn strip_comment(raw: &str) -> &str {
    match raw.find('!') {
        Some(p) => &raw[..p],
        None => raw,
    }
    .trim()
}

/// Floats of an HFSS comment block (`! Port Impedance re im …`) and its continuation lines
/// (comments holding only numbers).
pub(super) fn hfss_block(first: &str, lines: &mut Lines<'_>) -> Vec<f64> {
    let mut vals: Vec<f64> = first
        .split_ascii_whitespace()
        .filter_map(|t| t.parse().ok())
        .collect();
    loop {
        let mut ahead = lines.clone();
        let Some((_, l)) = ahead.next() else { break };
        let Some(body) = l.trim().strip_prefix('!') else {
            break;
        };
        let more: Option<Vec<f64>> = body
            .split_ascii_whitespace()
            .map(|t| t.parse().ok())
            .collect();
        match more {
            Some(m) if !m.is_empty() => {
                vals.extend(m);
                *lines = ahead;
            }
            _ => break,
        }
    }
    vals
}
