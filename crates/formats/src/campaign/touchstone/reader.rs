//! The Touchstone reader: takes a file's text (or path) and gives a [`Network`]
//! ([`parse_touchstone`], [`read_touchstone`]); what is read and what is refused is listed
//! in the [module documentation](super). Errors name the file and the line. The text's
//! lines, tokens and numbers are taken apart in `text`.

use super::network::{decode, ports_from_name, Network, TsFormat, MAX_PORTS, MAX_VALUE};
use super::text::{hfss_block, parse_complex, strip_comment, unit_scale, Lines, Tokens};
use crate::error::{Error, Result};
use num_complex::Complex64;
use std::path::Path;

/// Order of the numbers of a point.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum MatrixFormat {
    Full,
    Lower,
    Upper,
}

struct Parser<'a> {
    path: &'a Path,
    version: u8,
    ports: Option<usize>,
    name_ports: Option<usize>,
    scale: f64,
    fmt: TsFormat,
    option_seen: bool,
    r_option: Vec<Complex64>,
    reference: Option<Vec<Complex64>>,
    legacy_two_port: bool,
    /// The line of `[Two-Port Data Order]`, when given.
    two_port_order: Option<usize>,
    matrix: MatrixFormat,
    declared_points: Option<(usize, usize)>,
    in_network: bool,
    noise: Option<(usize, usize)>,
    freq_hz: Vec<f64>,
    s: Vec<Complex64>,
    hfss_z0: Vec<Vec<f64>>,
    row: Vec<f64>,
    per_point: usize,
    point_line: usize,
}

impl<'a> Parser<'a> {
    fn err(&self, lineno: usize, msg: impl std::fmt::Display) -> Error {
        Error::input(self.path, format!("line {lineno}: {msg}"))
    }

    fn option_line(&mut self, line: &str, lineno: usize) -> Result<()> {
        let mut toks = line[1..].split_ascii_whitespace().peekable();
        while let Some(t) = toks.next() {
            if let Some(s) = unit_scale(t) {
                self.scale = s;
                continue;
            }
            match t.to_ascii_lowercase().as_str() {
                "s" => {}
                "y" | "z" | "h" | "g" => {
                    return Err(self.err(
                        lineno,
                        format!("parameter type `{t}` not supported (only S)"),
                    ))
                }
                "ri" => self.fmt = TsFormat::Ri,
                "ma" => self.fmt = TsFormat::Ma,
                "db" => self.fmt = TsFormat::Db,
                "r" => {
                    // one value, one per port, or none (HFSS: `! Port Impedance` follows)
                    let mut r = Vec::new();
                    while let Some(v) = toks.peek().and_then(|v| parse_complex(v)) {
                        r.push(v);
                        toks.next();
                    }
                    self.r_option = r;
                }
                _ => return Err(self.err(lineno, format!("unknown option `{t}` in option line"))),
            }
        }
        Ok(())
    }

    fn set_ports(&mut self, n: usize, lineno: usize) -> Result<()> {
        if let Some(m) = self.name_ports {
            if m != n {
                return Err(self.err(
                    lineno,
                    format!("[Number of Ports] {n} but the file name says {m} ports (.s{m}p)"),
                ));
            }
        }
        if n == 0 {
            return Err(self.err(lineno, "[Number of Ports] must be at least 1"));
        }
        if n > MAX_PORTS {
            return Err(self.err(lineno, format!("[Number of Ports] {n} exceeds {MAX_PORTS}")));
        }
        self.ports = Some(n);
        Ok(())
    }

    /// A `[keyword]` line; `lines` gives the continuation of `[Reference]`.
    fn keyword(&mut self, line: &str, lineno: usize, lines: &mut Lines<'_>) -> Result<bool> {
        let close = line
            .find(']')
            .ok_or_else(|| self.err(lineno, format!("keyword `{line}` without `]`")))?;
        let key = line[1..close].trim().to_ascii_lowercase();
        let arg = line[close + 1..].trim();
        let number = |p: &Parser<'_>| -> Result<usize> {
            arg.split_ascii_whitespace()
                .next()
                .and_then(|v| v.parse().ok())
                .ok_or_else(|| {
                    p.err(
                        lineno,
                        format!("[{}] needs a whole number", &line[1..close]),
                    )
                })
        };
        match key.as_str() {
            "version" => {
                if !arg.starts_with('2') && !arg.starts_with('1') {
                    return Err(self.err(
                        lineno,
                        format!("Touchstone version `{arg}` not supported (1.x, 2.x)"),
                    ));
                }
                self.version = if arg.starts_with('2') { 2 } else { 1 };
                self.in_network = self.version == 1;
            }
            "number of ports" => {
                let n = number(self)?;
                self.set_ports(n, lineno)?;
            }
            "two-port data order" => {
                self.two_port_order = Some(lineno);
                self.legacy_two_port = match arg {
                    a if a.starts_with("21_12") => true,
                    a if a.starts_with("12_21") => false,
                    _ => {
                        return Err(self.err(
                            lineno,
                            format!("[Two-Port Data Order] `{arg}` (expected 12_21 or 21_12)"),
                        ))
                    }
                }
            }
            "number of frequencies" => self.declared_points = Some((number(self)?, lineno)),
            "number of noise frequencies" => {}
            "reference" => {
                let n = self
                    .ports
                    .ok_or_else(|| self.err(lineno, "[Reference] before [Number of Ports]"))?;
                let mut vals = Vec::with_capacity(n);
                let mut text = arg.to_string();
                loop {
                    for t in text.split_ascii_whitespace() {
                        let v = parse_complex(t).ok_or_else(|| {
                            self.err(
                                lineno,
                                format!("[Reference]: cannot parse `{t}` as an impedance"),
                            )
                        })?;
                        vals.push(v);
                    }
                    if vals.len() >= n {
                        break;
                    }
                    match lines.next() {
                        Some((_, l)) => text = strip_comment(l).to_string(),
                        None => break,
                    }
                }
                if vals.len() != n {
                    return Err(self.err(
                        lineno,
                        format!("[Reference] has {} values for {n} ports", vals.len()),
                    ));
                }
                self.reference = Some(vals);
            }
            "matrix format" => {
                self.matrix = match arg.to_ascii_lowercase().as_str() {
                    "full" => MatrixFormat::Full,
                    "lower" => MatrixFormat::Lower,
                    "upper" => MatrixFormat::Upper,
                    _ => {
                        return Err(self.err(
                            lineno,
                            format!("[Matrix Format] `{arg}` (expected Full, Lower or Upper)"),
                        ))
                    }
                }
            }
            "mixed-mode order" => {
                return Err(self.err(lineno, "mixed-mode data ([Mixed-Mode Order]) not supported"))
            }
            "begin information" => {
                for (_, l) in lines.by_ref() {
                    if l.trim()
                        .to_ascii_lowercase()
                        .starts_with("[end information]")
                    {
                        break;
                    }
                }
            }
            "network data" => self.in_network = true,
            "noise data" => {
                self.in_network = false;
                self.noise = Some((lineno, 0));
            }
            "end" => return Ok(false),
            _ => return Err(self.err(lineno, format!("unknown keyword `[{}]`", &line[1..close]))),
        }
        Ok(true)
    }

    fn start_points(&mut self, lineno: usize) -> Result<usize> {
        let n = match self.ports {
            Some(n) => n,
            None if self.version == 2 => {
                return Err(self.err(lineno, "data before [Number of Ports]"))
            }
            None => return Err(Error::input(
                self.path,
                "cannot tell the port count: a Touchstone v1 file must be named .sNp (e.g. .s2p)",
            )),
        };
        if self.version == 2 && n == 2 && self.two_port_order.is_none() {
            // v2.0 requires it of two-ports: without it, which pair is S21 is a guess
            return Err(self.err(
                lineno,
                "[Two-Port Data Order] missing: Touchstone v2.0 requires it (12_21 or 21_12) before the data of a two-port file, which pair is S21 is otherwise unknown",
            ));
        }
        let values = match self.matrix {
            MatrixFormat::Full => n * n,
            MatrixFormat::Lower | MatrixFormat::Upper => n * (n + 1) / 2,
        };
        self.per_point = 1 + 2 * values;
        self.row = Vec::with_capacity(self.per_point);
        Ok(n)
    }

    /// One data line (a `!` comment ends it). The hot path of the energy stage: the
    /// point's numbers are gathered in a local buffer, the fields read once.
    fn data_line(&mut self, line: &str, lineno: usize) -> Result<()> {
        if self.per_point == 0 {
            self.start_points(lineno)?;
        }
        let n = self.ports.expect("set by start_points");
        let per = self.per_point;
        if !self.row.is_empty() {
            // a continuation line holds (a, b) pairs only: an odd count means the point
            // started earlier than the port count says (e.g. one-port data named .s2p)
            let count = Tokens::new(line).count();
            if count % 2 == 1 {
                return Err(self.err(
                    lineno,
                    format!(
                        "{count} numbers on a continuation line (pairs expected): a {n}-port point has {per} numbers; is the port count right?"
                    ),
                ));
            }
        }
        let db = self.fmt == TsFormat::Db;
        let mut row = std::mem::take(&mut self.row);
        let mut toks = Tokens::new(line);
        let result = (|| {
            while let Some(tok) = toks.next() {
                let v: f64 = tok
                    .parse()
                    .map_err(|_| self.err(lineno, format!("cannot parse `{tok}` as a number")))?;
                let idx = row.len();
                // scikit-rf writes 20·log10(0) = -inf for |S| = 0
                if !(v.is_finite() || (db && idx % 2 == 1 && v == f64::NEG_INFINITY)) {
                    return Err(self.err(lineno, format!("non-finite value `{tok}`")));
                }
                // a value whose energy (|S|², summed over a sweep) would overflow to inf
                let over = match self.fmt {
                    _ if idx == 0 => false,
                    TsFormat::Ri => v.abs() > MAX_VALUE,
                    TsFormat::Ma => idx % 2 == 1 && v.abs() > MAX_VALUE,
                    TsFormat::Db => idx % 2 == 1 && v > 20.0 * MAX_VALUE.log10(),
                };
                if over {
                    return Err(self.err(
                        lineno,
                        format!("value `{tok}` overflows (|S| above {MAX_VALUE:e}: its energy is not finite)"),
                    ));
                }
                if idx == 0 {
                    let f = v * self.scale;
                    if let Some(&last) = self.freq_hz.last() {
                        // v1 two-port noise parameters follow the S data: rows of five
                        // numbers (f, NFmin, |Γopt|, ∠Γopt, Rn) whose frequency falls; a
                        // falling row of any other length is S data out of order
                        if f < last && n == 2 && self.version == 1 && Tokens::new(line).count() == 5
                        {
                            self.noise = Some((lineno, 1));
                            return Ok(());
                        }
                        if f <= last {
                            let prev = self.point_line;
                            let what = if f == last { "repeats" } else { "below" };
                            return Err(self.err(
                                lineno,
                                format!(
                                    "frequency {f} Hz not increasing ({what} {last} Hz of line {prev}): the rows stop increasing here (swapped or reversed?)"
                                ),
                            ));
                        }
                    }
                    self.point_line = lineno;
                }
                row.push(v);
                if row.len() == per {
                    self.finish_point(n, &row);
                    row.clear();
                    if toks.next().is_some() {
                        return Err(self.err(
                            lineno,
                            format!(
                                "more numbers after a complete point: a {n}-port point has {per} numbers; is the port count right?"
                            ),
                        ));
                    }
                    return Ok(());
                }
            }
            Ok(())
        })();
        self.row = row;
        result
    }

    fn finish_point(&mut self, n: usize, row: &[f64]) {
        let fmt = self.fmt;
        let pair = |a: f64, b: f64| -> Complex64 {
            match fmt {
                TsFormat::Ri => Complex64::new(a, b),
                TsFormat::Ma => Complex64::from_polar(a, b * std::f64::consts::PI / 180.0),
                TsFormat::Db => {
                    Complex64::from_polar(10f64.powf(a / 20.0), b * std::f64::consts::PI / 180.0)
                }
            }
        };
        self.freq_hz.push(row[0] * self.scale);
        let vals = row[1..].chunks_exact(2).map(|c| pair(c[0], c[1]));
        let base = self.s.len();
        self.s.resize(base + n * n, Complex64::new(0.0, 0.0));
        let m = &mut self.s[base..];
        match self.matrix {
            MatrixFormat::Full if n == 2 && self.legacy_two_port => {
                // S11 S21 S12 S22
                for (idx, v) in [0, 2, 1, 3].into_iter().zip(vals) {
                    m[idx] = v;
                }
            }
            MatrixFormat::Full => {
                for (o, v) in m.iter_mut().zip(vals) {
                    *o = v;
                }
            }
            MatrixFormat::Lower | MatrixFormat::Upper => {
                let lower = self.matrix == MatrixFormat::Lower;
                let cells = (0..n).flat_map(|i| {
                    let js: Box<dyn Iterator<Item = usize>> = if lower {
                        Box::new(0..=i)
                    } else {
                        Box::new(i..n)
                    };
                    js.map(move |j| (i, j))
                });
                for ((i, j), v) in cells.zip(vals) {
                    m[i * n + j] = v;
                    m[j * n + i] = v;
                }
            }
        }
    }
}

/// Parse the text of a Touchstone file; `path` names it in errors and gives the port count
/// of a v1 file (`.sNp`).
pub fn parse_touchstone(text: &str, path: &Path) -> Result<Network> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let mut p = Parser::new(path);
    let mut lines = Lines::new(text);
    let noise_rows = p.read_lines(&mut lines)?;
    let (n, points) = p.complete()?;
    let mut notes = Vec::new();
    if let Some((lineno, _)) = p.noise {
        notes.push(format!(
            "noise parameters from line {lineno} ({noise_rows} rows) recognised and skipped"
        ));
    }
    // reference impedance: HFSS comments per point, else [Reference], else the option line
    let z0_ohm = if !p.hfss_z0.is_empty() {
        p.hfss_reference(n, points)?
    } else {
        p.option_reference(n, points)?
    };
    Ok(Network {
        ports: n,
        version: p.version,
        freq_hz: p.freq_hz,
        s: p.s,
        z0_ohm,
        notes,
    })
}

impl<'a> Parser<'a> {
    /// Takes the file's path (named in errors; a v1 file's port count comes from its
    /// name); gives the parser before the first line: version 1, GHz, MA, 50 Ω, the full
    /// matrix, in the network data.
    fn new(path: &'a Path) -> Parser<'a> {
        let name_ports = ports_from_name(path);
        Parser {
            path,
            version: 1,
            ports: name_ports,
            name_ports,
            scale: 1e9,
            fmt: TsFormat::Ma,
            option_seen: false,
            r_option: vec![Complex64::new(50.0, 0.0)],
            reference: None,
            legacy_two_port: true,
            two_port_order: None,
            matrix: MatrixFormat::Full,
            declared_points: None,
            in_network: true,
            noise: None,
            freq_hz: Vec::new(),
            s: Vec::new(),
            hfss_z0: Vec::new(),
            row: Vec::new(),
            per_point: 0,
            point_line: 0,
        }
    }

    /// Takes the file's lines; reads every one (comments with HFSS port impedances, the
    /// option line, keywords, data rows) up to the end or `[End]`, and gives the number
    /// of noise-parameter rows skipped.
    fn read_lines(&mut self, lines: &mut Lines<'_>) -> Result<usize> {
        let mut noise_rows = 0usize;
        while let Some((lineno, raw)) = lines.next() {
            let t = raw.trim();
            if t.is_empty() {
                continue;
            }
            if let Some(c) = t.strip_prefix('!') {
                let c = c.trim_start();
                // `get`: byte 14 may fall inside a character of a non-ASCII comment
                if c.get(..14)
                    .is_some_and(|h| h.eq_ignore_ascii_case("port impedance"))
                {
                    let vals = hfss_block(&c[14..], lines);
                    self.hfss_z0.push(vals);
                }
                continue;
            }
            if t.starts_with('#') {
                let line = strip_comment(t);
                if !self.option_seen {
                    self.option_line(line, lineno)?;
                    self.option_seen = true;
                }
                continue;
            }
            if t.starts_with('[') {
                if !self.keyword(strip_comment(t), lineno, lines)? {
                    break;
                }
                continue;
            }
            if self.noise.is_some() {
                noise_rows += 1;
                continue;
            }
            if !self.in_network {
                return Err(self.err(lineno, "data before [Network Data]"));
            }
            self.data_line(t, lineno)?;
            if self.noise.is_some() {
                noise_rows += 1;
            }
        }
        Ok(noise_rows)
    }

    /// After the last line: gives (ports, frequency points), or the error of a truncated
    /// last row, of no data row, or of a point count other than `[Number of Frequencies]`.
    fn complete(&self) -> Result<(usize, usize)> {
        if !self.row.is_empty() {
            return Err(self.err(
                self.point_line,
                format!(
                    "truncated data row ({} of {} numbers)",
                    self.row.len(),
                    self.per_point
                ),
            ));
        }
        if self.freq_hz.is_empty() {
            return Err(Error::input(self.path, "no data rows"));
        }
        let n = self.ports.expect("data rows imply a port count");
        let points = self.freq_hz.len();
        if let Some((want, lineno)) = self.declared_points {
            if want != points {
                return Err(self.err(
                    lineno,
                    format!("[Number of Frequencies] {want} but the file holds {points} points"),
                ));
            }
        }
        Ok((n, points))
    }

    /// Takes the port and point counts; gives the reference impedance per point and port
    /// from the HFSS `! Port Impedance` blocks (one per point: the diagonal of an n × n
    /// block, or n values), or the error naming a block that is neither.
    fn hfss_reference(&self, n: usize, points: usize) -> Result<Vec<Complex64>> {
        let path = self.path;
        if self.hfss_z0.len() != points {
            return Err(Error::input(
                path,
                format!(
                    "{} `! Port Impedance` blocks for {points} frequency points",
                    self.hfss_z0.len()
                ),
            ));
        }
        let mut z = Vec::with_capacity(points * n);
        for (k, b) in self.hfss_z0.iter().enumerate() {
            let c: Vec<Complex64> = b
                .chunks_exact(2)
                .map(|c| Complex64::new(c[0], c[1]))
                .collect();
            if c.len() == n * n && n != 1 {
                z.extend((0..n).map(|i| c[i * n + i]));
            } else if c.len() == n && b.len() == 2 * n {
                z.extend(c);
            } else {
                return Err(Error::input(
                    path,
                    format!(
                        "`! Port Impedance` block {} has {} numbers, expected {} or {} for {n} ports",
                        k + 1,
                        b.len(),
                        2 * n,
                        2 * n * n
                    ),
                ));
            }
        }
        Ok(z)
    }

    /// Takes the port and point counts; gives the reference impedance per point and port
    /// from `[Reference]`, else the option line (one value for every port, one per port,
    /// or 50 Ω), or the error of an option line with another count.
    fn option_reference(&self, n: usize, points: usize) -> Result<Vec<Complex64>> {
        let path = self.path;
        let r = match &self.reference {
            Some(r) => r.clone(),
            None if self.r_option.len() == 1 => vec![self.r_option[0]; n],
            None if self.r_option.len() == n => self.r_option.clone(),
            None if self.r_option.is_empty() => vec![Complex64::new(50.0, 0.0); n],
            None => {
                return Err(Error::input(
                    path,
                    format!(
                        "option line gives {} reference impedances for {n} ports",
                        self.r_option.len()
                    ),
                ))
            }
        };
        Ok((0..points).flat_map(|_| r.iter().copied()).collect())
    }
}

/// Read a Touchstone file (bytes decoded by [`decode`]).
pub fn read_touchstone(path: &Path) -> Result<Network> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    parse_touchstone(&decode(&bytes), path)
}

#[cfg(test)]
mod tests {
    use super::super::network::SParam;
    use super::*;

    fn p(text: &str, name: &str) -> Result<Network> {
        parse_touchstone(text, Path::new(name))
    }

    #[test]
    fn options_anywhere_before_data_and_units() {
        let t = "! comment\n!another\n\n# MHz S RI R 50\n! mid\n100 1 0 0.5 -0.5 0.5 -0.5 0 1 ! trailing\n200 1 0 0.25 0 0.25 0 0 1\n";
        let ts = p(t, "a.s2p").unwrap();
        assert_eq!(ts.freq_hz, vec![100e6, 200e6]);
        assert_eq!(ts.get(0, 1, 0), Complex64::new(0.5, -0.5));
        assert_eq!(ts.get(0, 1, 1), Complex64::new(0.0, 1.0));
    }

    #[test]
    fn default_options_are_ghz_ma() {
        let ts = p("60 0 0 2 90 0 0 0 0\n", "a.s2p").unwrap();
        assert_eq!(ts.freq_hz[0], 60e9);
        assert!((ts.get(0, 1, 0) - Complex64::new(0.0, 2.0)).norm() < 1e-12);
        assert_eq!(ts.z0_ohm, vec![Complex64::new(50.0, 0.0); 2]);
    }

    #[test]
    fn db_format_and_minus_inf() {
        let ts = p("# Hz S DB R 50\n1 -inf 0 -20 180 0 0 0 0\n", "a.S2P").unwrap();
        assert!((ts.get(0, 1, 0) - Complex64::new(-0.1, 0.0)).norm() < 1e-12);
        assert_eq!(ts.get(0, 0, 0), Complex64::new(0.0, 0.0));
        // -inf is only a dB magnitude
        let e = p("# Hz S RI R 50\n1 -inf 0 0 0 0 0 0 0\n", "a.s2p").unwrap_err();
        assert!(e.to_string().contains("line 2: non-finite"), "{e}");
    }

    /// The old reader regrouped a one-port file nine numbers at a time (silently wrong
    /// when the point count was a multiple of 3).
    #[test]
    fn one_port_points_are_three_numbers() {
        let t = "# GHz S RI R 50\n1 0.1 0.2\n2 0.3 0.4\n3 0.5 0.6\n";
        let ts = p(t, "m.s1p").unwrap();
        assert_eq!(ts.ports, 1);
        assert_eq!(ts.freq_hz, vec![1e9, 2e9, 3e9]);
        assert_eq!(ts.get(2, 0, 0), Complex64::new(0.5, 0.6));
        let e = ts.param(SParam::S21, Path::new("m.s1p")).unwrap_err();
        assert!(
            e.to_string()
                .contains("m.s1p: parameter S21 does not exist in a 1-port file"),
            "{e}"
        );
        assert_eq!(
            ts.param(SParam::S11, Path::new("m.s1p")).unwrap()[1],
            Complex64::new(0.3, 0.4)
        );
        // a two-port file named .s1p: the point ends inside the line
        let e = p("# GHz S RI R 50\n1 0 0 1 0 1 0 0 0\n", "x.s1p").unwrap_err();
        assert!(
            e.to_string()
                .contains("x.s1p: line 2: more numbers after a complete point"),
            "{e}"
        );
    }

    #[test]
    fn three_port_wrapped_row_major() {
        let t = "# Hz S RI R 50\n1 11 0 12 0 13 0\n 21 0 22 0 23 0\n 31 0 32 0 33 0\n2 1 0 2 0 3 0\n 4 0 5 0 6 0\n 7 0 8 0 9 0\n";
        let ts = p(t, "a.s3p").unwrap();
        assert_eq!(ts.ports, 3);
        assert_eq!(ts.get(0, 1, 2), Complex64::new(23.0, 0.0));
        assert_eq!(ts.get(1, 2, 0), Complex64::new(7.0, 0.0));
        assert_eq!(
            ts.param("S3,1".parse().unwrap(), Path::new("a")).unwrap(),
            vec![Complex64::new(31.0, 0.0), Complex64::new(7.0, 0.0)]
        );
    }

    #[test]
    fn version_two_with_reference_matrix_format_and_noise() {
        let t = "[Version] 2.0\r\n# GHz S MA R 50\r\n[Number of Ports] 2\r\n[Two-Port Data Order] 12_21\r\n[Number of Frequencies] 2\r\n[Reference] 50\r\n 75\r\n[Matrix Format] Full\r\n[Network Data]\r\n1 1 0 2 0 3 0 4 0\r\n2 1 0 2 0 3 0 4 0\r\n[Noise Data]\r\n1 1 0.5 10 0.3\r\n[End]\r\n";
        let ts = p(t, "a.ts").unwrap();
        assert_eq!(ts.version, 2);
        assert_eq!(ts.get(0, 0, 1), Complex64::new(2.0, 0.0));
        assert_eq!(ts.z0_ohm[1], Complex64::new(75.0, 0.0));
        assert_eq!(ts.notes.len(), 1, "{:?}", ts.notes);
        let lower = "[Version] 2.0\n# Hz S RI R 50\n[Number of Ports] 3\n[Matrix Format] Lower\n[Network Data]\n1 11 0\n 21 0 22 0\n 31 0 32 0 33 0\n[End]\n";
        let ts = p(lower, "b.ts").unwrap();
        assert_eq!(ts.get(0, 0, 2), Complex64::new(31.0, 0.0));
        assert_eq!(ts.get(0, 2, 1), Complex64::new(32.0, 0.0));
        let e = p("[Version] 2.0\n[Number of Ports] 4\n", "c.s2p").unwrap_err();
        assert!(
            e.to_string()
                .contains("c.s2p: line 2: [Number of Ports] 4 but the file name says 2"),
            "{e}"
        );
    }

    #[test]
    fn v2_two_port_without_data_order_is_refused() {
        let t = "[Version] 2.0\n# GHz S RI R 50\n[Number of Ports] 2\n[Network Data]\n1 1 0 2 0 3 0 4 0\n[End]\n";
        let e = p(t, "a.ts").unwrap_err().to_string();
        assert!(
            e.contains("a.ts: line 5:") && e.contains("[Two-Port Data Order]"),
            "{e}"
        );
        assert!(!e.contains('\n'));
        // with it, and for other port counts (which have no such keyword), accepted
        let with = t.replace(
            "[Network Data]",
            "[Two-Port Data Order] 12_21\n[Network Data]",
        );
        assert!(p(&with, "a.ts").is_ok());
        let one =
            "[Version] 2.0\n# GHz S RI R 50\n[Number of Ports] 1\n[Network Data]\n1 1 0\n[End]\n";
        assert!(p(one, "a.ts").is_ok());
    }

    #[test]
    fn v1_noise_block_after_two_port_data() {
        let t = "# GHz S MA R 50\n1 0 0 1 0 1 0 0 0\n2 0 0 1 0 1 0 0 0\n! Noise\n1 1.5 0.3 20 0.2\n2 1.6 0.3 21 0.2\n";
        let ts = p(t, "n.s2p").unwrap();
        assert_eq!(ts.freq_hz.len(), 2);
        assert!(ts.notes[0].contains("line 5 (2 rows)"), "{:?}", ts.notes);
    }

    #[test]
    fn bom_latin1_cr_complex_and_per_port_reference() {
        let mut bytes =
            b"\xEF\xBB\xBF! 25\xB0C\r# Hz S RI R 50 (10+10j)\r1 1 0 0 0 0 0 1 0\r".to_vec();
        let ts = parse_touchstone(&decode(&bytes), Path::new("a.s2p")).unwrap();
        assert_eq!(ts.z0_ohm[1], Complex64::new(10.0, 10.0));
        assert_eq!(ts.get(0, 1, 1), Complex64::new(1.0, 0.0));
        bytes.drain(..3);
        assert!(parse_touchstone(&decode(&bytes), Path::new("a.s2p")).is_ok());
    }

    #[test]
    fn hfss_port_impedance_comments() {
        let t = "# GHz S MA R\n1 0 0 1 0 1 0 0 0\n! Port Impedance 49.5 0.1 50.5 -0.2\n2 0 0 1 0 1 0 0 0\n! Port Impedance 49 0 51\n! 0\n";
        let ts = p(t, "h.s2p").unwrap();
        assert_eq!(ts.z0_ohm[0], Complex64::new(49.5, 0.1));
        assert_eq!(ts.z0_ohm[3], Complex64::new(51.0, 0.0));
    }

    #[test]
    fn errors_name_line() {
        let e = p("# Hz S RI R 50\n1 0 0 x 0 0 0 0 0\n", "b.s2p").unwrap_err();
        assert!(e.to_string().contains("b.s2p: line 2"), "{e}");
        let e = p("# Hz S RI R 50\n1 0 0 NaN 0 0 0 0 0\n", "b.s2p").unwrap_err();
        assert!(e.to_string().contains("non-finite"), "{e}");
        let e = p("# Hz S RI R 50\n1 0 0 1 0 0 0 0 0\n2 0 0 1\n", "b.s2p").unwrap_err();
        assert!(e.to_string().contains("line 3: truncated"), "{e}");
        let e = p("# Hz Z RI R 50\n", "b.s2p").unwrap_err();
        assert!(e.to_string().contains("only S"), "{e}");
        let e = p("# Hz S RI R 50\n1 0 0\n", "b.txt").unwrap_err();
        assert!(e.to_string().contains("must be named .sNp"), "{e}");
        let e = p("# Hz S RI R 50\n2 0 0\n1 0 0\n", "b.s1p").unwrap_err();
        assert!(
            e.to_string()
                .contains("line 3: frequency 1 Hz not increasing"),
            "{e}"
        );
        // a swapped pair of two-port rows is not a v1 noise block: it names both lines
        let e = p(
            "# Hz S RI R 50\n1 0 0 1 0 0 0 0 0\n3 0 0 1 0 0 0 0 0\n2 0 0 1 0 0 0 0 0\n",
            "b.s2p",
        )
        .unwrap_err()
        .to_string();
        assert!(
            e.contains("line 4: frequency 2 Hz not increasing (below 3 Hz of line 3)")
                && e.contains("swapped or reversed"),
            "{e}"
        );
        let e = p("# Hz S RI R 50\n1 0 0\n1 0 0\n", "b.s1p").unwrap_err();
        assert!(e.to_string().contains("(repeats 1 Hz of line 2)"), "{e}");
    }
}
