//! The naming pattern of `import --sweeps`: `{position}`, `{direction}` or `{angle}`, and
//! optionally `{pulse}` between literal text, each field with an optional format
//! (`{direction:02}`, `{angle:+03}`, `{angle:.1}`).
//!
//! Takes the `--name-pattern` text ([`parse_pattern`], refused in one line naming the
//! pattern) and a file name with the poses' labels ([`match_name`]); gives what the name
//! says, field by field ([`Said`]). An angle must be written exactly as its format writes
//! it (as Rust and Python format numbers), so one name never reads as two angles; an index
//! never reads digits after a `+` (`az+05` is a signed number, an angle).

use crate::error::{Error, Result};

/// A field of a naming pattern.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Field {
    Position,
    Direction,
    Pulse,
    Angle,
}

/// The format of a field: `{name:SPEC}` with SPEC = `[+][0][width][.precision]` as Rust
/// and Python format numbers (`+` always signed, `0` zero-padded to `width` characters
/// sign included, `.p` exactly p decimals). For the index fields only a width is taken:
/// exactly that many digits (`{direction:02}` reads `07`, not `7`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub(super) struct Spec {
    plus: bool,
    zero: bool,
    width: Option<usize>,
    precision: Option<usize>,
}

/// A piece of a naming pattern.
#[derive(Debug, Clone, PartialEq)]
pub(super) enum Piece {
    Lit(String),
    Field(Field, Spec),
}

const FIELDS: [(&str, Field); 4] = [
    ("position", Field::Position),
    ("direction", Field::Direction),
    ("pulse", Field::Pulse),
    ("angle", Field::Angle),
];

pub(super) fn parse_spec(p: &str, name: &str, spec: &str, field: Field) -> Result<Spec> {
    let bad = |why: &str| {
        Error::param(
            "--name-pattern",
            format!("`{p}`: `{{{name}:{spec}}}`: {why}"),
        )
    };
    let mut s = Spec::default();
    let mut rest = spec;
    if field == Field::Angle {
        if let Some(r) = rest.strip_prefix('+') {
            s.plus = true;
            rest = r;
        }
        if let Some(r) = rest.strip_prefix('0') {
            s.zero = true;
            rest = r;
        }
        if let Some((w, prec)) = rest.split_once('.') {
            s.precision = Some(
                prec.parse::<usize>()
                    .ok()
                    .filter(|&v| v <= 9)
                    .ok_or_else(|| bad("the precision after `.` must be a number up to 9"))?,
            );
            rest = w;
        }
    }
    if !rest.is_empty() {
        s.width = Some(
            rest.parse::<usize>()
                .ok()
                .filter(|&w| {
                    (1..=crate::campaign::manifest::limits::MAX_PATTERN_WIDTH).contains(&w)
                })
                .ok_or_else(|| {
                    bad(if field == Field::Angle {
                        "the format is [+][0][width][.precision], e.g. +03 or .1"
                    } else {
                        "the width must be a number (digits in the name)"
                    })
                })?,
        );
    }
    Ok(s)
}

pub(super) fn parse_pattern(p: &str) -> Result<Vec<Piece>> {
    let mut out = Vec::new();
    let mut rest = p;
    while let Some(open) = rest.find('{') {
        if open > 0 {
            out.push(Piece::Lit(rest[..open].to_string()));
        }
        let close = rest[open..]
            .find('}')
            .ok_or_else(|| Error::param("--name-pattern", format!("`{p}`: `{{` without `}}`")))?
            + open;
        let inner = &rest[open + 1..close];
        let (name, spec) = inner.split_once(':').unwrap_or((inner, ""));
        let field = FIELDS
            .iter()
            .find(|f| f.0 == name)
            .map(|f| f.1)
            .ok_or_else(|| {
                Error::param(
                    "--name-pattern",
                    format!("`{p}`: unknown field `{{{name}}}` (use {{position}}, {{direction}} or {{angle}}, {{pulse}})"),
                )
            })?;
        out.push(Piece::Field(field, parse_spec(p, name, spec, field)?));
        rest = &rest[close + 1..];
    }
    if !rest.is_empty() {
        out.push(Piece::Lit(rest.to_string()));
    }
    let has = |f: Field| {
        out.iter()
            .any(|q| matches!(q, Piece::Field(g, _) if *g == f))
    };
    if !has(Field::Position) {
        return Err(Error::param(
            "--name-pattern",
            format!("`{p}` has no {{position}}"),
        ));
    }
    match (has(Field::Direction), has(Field::Angle)) {
        (false, false) => Err(Error::param(
            "--name-pattern",
            format!("`{p}` has no {{direction}} (index 0..n−1) or {{angle}} (signed degrees)"),
        )),
        (true, true) => Err(Error::param(
            "--name-pattern",
            format!("`{p}` has both {{direction}} and {{angle}}: name the direction once"),
        )),
        _ => Ok(out),
    }
}

/// An angle written as a field of format `s` writes it (see [`Spec`]).
pub(super) fn format_angle(v: f64, s: &Spec) -> String {
    let digits = match s.precision {
        Some(p) => format!("{:.p$}", v.abs()),
        None => format!("{}", v.abs()),
    };
    let sign = if v.is_sign_negative() && digits.bytes().any(|b| b.is_ascii_digit() && b != b'0') {
        "-"
    } else if s.plus {
        "+"
    } else {
        ""
    };
    let len = sign.len() + digits.len();
    match s.width {
        Some(w) if w > len && s.zero => format!("{sign}{}{digits}", "0".repeat(w - len)),
        Some(w) if w > len => format!("{}{sign}{digits}", " ".repeat(w - len)),
        _ => format!("{sign}{digits}"),
    }
}

/// Whether `text` is angle `v` as format `s` writes it; without a precision in the format
/// any number of decimals the text has is taken as its precision (`{angle}` reads `5`
/// as Rust writes 5.0 and `5.0` as Python does).
fn written_as(v: f64, s: &Spec, text: &str) -> bool {
    if format_angle(v, s) == text {
        return true;
    }
    match (s.precision, text.split_once('.')) {
        (None, Some((_, frac))) => {
            let p = Spec {
                precision: Some(frac.len()),
                ..*s
            };
            format_angle(v, &p) == text
        }
        _ => false,
    }
}

/// The value of a direction in a name: its index, or its angle in degrees.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum DirectionValue {
    /// `{direction}` or an index column `direction`.
    Index(i64),
    /// `{angle}` or an index column `angle_deg`.
    Angle(f64),
}

/// What a name says, field by field (a field named twice must say the same both times).
#[derive(Debug, Clone, Default, PartialEq)]
pub(super) struct Said {
    pub(super) position: Option<String>,
    pub(super) direction: Option<DirectionValue>,
    pub(super) pulse: Option<i64>,
}

/// How `{position}` reads: the poses' labels (a run naming one of them is preferred) and
/// whether they are all numbers (then `{position}` is a run of digits, `{position:03}`
/// exactly three).
pub(super) struct LabelSet<'a> {
    pub(super) labels: &'a [String],
    pub(super) numeric: bool,
}

/// Match the name `s` from byte `at` against `pieces`, filling `said`.
pub(super) fn match_name(
    pieces: &[Piece],
    s: &str,
    at: usize,
    labels: &LabelSet<'_>,
    said: &mut Said,
) -> bool {
    let Some((first, rest)) = pieces.split_first() else {
        return at == s.len();
    };
    let t = &s[at..];
    match first {
        Piece::Lit(l) => {
            t.starts_with(l.as_str()) && match_name(rest, s, at + l.len(), labels, said)
        }
        Piece::Field(f, spec) => {
            for n in field_lengths(*f, spec, s, at, labels) {
                let saved = said.clone();
                if record(*f, spec, &t[..n], said) && match_name(rest, s, at + n, labels, said) {
                    return true;
                }
                *said = saved;
            }
            false
        }
    }
}

/// The lengths field `f` may take at byte `at` of the name `s`, in the order they are
/// tried (the longest reading first).
fn field_lengths(f: Field, spec: &Spec, s: &str, at: usize, labels: &LabelSet<'_>) -> Vec<usize> {
    let t = &s[at..];
    let digits = t.bytes().take_while(u8::is_ascii_digit).count();
    let exact = |n: usize| -> Vec<usize> {
        match spec.width {
            Some(w) if w <= n => vec![w],
            Some(_) => vec![],
            None => (1..=n).rev().collect(),
        }
    };
    match f {
        Field::Position if labels.numeric => exact(digits),
        Field::Position => {
            // a label the poses name first (longest first), then any other run
            let mut v: Vec<usize> = labels
                .labels
                .iter()
                .filter(|l| t.starts_with(l.as_str()))
                .map(String::len)
                .collect();
            v.sort_unstable_by(|a, b| b.cmp(a));
            for n in (1..=t.len()).rev().filter(|&n| t.is_char_boundary(n)) {
                if !v.contains(&n) {
                    v.push(n);
                }
            }
            v
        }
        // an index is unsigned: digits after a `+` are a signed number (an
        // angle), never read as an index (`az+05` is not direction 5)
        Field::Direction | Field::Pulse if s[..at].ends_with('+') => vec![],
        Field::Direction | Field::Pulse => exact(digits),
        Field::Angle => {
            // (spaces first: a width without `0` pads with them)
            let lead = t.bytes().take_while(|&b| b == b' ').count();
            let u = &t[lead..];
            let sg = usize::from(u.starts_with(['+', '-']));
            let int = u[sg..].bytes().take_while(u8::is_ascii_digit).count();
            let mut ends = Vec::new();
            if int > 0 {
                let frac = u[sg + int..]
                    .strip_prefix('.')
                    .map(|r| r.bytes().take_while(u8::is_ascii_digit).count())
                    .unwrap_or(0);
                if frac > 0 {
                    ends.push(lead + sg + int + 1 + frac);
                }
                ends.extend((1..=int).rev().map(|i| lead + sg + i));
            }
            ends
        }
    }
}

/// Record what `text`, read as field `f`, says; false when it is not a value of the field
/// or contradicts what the name said before (`said` is then unchanged).
fn record(f: Field, spec: &Spec, text: &str, said: &mut Said) -> bool {
    match f {
        Field::Position => agree(&mut said.position, text.to_string()),
        Field::Direction | Field::Pulse => match text.parse::<i64>() {
            Ok(v) if f == Field::Pulse => agree(&mut said.pulse, v),
            Ok(v) => agree(&mut said.direction, DirectionValue::Index(v)),
            Err(_) => false,
        },
        Field::Angle => match text.trim_start().parse::<f64>() {
            // the name must be the angle as the format writes it
            Ok(v) if v.is_finite() && written_as(v, spec, text) => {
                agree(&mut said.direction, DirectionValue::Angle(v))
            }
            _ => false,
        },
    }
}

/// Set `slot` to `v` unless it already holds another value (a field named twice must say
/// the same both times).
fn agree<T: PartialEq>(slot: &mut Option<T>, v: T) -> bool {
    if slot.as_ref().is_some_and(|old| *old != v) {
        false
    } else {
        *slot = Some(v);
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn said(pattern: &str, labels: &[&str], name: &str) -> Option<Said> {
        let pcs = parse_pattern(pattern).unwrap();
        let labels: Vec<String> = labels.iter().map(|l| l.to_string()).collect();
        let set = LabelSet {
            numeric: labels.iter().all(|l| l.parse::<i64>().is_ok()),
            labels: &labels,
        };
        let mut v = Said::default();
        match_name(&pcs, name, 0, &set, &mut v).then_some(v)
    }

    #[test]
    fn naming_patterns_match_with_and_without_widths() {
        let v = said(
            "pos{position}_dir{direction:02}_k{pulse}.s2p",
            &["12"],
            "pos12_dir07_k1.s2p",
        )
        .unwrap();
        assert_eq!(v.position.as_deref(), Some("12"));
        assert_eq!(v.direction, Some(DirectionValue::Index(7)));
        assert_eq!(v.pulse, Some(1));
        assert!(said(
            "pos{position}_dir{direction:02}_k{pulse}.s2p",
            &["12"],
            "pos12_dir7_k1.s2p"
        )
        .is_none());
        let v = said("{position}{direction:02}.s1p", &["103"], "10312.s1p").unwrap();
        assert_eq!(v.position.as_deref(), Some("103"));
        assert_eq!(v.direction, Some(DirectionValue::Index(12)));
        assert!(parse_pattern("p{position}.s2p").is_err());
        assert!(parse_pattern("p{position}_{azimuth}.s2p").is_err());
        assert!(parse_pattern("p{position}_{direction}_{angle}.s2p").is_err());
    }

    #[test]
    fn angles_and_labels_in_names() {
        let pat = "{position}_az{angle:+03}.s2p";
        let labels = ["P01", "P02", "P10"];
        for (name, label, angle) in [
            ("P01_az+05.s2p", "P01", 5.0),
            ("P10_az-45.s2p", "P10", -45.0),
            ("P02_az+00.s2p", "P02", 0.0),
            ("P02_az+90.s2p", "P02", 90.0),
            ("P02_az-90.s2p", "P02", -90.0),
        ] {
            let v = said(pat, &labels, name).unwrap_or_else(|| panic!("{name}"));
            assert_eq!(v.position.as_deref(), Some(label), "{name}");
            assert_eq!(v.direction, Some(DirectionValue::Angle(angle)), "{name}");
        }
        // not as the format writes it: no sign, no padding, a decimal point
        for name in [
            "P01_az5.s2p",
            "P01_az+5.s2p",
            "P01_az05.s2p",
            "P01_az+05.0.s2p",
        ] {
            assert!(said(pat, &labels, name).is_none(), "{name}");
        }
        // an unknown label is read (and refused later, naming the file)
        let v = said(pat, &labels, "P13_az+05.s2p").unwrap();
        assert_eq!(v.position.as_deref(), Some("P13"));
        // precision and plain forms
        let v = said("p{position}_{angle:.1}.s2p", &["1"], "p1_-2.5.s2p").unwrap();
        assert_eq!(v.direction, Some(DirectionValue::Angle(-2.5)));
        assert!(said("p{position}_{angle:.1}.s2p", &["1"], "p1_-2.50.s2p").is_none());
        let v = said("p{position}_{angle}.s2p", &["1"], "p1_-45.s2p").unwrap();
        assert_eq!(v.direction, Some(DirectionValue::Angle(-45.0)));
        // without a precision, the decimals the name has (Python writes 5.0 as `5.0`)
        let v = said("p{position}_{angle}.s2p", &["1"], "p1_5.0.s2p").unwrap();
        assert_eq!(v.direction, Some(DirectionValue::Angle(5.0)));
        assert!(said("p{position}_{angle:+}.s2p", &["1"], "p1_5.0.s2p").is_none());
        // `az+05` is a signed number, never direction index 5
        assert!(said("P{position:02}_az+{direction}.s2p", &["3"], "P03_az+05.s2p").is_none());
        assert!(said("P{position:02}_az{direction}.s2p", &["3"], "P03_az+05.s2p").is_none());
        assert_eq!(
            said(
                "P{position:02}_az{direction:02}.s2p",
                &["3"],
                "P03_az05.s2p"
            )
            .unwrap()
            .direction,
            Some(DirectionValue::Index(5))
        );
    }

    #[test]
    fn angle_formats_as_rust_and_python_do() {
        let sp = |s: &str| parse_spec("p", "angle", s, Field::Angle).unwrap();
        assert_eq!(format_angle(5.0, &sp("+03")), format!("{:+03}", 5.0));
        assert_eq!(format_angle(-45.0, &sp("+03")), format!("{:+03}", -45.0));
        assert_eq!(format_angle(0.0, &sp("+03")), "+00");
        assert_eq!(format_angle(-2.5, &sp(".1")), format!("{:.1}", -2.5));
        assert_eq!(format_angle(7.5, &sp("05.1")), format!("{:05.1}", 7.5));
        assert_eq!(format_angle(-90.0, &sp("")), "-90");
        assert!(parse_spec("p", "angle", "x3", Field::Angle).is_err());
    }
}
