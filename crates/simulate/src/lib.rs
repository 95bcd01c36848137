//! Physics-based campaign simulator (DESIGN §1, §2 "Scattering"): writes sweeps in the same
//! formats a VNA campaign would, plus its ground truth.
//!
//! Takes a manifest with the simulator-only `[scene]` ([`SceneConfig`], checked once into a
//! [`SceneValid`]) and `[clutter]` (model schema) sections and a layout; gives
//! `DIR/campaign.toml` (with `[sweeps]`), the sweeps (Touchstone or Parquet) and
//! `DIR/truth/` (`scatterers.csv`, `clusters.csv`, `rays.parquet`: every path seen from every
//! position with its delay, angle and power).
//!
//! S21(f) for one (position, direction, pulse) is the coherent sum over paths
//! S21 = Σ F(θ_p, f)² · λ(f) · A_p · e^{−j2πf τ_p} + coupling + noise, with F the complex
//! one-way field of [`ArrayPattern`] (|F|² = gain; Tx and Rx identical, side by side),
//! evaluated at every frequency point (`pattern_knots = 0`, the default) or tabulated at
//! `pattern_knots` frequencies and interpolated linearly (faster, but the interpolation error
//! is periodic in frequency and shows as weak echo replicas at ±1/knot-spacing):
//! * point scatterer at range d with complex RRCS x (|x|² = σ): A = x / ((4π)^{3/2} d²),
//!   τ = 2d/c — the radar equation in amplitude;
//! * diffuse walls: σ per metre of wall spread over `scatterers_per_cell` (≥ 10) random
//!   off-grid scatterers per range cell (c/2B of wall length), complex Gaussian x, with a
//!   Lambertian factor √cos(incidence);
//! * specular walls (image method, monostatic: the normal-incidence point):
//!   A = Γ / (4π · 2d), Γ = (1 − √εr)/(1 + √εr) (Fresnel, normal incidence, εr complex);
//! * corners (dihedral, concave seen from the room), edges (convex: door frames, pillar and
//!   cabinet edges) as strong point scatterers;
//! * perimeter clutter clusters drawn from `[clutter]`: centres at arc-length spacing
//!   ~ family(d_c) along the perimeter, offset ~ family(d_p) into the room; rays with
//!   exponential excess delays (rate λ) and Laplacian angular offsets (std from the model,
//!   at a nominal 2 m viewing distance) as virtual scatterers behind the centre (multi-bounce
//!   paths appear beyond the wall), σ_ray = σ_c · e^{−τ/γ};
//! * optional `[[scene.targets]]` point targets; `walls = false` drops the layout's walls,
//!   corners and clutter (point-target scenes);
//! * Tx→Rx coupling: a −`coupling_db` term at `coupling_delay_ns` with a 2 GHz ripple (replicas at ±0.5 ns);
//! * complex white noise of variance floor/tx power per point, independent per pulse.
//!
//! Occlusion: a path is dropped when the segment from the pose to the scatterer crosses a
//! wall. Every random draw comes from the manifest seed: the scene from one ChaCha stream,
//! the noise of each sweep from its own stream keyed by (position, direction, pulse), so the
//! bytes do not depend on the thread count. The energy/mapping models know none of the
//! specular, Lambertian, clutter-geometry or coupling details (no inverse crime).
//!
//! Layout: [`scene`] (`[scene]` parameters and the scatterers), [`draws`] (random draws
//! shared with [`crate::model`]), [`paths`] (paths seen from a pose), [`synth`] (S21
//! synthesis and noise; `binned`, the same sum regrouped by pattern-table cell, which it uses
//! for mechanical steering with the pattern at every point), [`truth`] (ground-truth tables) and `output` (sweep writer and the
//! output manifest); [`simulate`] runs them in that order. [`zoo`] generates scenes for it
//! (the scene zoo, `pradar zoo`).
#![deny(missing_docs)]

// the lower layers' modules under their old paths (`crate::campaign::…`)
use pradar_formats::{campaign, error, io, model_file, params, table, units};
use pradar_radar::pattern;

mod binned;
pub mod draws;
mod output;
pub mod paths;
pub mod scene;
pub mod synth;
pub mod truth;
pub mod zoo;

pub use draws::{draw_rays, draw_shadowed, laplace, perimeter_walk};
pub use paths::Path1;
pub use scene::{
    Material, PointTarget, Scatterer, ScattererKind, Scene, SceneConfig, SceneValid, TruthCluster,
};
pub use synth::synth_sweep;
pub use truth::{truth_rays_frame, write_truth_clusters, write_truth_scatterers, TruthRay};

use crate::campaign::layout::Layout;
use crate::campaign::manifest::{one_line, Campaign, SweepFormat, C0};
use crate::campaign::sweeps::PositionSweeps;
use crate::error::{Error, Result};
use crate::model_file::ModelConfig;
use crate::params::ParamGuard;
use crate::pattern::ArrayPattern;
use geo::Coord;
use std::path::{Path, PathBuf};

/// What `simulate` produced.
#[derive(Debug, Clone)]
pub struct SimReport {
    /// Sweeps written.
    pub sweeps: usize,
    /// Scatterers in the scene.
    pub scatterers: usize,
    /// Clutter clusters.
    pub clusters: usize,
    /// Path of the written manifest.
    pub manifest: PathBuf,
}

/// Whether the manifest has a `[scene]` section (a simulated campaign; `simulate` copies it
/// into the manifest it writes), read from its text as [`scene_sections`] reads it.
pub fn has_scene(c: &Campaign) -> Result<bool> {
    let text = crate::io::read_text(&c.path)?;
    let t: toml::Table =
        toml::from_str(&text).map_err(|e| Error::input(&c.path, one_line(&e.to_string())))?;
    Ok(t.contains_key("scene"))
}

/// Write campaign `c` as it is loaded (its changed seed, pulses, band, array, directions
/// and noise over its manifest's text, no `[sweeps]`) into `out_dir/campaign.toml` with
/// its layout beside it; returns the manifest's path (`explore` maps `synth` data with it).
pub fn write_campaign(c: &Campaign, out_dir: &Path) -> Result<PathBuf> {
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, e))?;
    output::write_manifest(c, out_dir, None)
}

/// Read `[scene]` (checked) and `[clutter]` from the manifest text (simulator only).
pub fn scene_sections(c: &Campaign) -> Result<(SceneValid, Option<ModelConfig>)> {
    let text = crate::io::read_text(&c.path)?;
    let t: toml::Table =
        toml::from_str(&text).map_err(|e| Error::input(&c.path, one_line(&e.to_string())))?;
    let scene_v = t
        .get("scene")
        .cloned()
        .ok_or_else(|| Error::input(&c.path, "simulate needs a [scene] section"))?;
    let scene: SceneConfig = scene_v.try_into().map_err(|e: toml::de::Error| {
        Error::input(&c.path, format!("[scene]: {}", one_line(&e.to_string())))
    })?;
    let scene = scene
        .check()
        .map_err(|e| Error::input(&c.path, e.to_string()))?;
    let clutter = match t.get("clutter") {
        Some(v) => Some(ModelConfig::from_value(v.clone(), &c.path, "clutter")?),
        None => None,
    };
    Ok((scene, clutter))
}

/// Run the simulator: write the campaign into `out_dir`. `progress` is called after each
/// position with (done, total).
///
/// Steps: read and check `[scene]`/`[clutter]`, build the [`Scene`], tabulate the array
/// pattern per direction, then per position synthesise the sweeps ([`synth`]) and their
/// truth rays ([`truth`]); finally the truth tables and the output manifest.
///
/// ```no_run
/// use pradar_formats::campaign::manifest::SweepFormat;
/// use pradar_simulate::simulate;
/// use pradar_formats::campaign::Campaign;
/// use std::path::Path;
///
/// let c = Campaign::load(Path::new("data/corridor/campaign.toml"))?;
/// let r = simulate(&c, Path::new("/tmp/sim"), SweepFormat::Parquet, &|_, _| {})?;
/// println!("{} sweeps, manifest {}", r.sweeps, r.manifest.display());
/// # Ok::<(), pradar_formats::error::Error>(())
/// ```
pub fn simulate(
    c: &Campaign,
    out_dir: &Path,
    format: SweepFormat,
    progress: &dyn Fn(usize, usize),
) -> Result<SimReport> {
    let m = &c.manifest;
    let (scene_cfg, clutter) = scene_sections(c)?;
    let layout = Layout::load(&c.layout_path())?;
    let knots = if scene_cfg.pattern_knots == 0 {
        m.band.points
    } else {
        scene_cfg.pattern_knots
    };
    let scene = Scene::build(
        layout,
        scene_cfg.clone(),
        clutter.as_ref(),
        m.band.bandwidth_hz(),
        m.seed,
    );
    let pattern = ArrayPattern::new(m.array, m.band.center_hz())?;
    let angles = m.directions.angles_deg();
    let tables = || pattern.tables(&angles, &m.band, knots);
    let synth = synth::SweepSynth::new(m, &scene_cfg, knots, &tables, angles.clone());
    let nd = synth.directions();
    let (np, nk, nf) = (m.positions(), m.pulses, m.band.points);
    std::fs::create_dir_all(out_dir).map_err(|e| Error::io(out_dir, e))?;
    let truth_dir = out_dir.join("truth");
    std::fs::create_dir_all(&truth_dir).map_err(|e| Error::io(&truth_dir, e))?;
    let mut sweeps = output::SweepSink::create(out_dir, format)?;
    let rays_path = truth_dir.join("rays.parquet");
    let mut rays = table::ParquetStream::create(&rays_path)?;
    let g0 = pattern.gain(0.0, 0.0, m.band.center_hz());
    let lc = C0 / m.band.center_hz();
    let ids = truth::TruthIds::of(&scene);
    for p in 0..np {
        let pose = m.poses[p];
        let at = Coord {
            x: pose.x_m,
            y: pose.y_m,
        };
        let paths = scene.paths(at);
        let sw = PositionSweeps {
            position: p,
            directions: nd,
            pulses: nk,
            points: nf,
            s21: synth.position(p, pose.heading_deg.to_radians(), &paths),
            missing: vec![],
        };
        sweeps.write(&m.band, &sw, &m.name)?;
        let rows = truth::truth_rays(&scene, &ids, &paths, g0, lc);
        rays.write(&truth_rays_frame(&rays_path, p, pose.heading_deg, &rows)?)?;
        progress(p + 1, np);
    }
    sweeps.finish()?;
    rays.finish(None)?;
    write_truth_scatterers(&truth_dir, &scene.scatterers)?;
    write_truth_clusters(&truth_dir, &scene.clusters)?;
    let manifest = output::write_manifest(c, out_dir, Some(format))?;
    Ok(SimReport {
        sweeps: np * nd * nk,
        scatterers: scene.scatterers.len(),
        clusters: scene.clusters.len(),
        manifest,
    })
}
