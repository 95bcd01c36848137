//! The network model of a Touchstone file: the parsed [`Network`] (frequencies, S matrices,
//! reference impedances, notes), one S-parameter [`SParam`], the number format [`TsFormat`],
//! the text decoding of a file's bytes ([`decode`]), the port count of a `.sNp` name
//! ([`ports_from_name`]) and the bounds the reader enforces ([`MAX_PORTS`], [`MAX_VALUE`]).

use crate::error::{Error, Result};
use num_complex::Complex64;
use std::borrow::Cow;
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

/// One S-parameter S_ij (i = output port, j = input port, both from 1), e.g. S21.
///
/// Written `S21` (ports 1..9) or `S10,2` (any ports); `[sweeps] parameter` in the manifest.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
#[serde(try_from = "String", into = "String")]
pub struct SParam {
    /// Output (receiving) port, from 1.
    pub to_port: usize,
    /// Input (driven) port, from 1.
    pub from_port: usize,
}

impl SParam {
    /// S21: the transmission from port 1 to port 2 (the quasi-monostatic pair's default).
    pub const S21: SParam = SParam {
        to_port: 2,
        from_port: 1,
    };
    /// S11: the reflection at port 1 (a monostatic one-port).
    pub const S11: SParam = SParam {
        to_port: 1,
        from_port: 1,
    };

    /// The default for a file of `ports` ports: S11 for a one-port, S21 otherwise.
    pub fn default_for(ports: usize) -> SParam {
        if ports == 1 {
            SParam::S11
        } else {
            SParam::S21
        }
    }
}

impl std::fmt::Display for SParam {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        if self.to_port < 10 && self.from_port < 10 {
            write!(f, "S{}{}", self.to_port, self.from_port)
        } else {
            write!(f, "S{},{}", self.to_port, self.from_port)
        }
    }
}

impl std::str::FromStr for SParam {
    type Err = String;
    fn from_str(s: &str) -> std::result::Result<Self, String> {
        let bad = || format!("`{s}` is not an S-parameter (write e.g. S21, S11 or S10,2)");
        let rest = s
            .strip_prefix('S')
            .or_else(|| s.strip_prefix('s'))
            .ok_or_else(bad)?;
        let (i, j) = match rest.split_once(',') {
            Some((i, j)) => (i.trim().parse().ok(), j.trim().parse().ok()),
            None if rest.len() == 2 && rest.bytes().all(|b| b.is_ascii_digit()) => {
                (rest[..1].parse().ok(), rest[1..].parse().ok())
            }
            None => (None, None),
        };
        match (i, j) {
            (Some(i), Some(j)) if i >= 1 && j >= 1 => Ok(SParam {
                to_port: i,
                from_port: j,
            }),
            _ => Err(bad()),
        }
    }
}

impl TryFrom<String> for SParam {
    type Error = String;
    fn try_from(s: String) -> std::result::Result<Self, String> {
        s.parse()
    }
}

impl From<SParam> for String {
    fn from(p: SParam) -> String {
        p.to_string()
    }
}

/// A parsed network of any port count.
#[derive(Debug, Clone, PartialEq)]
pub struct Network {
    /// Number of ports n.
    pub ports: usize,
    /// Touchstone version of the file (1 or 2).
    pub version: u8,
    /// Frequencies, Hz, increasing.
    pub freq_hz: Vec<f64>,
    /// S matrices, row-major per point: `s[(k·n + i)·n + j]` = S_{i+1, j+1}(f_k).
    pub s: Vec<Complex64>,
    /// Reference impedance per point and port, ohm: `z0_ohm[k·n + i]`.
    pub z0_ohm: Vec<Complex64>,
    /// What was recognised and skipped (noise parameters), one sentence each.
    pub notes: Vec<String>,
}

impl Network {
    /// S_ij at point `k` (`i`, `j` from 0).
    pub fn get(&self, k: usize, i: usize, j: usize) -> Complex64 {
        self.s[(k * self.ports + i) * self.ports + j]
    }

    /// Check that `p` exists in this network; the error names `path` and the reason.
    pub fn check_param(&self, p: SParam, path: &Path) -> Result<()> {
        if p.to_port > self.ports || p.from_port > self.ports {
            let hint = if self.ports == 1 {
                " (a one-port file holds S11 only: set [sweeps] parameter = \"S11\")"
            } else {
                ""
            };
            return Err(Error::input(
                path,
                format!(
                    "parameter {p} does not exist in a {}-port file{hint}",
                    self.ports
                ),
            ));
        }
        Ok(())
    }

    /// Copy parameter `p` at every point into `out` (of `freq_hz.len()` values).
    pub fn param_into(&self, p: SParam, path: &Path, out: &mut [Complex64]) -> Result<()> {
        self.check_param(p, path)?;
        let n = self.ports;
        let off = (p.to_port - 1) * n + (p.from_port - 1);
        for (k, o) in out.iter_mut().enumerate().take(self.freq_hz.len()) {
            *o = self.s[k * n * n + off];
        }
        Ok(())
    }

    /// Parameter `p` at every point.
    pub fn param(&self, p: SParam, path: &Path) -> Result<Vec<Complex64>> {
        let mut out = vec![Complex64::new(0.0, 0.0); self.freq_hz.len()];
        self.param_into(p, path, &mut out)?;
        Ok(out)
    }
}

/// The text of a Touchstone file: UTF-8 without its byte-order mark, or Latin-1 when the
/// bytes are not UTF-8 (Latin-1 maps every byte to a character, so it never fails).
pub fn decode(bytes: &[u8]) -> Cow<'_, str> {
    let bytes = bytes.strip_prefix(b"\xEF\xBB\xBF").unwrap_or(bytes);
    match std::str::from_utf8(bytes) {
        Ok(s) => Cow::Borrowed(s),
        Err(_) => Cow::Owned(bytes.iter().map(|&b| b as char).collect()),
    }
}

/// Port count from a `.sNp` extension (any case), if the name has one.
pub fn ports_from_name(path: &Path) -> Option<usize> {
    let ext = path.extension()?.to_str()?.to_ascii_lowercase();
    let digits = ext.strip_prefix('s')?.strip_suffix('p')?;
    digits
        .parse()
        .ok()
        .filter(|&n| (1..=MAX_PORTS).contains(&n))
}

/// Most ports of a Touchstone network: a point holds 2·n² numbers, so the port count
/// bounds every buffer the reader sizes from it (a corrupt `[Number of Ports]` asked for
/// 3·10^17 bytes).
pub const MAX_PORTS: usize = 1000;

/// The largest |S| read (RI and MA values; 2000 dB in DB): an S-parameter is about 1 for
/// a passive network, and a larger value would make the energies (|S|² summed over a
/// sweep) overflow to inf, so it is refused naming the line.
pub const MAX_VALUE: f64 = 1e100;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sparam_names() {
        assert!("S2".parse::<SParam>().is_err() && "S0,1".parse::<SParam>().is_err());
        assert_eq!("s12".parse::<SParam>().unwrap().to_string(), "S12");
    }
}
