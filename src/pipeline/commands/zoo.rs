//! `pradar zoo`: write the scene zoo ([`crate::simulate::zoo`]) — every scene, its
//! noise-only twin and its second realisation, each a `campaign.toml` and `layout.geojson`
//! that `pradar simulate` takes — and `scenes.tsv`, one line per scene.

use crate::error::{Error, Result};
use crate::simulate::zoo;
use std::fmt;
use std::path::PathBuf;

/// `pradar zoo`: the generator's seed and scene count, and the output folder.
#[derive(Debug, Clone)]
pub struct Zoo {
    /// Output folder (`DIR/<name>/`, `DIR/<name>-twin/`, `DIR/<name>-r2/`, `DIR/scenes.tsv`).
    pub out: PathBuf,
    /// Generator seed.
    pub seed: u64,
    /// Number of scenes.
    pub count: usize,
}

/// What `zoo` wrote.
#[derive(Debug, Clone)]
pub struct ZooSummary {
    /// The scenes (name and one-line description).
    pub scenes: Vec<(String, String)>,
    /// The folder.
    pub out: PathBuf,
}

impl fmt::Display for ZooSummary {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (name, d) in &self.scenes {
            writeln!(f, "{name}: {d}")?;
        }
        write!(
            f,
            "{} scenes (with their -twin and -r2) -> {}",
            self.scenes.len(),
            self.out.display()
        )
    }
}

/// Run `pradar zoo`.
pub fn zoo(cmd: &Zoo) -> Result<ZooSummary> {
    if cmd.count == 0 {
        return Err(Error::param("--count", "must be >= 1"));
    }
    let scenes = zoo::generate(cmd.seed, cmd.count);
    zoo::write(&cmd.out, &scenes)?;
    Ok(ZooSummary {
        scenes: scenes
            .iter()
            .map(|s| (s.name.clone(), s.description.clone()))
            .collect(),
        out: cmd.out.clone(),
    })
}
