//! Touchstone v1 two-port files (`.s2p`) as a VNA writes them and scikit-rf reads them.
//!
//! Takes text with `!` comments (whole-line or trailing), an option line
//! `# <Hz|kHz|MHz|GHz> S <RI|MA|DB> R <z0>` anywhere before the first data line (defaults
//! `GHz S MA R 50` when absent), and data rows `f S11 S21 S12 S22` (two numbers each; rows
//! may wrap, tokens are grouped nine at a time). Gives the frequency grid in Hz and the four
//! complex S-parameters. MA and DB angles are in degrees; DB magnitude is 20·log10|S|.
//!
//! Why not the `touchstone` crate (0.17, evaluated): it parses into its own network type
//! with an allocation per row and reports errors without file line numbers; the energy stage
//! reads tens of thousands of files and must name the file and line of a bad number, so a
//! small dedicated reader is both faster and gives the errors users need.

use crate::error::{Error, Result};
use num_complex::Complex64;
use std::io::Write;
use std::path::Path;

/// Number representation of the data rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum TsFormat {
    /// Real / imaginary.
    Ri,
    /// Magnitude / angle (degrees).
    Ma,
    /// dB (20·log10) / angle (degrees).
    Db,
}

/// A parsed two-port network.
#[derive(Debug, Clone, PartialEq)]
pub struct Touchstone {
    /// Frequencies, Hz.
    pub freq_hz: Vec<f64>,
    /// S11, S21, S12, S22 per frequency.
    pub s: Vec<[Complex64; 4]>,
    /// Reference impedance, ohm.
    pub z0: f64,
}

fn unit_scale(tok: &str) -> Option<f64> {
    match tok.to_ascii_lowercase().as_str() {
        "hz" => Some(1.0),
        "khz" => Some(1e3),
        "mhz" => Some(1e6),
        "ghz" => Some(1e9),
        _ => None,
    }
}

fn to_complex(fmt: TsFormat, a: f64, b: f64) -> Complex64 {
    match fmt {
        TsFormat::Ri => Complex64::new(a, b),
        TsFormat::Ma => Complex64::from_polar(a, b.to_radians()),
        TsFormat::Db => Complex64::from_polar(10f64.powf(a / 20.0), b.to_radians()),
    }
}

struct Options {
    scale: f64,
    fmt: TsFormat,
    z0: f64,
}

fn parse_option_line(line: &str, path: &Path, lineno: usize) -> Result<Options> {
    let mut o = Options {
        scale: 1e9,
        fmt: TsFormat::Ma,
        z0: 50.0,
    };
    let mut toks = line[1..].split_ascii_whitespace();
    while let Some(t) = toks.next() {
        if let Some(s) = unit_scale(t) {
            o.scale = s;
            continue;
        }
        match t.to_ascii_lowercase().as_str() {
            "s" => {}
            "y" | "z" | "h" | "g" => {
                return Err(Error::input(
                    path,
                    format!("line {lineno}: parameter type `{t}` not supported (only S)"),
                ))
            }
            "ri" => o.fmt = TsFormat::Ri,
            "ma" => o.fmt = TsFormat::Ma,
            "db" => o.fmt = TsFormat::Db,
            "r" => {
                let v = toks.next().ok_or_else(|| {
                    Error::input(path, format!("line {lineno}: option `R` without a value"))
                })?;
                o.z0 = v.parse().map_err(|_| {
                    Error::input(
                        path,
                        format!("line {lineno}: bad reference impedance `{v}`"),
                    )
                })?;
            }
            _ => {
                return Err(Error::input(
                    path,
                    format!("line {lineno}: unknown option `{t}` in option line"),
                ))
            }
        }
    }
    Ok(o)
}

/// Parse the text of a `.s2p` file; `path` names it in errors.
pub fn parse_s2p(text: &str, path: &Path) -> Result<Touchstone> {
    let mut opts: Option<Options> = None;
    let mut freq_hz = Vec::new();
    let mut s = Vec::new();
    let mut row = [0f64; 9];
    let mut n = 0usize;
    let mut row_line = 0usize;
    for (i, raw) in text.lines().enumerate() {
        let lineno = i + 1;
        let line = match raw.find('!') {
            Some(p) => &raw[..p],
            None => raw,
        }
        .trim();
        if line.is_empty() {
            continue;
        }
        if line.starts_with('#') {
            if opts.is_none() && freq_hz.is_empty() && n == 0 {
                opts = Some(parse_option_line(line, path, lineno)?);
            }
            continue;
        }
        if line.starts_with('[') {
            return Err(Error::input(
                path,
                format!("line {lineno}: Touchstone v2 keyword `{line}` not supported (write v1)"),
            ));
        }
        let o = opts.get_or_insert(Options {
            scale: 1e9,
            fmt: TsFormat::Ma,
            z0: 50.0,
        });
        for tok in line.split_ascii_whitespace() {
            let v: f64 = tok.parse().map_err(|_| {
                Error::input(
                    path,
                    format!("line {lineno}: cannot parse `{tok}` as a number"),
                )
            })?;
            if !v.is_finite() {
                return Err(Error::input(
                    path,
                    format!("line {lineno}: non-finite value `{tok}`"),
                ));
            }
            if n == 0 {
                row_line = lineno;
            }
            row[n] = v;
            n += 1;
            if n == 9 {
                let f = row[0] * o.scale;
                if let Some(&last) = freq_hz.last() {
                    if f <= last {
                        return Err(Error::input(
                            path,
                            format!("line {row_line}: frequency {f} Hz not increasing"),
                        ));
                    }
                }
                freq_hz.push(f);
                s.push([
                    to_complex(o.fmt, row[1], row[2]),
                    to_complex(o.fmt, row[3], row[4]),
                    to_complex(o.fmt, row[5], row[6]),
                    to_complex(o.fmt, row[7], row[8]),
                ]);
                n = 0;
            }
        }
    }
    if n != 0 {
        return Err(Error::input(
            path,
            format!("line {row_line}: truncated data row ({n} of 9 numbers)"),
        ));
    }
    if freq_hz.is_empty() {
        return Err(Error::input(path, "no data rows"));
    }
    Ok(Touchstone {
        freq_hz,
        s,
        z0: opts.map(|o| o.z0).unwrap_or(50.0),
    })
}

/// Read a `.s2p` file.
pub fn read_s2p(path: &Path) -> Result<Touchstone> {
    let text = crate::io::read_text(path)?;
    parse_s2p(&text, path)
}

/// Write a two-port network as Touchstone v1 with the given format and `digits` significant
/// digits after the decimal point (scientific notation), frequencies in Hz.
pub fn write_s2p<W: Write>(
    w: &mut W,
    freq_hz: &[f64],
    s: &[[Complex64; 4]],
    fmt: TsFormat,
    digits: usize,
    comment: &str,
) -> std::io::Result<()> {
    for c in comment.lines() {
        writeln!(w, "! {c}")?;
    }
    let f = match fmt {
        TsFormat::Ri => "RI",
        TsFormat::Ma => "MA",
        TsFormat::Db => "DB",
    };
    writeln!(w, "# Hz S {f} R 50")?;
    let mut line = String::with_capacity(256);
    for (fr, sp) in freq_hz.iter().zip(s) {
        use std::fmt::Write as _;
        line.clear();
        let _ = write!(line, "{fr:.0}");
        for z in sp {
            let (a, b) = match fmt {
                TsFormat::Ri => (z.re, z.im),
                TsFormat::Ma => (z.norm(), z.arg().to_degrees()),
                TsFormat::Db => (20.0 * z.norm().max(1e-300).log10(), z.arg().to_degrees()),
            };
            let _ = write!(line, " {a:.digits$e} {b:.digits$e}");
        }
        line.push('\n');
        w.write_all(line.as_bytes())?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn options_anywhere_before_data_and_units() {
        let t = "! comment\n!another\n\n# MHz S RI R 50\n! mid\n100 1 0 0.5 -0.5 0.5 -0.5 0 1 ! trailing\n200 1 0 0.25 0 0.25 0 0 1\n";
        let ts = parse_s2p(t, Path::new("a.s2p")).unwrap();
        assert_eq!(ts.freq_hz, vec![100e6, 200e6]);
        assert_eq!(ts.s[0][1], Complex64::new(0.5, -0.5));
    }

    #[test]
    fn default_options_are_ghz_ma() {
        let ts = parse_s2p("60 0 0 2 90 0 0 0 0\n", Path::new("a.s2p")).unwrap();
        assert_eq!(ts.freq_hz[0], 60e9);
        assert!((ts.s[0][1] - Complex64::new(0.0, 2.0)).norm() < 1e-12);
    }

    #[test]
    fn db_format() {
        let ts = parse_s2p(
            "# Hz S DB R 50\n1 0 0 -20 180 0 0 0 0\n",
            Path::new("a.s2p"),
        )
        .unwrap();
        assert!((ts.s[0][1] - Complex64::new(-0.1, 0.0)).norm() < 1e-12);
    }

    #[test]
    fn errors_name_line() {
        let e = parse_s2p("# Hz S RI R 50\n1 0 0 x 0 0 0 0 0\n", Path::new("b.s2p")).unwrap_err();
        assert!(
            e.to_string().contains("b.s2p") && e.to_string().contains("line 2"),
            "{e}"
        );
        let e = parse_s2p("# Hz S RI R 50\n1 0 0 NaN 0 0 0 0 0\n", Path::new("b.s2p")).unwrap_err();
        assert!(e.to_string().contains("non-finite"), "{e}");
        let e = parse_s2p(
            "# Hz S RI R 50\n1 0 0 1 0 0 0 0 0\n2 0 0 1\n",
            Path::new("b.s2p"),
        )
        .unwrap_err();
        assert!(e.to_string().contains("truncated"), "{e}");
        let e = parse_s2p("# Hz Z RI R 50\n", Path::new("b.s2p")).unwrap_err();
        assert!(e.to_string().contains("only S"), "{e}");
    }

    #[test]
    fn round_trip_to_printed_precision() {
        let f: Vec<f64> = (0..50).map(|k| 57.5e9 + k as f64 * 1e8).collect();
        let s: Vec<[Complex64; 4]> = (0..50)
            .map(|k| {
                let z = Complex64::from_polar(0.01 + k as f64 * 1e-3, 0.37 * k as f64);
                [z, z * 0.5, z.conj(), -z]
            })
            .collect();
        for fmt in [TsFormat::Ri, TsFormat::Ma, TsFormat::Db] {
            let mut buf = Vec::new();
            write_s2p(&mut buf, &f, &s, fmt, 12, "test").unwrap();
            let back = parse_s2p(std::str::from_utf8(&buf).unwrap(), Path::new("m")).unwrap();
            assert_eq!(back.freq_hz, f);
            for (a, b) in s.iter().zip(&back.s) {
                for i in 0..4 {
                    if fmt == TsFormat::Ri {
                        // exact to the printed digits
                        let p = |v: f64| format!("{v:.12e}").parse::<f64>().unwrap();
                        assert_eq!(b[i].re, p(a[i].re));
                        assert_eq!(b[i].im, p(a[i].im));
                    } else {
                        assert!((a[i] - b[i]).norm() < 1e-11 * a[i].norm().max(1e-3));
                    }
                }
            }
        }
    }
}
