//! The Touchstone writer: takes a two-port network's frequencies and S matrices and gives a
//! Touchstone v1 `.s2p` text ([`write_s2p`]) in RI, MA or DB.

use super::network::TsFormat;
use num_complex::Complex64;
use std::io::Write;

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
    use crate::campaign::touchstone::parse_touchstone;
    use std::path::Path;

    fn p(text: &str, name: &str) -> crate::error::Result<super::super::Network> {
        parse_touchstone(text, Path::new(name))
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
            let back = p(std::str::from_utf8(&buf).unwrap(), "m.s2p").unwrap();
            assert_eq!(back.freq_hz, f);
            for (k, a) in s.iter().enumerate() {
                // written S11 S21 S12 S22
                let b = [
                    back.get(k, 0, 0),
                    back.get(k, 1, 0),
                    back.get(k, 0, 1),
                    back.get(k, 1, 1),
                ];
                for i in 0..4 {
                    if fmt == TsFormat::Ri {
                        let q = |v: f64| format!("{v:.12e}").parse::<f64>().unwrap();
                        assert_eq!(b[i].re, q(a[i].re));
                        assert_eq!(b[i].im, q(a[i].im));
                    } else {
                        assert!((a[i] - b[i]).norm() < 1e-11 * a[i].norm().max(1e-3));
                    }
                }
            }
        }
    }
}
