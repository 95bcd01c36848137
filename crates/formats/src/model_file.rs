//! Model files (DESIGN §3 "Model"): the TOML schema shared by fitted models (`fit`) and the
//! simulator's ground truth (`[clutter]` in a campaign manifest).
//!
//! One table per quantity with `value`, `unit`, `family` and, when fitted, `interval`
//! (95 % bootstrap), `ks` (statistic), `ks_p` (parametric-bootstrap p-value) and `n`.
//! Quantities (units fixed by the schema):
//! * `inter_cluster_rate` Λ (1/ns) — informational in a model: the channel model derives it
//!   from the perimeter geometry;
//! * `intra_cluster_rate` λ (1/ns), exponential inter-arrival times;
//! * `intra_cluster_aoa` (deg), the standard deviation of the Laplacian AoA offsets
//!   (scale b = std/√2);
//! * `perimeter_offset` d_p (m), centroid distance from the closest wall;
//! * `perimeter_spacing` d_c (m), spacing of centroid projections along the perimeter;
//! * `cluster_decay` Γ (ns) and `ray_decay` γ (ns), power decay constants;
//! * `rays_per_cluster` (count, mean) and `cluster_rrcs` (m², mean σ of a cluster's first ray);
//! * `[diffuse]` (optional; [`DiffuseModel`]): the dense component, the walls' diffuse
//!   returns — `wall_rcs_per_m` (m²/m, backscatter σ per metre of wall at normal incidence),
//!   `lambert_exponent` (1, power ∝ cos^n of the incidence angle), `power_share` (1, the
//!   diffuse share of the extracted MPC power) and `decay` (ns, −10·log10(e)/slope of the
//!   diffuse MPCs' power against delay). `synth` draws walls from the first two; the other
//!   two describe the fitted data.
//! * `[walls]` (optional; [`WallModel`]): the layout's specular returns —
//!   `specular_gamma` (1, the magnitude |Γ| of the walls' reflection at normal incidence)
//!   and `[walls.material_gamma.<material>]` (1, the same for the walls of one layout
//!   material, where the data had enough of them; the others take `specular_gamma`),
//!   `corner_rcs` (m², σ of every concave corner of the perimeter, a dihedral) and
//!   `edge_rcs` (m², σ of every other ring vertex: door frames, pillar and cabinet edges). `synth` adds, per pose, the image-method
//!   return of every wall whose normal-incidence point it sees (`model::walls`). It
//!   follows from the layout (an input) once |Γ| is known, so a model with it is
//!   quasi-deterministic (geometry rays plus stochastic clusters).
//!
//! **Schema versions.** `schema_version = 2` (what this build writes, [`SCHEMA_VERSION`]):
//! * the cluster law puts every cluster at its own range: ray k of cluster l has
//!   |A|² = σ_l · e^{−(T_l − T_0)/Γ} · e^{−τ_k/γ} / ((4π)³ r_l⁴), r_l = c·T_l/2 the range of
//!   the cluster's first arrival and T_0 the pose's first visible cluster (`model::channel`),
//!   so `cluster_decay` Γ is the *excess* decay on top of the radar equation's r⁻⁴, and
//!   `value = inf` (no excess decay: the radar equation alone) is legal, as is an
//!   `interval` whose upper end is `inf`;
//! * a quantity the data cannot inform carries `not_estimable = "<reason>"` *and* a stated,
//!   drawable `value` ([`ModelConfig::with_stated_values`]: the paper's Table 1 where it
//!   gives one, the documented defaults elsewhere, Γ = ∞), so `synth`, `check`,
//!   `calibrate --prior` and the experiments accept every file `fit` writes as it is, and
//!   Table 1 says which values are stated rather than estimated.
//!
//! `schema_version = 1` (files written before) is read with its old meaning: every cluster
//! of a pose is anchored at the range d_0 of the pose's first visible cluster
//! (|A|² = σ_l · e^{−(T_l − T_0)/Γ} · e^{−τ_k/γ} / ((4π)³ d_0⁴), Γ the total decay, path
//! loss included, finite), and a not-estimable quantity has no `value` (read back as NaN):
//! [`ModelConfig::check`] accepts it, and [`ModelConfig::require_estimable`] — what `synth`
//! calls — refuses it, naming it, unless a value is supplied with `--set`.

use crate::campaign::manifest::{one_line, ArrayConfig, Band};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// The model schema version this build writes (older versions are read with their meaning:
/// module docs).
pub const SCHEMA_VERSION: u32 = 2;

/// The comment block every saved model file opens with: each quantity's meaning and
/// estimator (the module docs of `fit`, `model::levels` and `calibrate` have the equations).
pub const HEADER: &str = "\
# pradar channel model (DESIGN §3 \"Model\"; docs/model.md). Per quantity: value, unit,
# family, interval (95 %), ks, ks_p (parametric bootstrap), n (samples).
# From the clustered MPCs (`fit`): inter_cluster_rate Λ (1/ns, informational: synth derives
#   it from d_c), intra_cluster_rate λ (1/ns), intra_cluster_aoa (deg, Laplacian std of the
#   rays' angle offsets), perimeter_offset d_p (m), perimeter_spacing d_c (m), cluster_decay
#   Γ (ns, the excess decay of cluster power beyond each cluster's own r⁻⁴; inf = none) and
#   ray_decay γ (ns), rays_per_cluster (mean); [diffuse] lambert_exponent, power_share, decay.
# A quantity with not_estimable = \"<reason>\" was not informed by these data: its value is
#   a stated default that synth draws from (schema_version 2), not an estimate.
# Levels read from the energy table through the model's own forward response
#   (`fit --energy`, `reproduce`; model::levels): walls.specular_gamma and
#   walls.material_gamma.<material> (|Γ| at normal incidence: sqrt of the median ratio of the
#   measured peak at each seen wall foot to a unit-|Γ| echo there), walls.corner_rcs and
#   walls.edge_rcs (m², median excess over the walls at the seen layout vertices per unit-σ
#   response), diffuse.wall_rcs_per_m (m²/m, median on-wall cell / unit wall, / ln 2),
#   cluster_rrcs (m², first-ray σ at which synth's mean signal bins per profile equals the
#   table's). Without the table these are the cluster chain's CLEAN-peak values.
# [calibration], when present: the values are posterior medians of `pradar calibrate`.
";

fn nan() -> f64 {
    f64::NAN
}

fn is_nan(v: &f64) -> bool {
    v.is_nan()
}

/// The distribution families a model file may name.
pub const FAMILIES: [&str; 9] = [
    "exponential",
    "shifted_exponential",
    "laplacian",
    "gaussian",
    "lognormal",
    "gamma",
    "rayleigh",
    "poisson",
    "constant",
];

/// An `interval` of exactly two numbers (serde's fixed-size array reads the first two of
/// a longer list and ignores the rest).
fn two_bounds<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<[f64; 2]>, D::Error> {
    let v: Vec<f64> = serde::Deserialize::deserialize(d)?;
    match v[..] {
        [lo, hi] => Ok(Some([lo, hi])),
        _ => Err(serde::de::Error::custom(format!(
            "interval: {} bounds given, exactly 2 needed ([lo, hi])",
            v.len()
        ))),
    }
}

/// The fit's diagnostics of a quantity, when present: a finite, ordered interval, a KS
/// statistic and p-value in [0, 1].
fn check_diagnostics(name: &str, q: &Quantity, infinite_ok: bool) -> Result<()> {
    if let Some([lo, hi]) = q.interval {
        let hi_ok = hi.is_finite() || (infinite_ok && hi == f64::INFINITY);
        if !(lo.is_finite() && hi_ok && lo <= hi) {
            let what = if infinite_ok {
                "must be finite (the upper end may be inf) with lo <= hi"
            } else {
                "must be finite with lo <= hi"
            };
            return Err(Error::param(
                format!("{name}.interval"),
                format!("[{lo}, {hi}] {what}"),
            ));
        }
    }
    for (field, v) in [("ks", q.ks), ("ks_p", q.ks_p)] {
        if let Some(v) = v {
            if !(0.0..=1.0).contains(&v) {
                return Err(Error::param(
                    format!("{name}.{field}"),
                    format!("{v} outside [0, 1]"),
                ));
            }
        }
    }
    Ok(())
}

/// One modelled quantity.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Quantity {
    /// Estimate (or true value); when not estimable, the stated value drawn from (schema 2)
    /// or NaN (absent from the file; schema 1).
    #[serde(default = "nan", skip_serializing_if = "is_nan")]
    pub value: f64,
    /// Unit.
    pub unit: String,
    /// Distribution family, one of [`FAMILIES`] (`exponential`, `shifted_exponential`,
    /// `laplacian`, `gaussian`, `lognormal`, `gamma`, `rayleigh`, `poisson`, `constant`).
    pub family: String,
    /// 95 % bootstrap interval (exactly two bounds in the file: a third is refused, not
    /// dropped).
    #[serde(
        default,
        skip_serializing_if = "Option::is_none",
        deserialize_with = "two_bounds"
    )]
    pub interval: Option<[f64; 2]>,
    /// KS statistic.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ks: Option<f64>,
    /// KS parametric-bootstrap p-value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub ks_p: Option<f64>,
    /// Sample size.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub n: Option<usize>,
    /// Why the quantity could not be estimated (its value is then a stated default, or NaN
    /// in a schema-1 file).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub not_estimable: Option<String>,
}

impl Quantity {
    /// A bare value.
    pub fn new(value: f64, unit: &str, family: &str) -> Self {
        Quantity {
            value,
            unit: unit.into(),
            family: family.into(),
            interval: None,
            ks: None,
            ks_p: None,
            n: None,
            not_estimable: None,
        }
    }

    /// A quantity that could not be estimated, with the reason.
    pub fn not_estimable(unit: &str, family: &str, reason: impl Into<String>) -> Self {
        Quantity {
            value: f64::NAN,
            not_estimable: Some(reason.into()),
            ..Quantity::new(f64::NAN, unit, family)
        }
    }

    /// Whether the quantity was estimated (not flagged not estimable).
    pub fn is_estimable(&self) -> bool {
        self.not_estimable.is_none()
    }

    /// Whether a generator can draw from it: it has a value (estimated, or stated for a
    /// flagged quantity).
    pub fn is_drawable(&self) -> bool {
        !self.value.is_nan()
    }
}

/// The dense (diffuse) component of a channel model: the walls' diffuse returns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiffuseModel {
    /// Backscatter σ per metre of wall at normal incidence, m²/m.
    pub wall_rcs_per_m: Quantity,
    /// Lambertian exponent n: diffuse power ∝ cos^n(incidence).
    pub lambert_exponent: Quantity,
    /// Share of the extracted MPC power that is diffuse (informational).
    pub power_share: Quantity,
    /// Power decay of the diffuse MPCs against delay, ns (informational).
    pub decay: Quantity,
}

/// The layout's specular returns (image method) in a channel model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct WallModel {
    /// |Γ| at normal incidence (1) of every wall whose material has no entry of its own.
    pub specular_gamma: Quantity,
    /// |Γ| of the walls of one layout material (the GeoJSON's `properties.material`), by
    /// material name, where the table had enough of its walls to read it.
    #[serde(default, skip_serializing_if = "std::collections::BTreeMap::is_empty")]
    pub material_gamma: std::collections::BTreeMap<String, Quantity>,
    /// σ of the layout's concave perimeter corners (dihedrals), m².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub corner_rcs: Option<Quantity>,
    /// σ of every other ring vertex (convex edges: door frames, pillars, cabinets), m².
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub edge_rcs: Option<Quantity>,
}

impl WallModel {
    /// |Γ| of a wall of `material`.
    pub fn gamma(&self, material: &str) -> f64 {
        self.material_gamma
            .get(material)
            .map_or(self.specular_gamma.value, |q| q.value)
    }
}

/// Bin settings the model was fitted with.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BinSettings {
    /// Bin width, ns.
    pub bin_width_ns: f64,
    /// Window name.
    pub window: String,
}

/// A channel model (fitted, or the simulator's ground truth).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ModelConfig {
    /// Schema version: [`SCHEMA_VERSION`] (2), or 1 read with its old meaning (module docs).
    pub schema_version: u32,
    /// Array the data came from.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub array: Option<ArrayConfig>,
    /// Band.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub band: Option<Band>,
    /// Bin settings.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub bins: Option<BinSettings>,
    /// Λ, 1/ns.
    pub inter_cluster_rate: Quantity,
    /// λ, 1/ns.
    pub intra_cluster_rate: Quantity,
    /// AoA std, deg.
    pub intra_cluster_aoa: Quantity,
    /// d_p, m.
    pub perimeter_offset: Quantity,
    /// d_c, m.
    pub perimeter_spacing: Quantity,
    /// Γ, ns.
    pub cluster_decay: Quantity,
    /// γ, ns.
    pub ray_decay: Quantity,
    /// Rays per cluster (mean).
    pub rays_per_cluster: Quantity,
    /// Mean σ of a cluster's first ray, m².
    pub cluster_rrcs: Quantity,
    /// The dense (diffuse) component (absent: no walls are drawn).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub diffuse: Option<DiffuseModel>,
    /// The layout's specular returns (absent: none are drawn).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub walls: Option<WallModel>,
    /// How the values were obtained when not by the cluster fit (`pradar calibrate`
    /// writes it; absent in fitted and hand-written models, which read as before).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub calibration: Option<CalibrationMeta>,
    /// Legacy, read and dropped: the `[correction]` section that `fit` wrote while it ran
    /// Table 1's bias correction (indirect inference, removed; docs/correction.md). A user's
    /// old model file with it still loads (its values are read as any fitted values: they
    /// are the corrected ones, and its "not identifiable" quantities stay flagged); the
    /// section's content is not read, and nothing writes it (`Some` only for such a file).
    #[serde(default, rename = "correction", skip_serializing)]
    pub legacy_correction: Option<serde::de::IgnoredAny>,
}

/// `[calibration]` of a calibrated model: the method and its run. The quantities' `value`
/// is then the posterior median and `interval` the 95 % credible interval.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationMeta {
    /// Method, e.g. `abc-smc` (the calibrate module's docs give its equations).
    pub method: String,
    /// Simulations run.
    pub simulations: usize,
    /// Weighted particles in the final population.
    pub particles: usize,
    /// Generations (populations) run.
    pub generations: usize,
    /// Final tolerance ε (distance in MAD-scaled summary units).
    pub epsilon: f64,
    /// Seed of the run.
    pub seed: u64,
    /// The quantities inferred (the others were held at the prior file's value).
    pub free: Vec<String>,
}

impl ModelConfig {
    /// Defaults: Table 1 of the source paper where it gives a value (Λ 0.21/ns, λ 0.43/ns,
    /// AoA std 16.9°, perimeter distance 5.02 ns read one-way → d_c = 1.505 m), and stated
    /// choices elsewhere (d_p 0.3 m, Γ 12 ns of excess decay, γ 3 ns, 6 rays per cluster,
    /// σ 0.01 m²); schema [`SCHEMA_VERSION`]. The 12 ns was chosen as a total decay under
    /// schema 1 and kept as the excess decay (a stated choice: the paper gives no Γ; the
    /// physics simulator's clusters have none, Γ = ∞, the stated value of a fitted file).
    pub fn table1_defaults() -> Self {
        ModelConfig {
            schema_version: SCHEMA_VERSION,
            array: None,
            band: None,
            bins: None,
            inter_cluster_rate: Quantity::new(0.21, "1/ns", "exponential"),
            intra_cluster_rate: Quantity::new(0.43, "1/ns", "exponential"),
            intra_cluster_aoa: Quantity::new(16.9, "deg", "laplacian"),
            perimeter_offset: Quantity::new(0.3, "m", "exponential"),
            perimeter_spacing: Quantity::new(5.02e-9 * crate::units::C0, "m", "exponential"),
            cluster_decay: Quantity::new(12.0, "ns", "exponential"),
            ray_decay: Quantity::new(3.0, "ns", "exponential"),
            rays_per_cluster: Quantity::new(6.0, "count", "poisson"),
            cluster_rrcs: Quantity::new(0.01, "m2", "lognormal"),
            diffuse: None,
            walls: None,
            calibration: None,
            legacy_correction: None,
        }
    }

    /// Validate values, units and families; errors name the field. Besides being finite
    /// and positive, every value must lie in the range the schema gives its quantity
    /// (with its reason), and the family must be one of [`FAMILIES`].
    pub fn check(&self) -> Result<()> {
        if !(1..=SCHEMA_VERSION).contains(&self.schema_version) {
            return Err(Error::param(
                "schema_version",
                format!(
                    "unsupported {} (this build reads 1 to {SCHEMA_VERSION})",
                    self.schema_version
                ),
            ));
        }
        let v2 = self.schema_version >= 2;
        for (name, v, unit) in self.quantities() {
            if v.unit != unit {
                return Err(Error::param(
                    format!("{name}.unit"),
                    format!("`{}` (expected `{unit}`)", v.unit),
                ));
            }
            if !FAMILIES.contains(&v.family.as_str()) {
                return Err(Error::param(
                    format!("{name}.family"),
                    format!(
                        "unknown family `{}` (one of {})",
                        v.family,
                        FAMILIES.join(", ")
                    ),
                ));
            }
            // the excess cluster decay of schema 2 may be infinite (no excess decay)
            let infinite_ok = v2 && name == "cluster_decay";
            check_diagnostics(name, v, infinite_ok)?;
            if let Some(reason) = &v.not_estimable {
                if v.value.is_nan() {
                    continue;
                }
                if !v2 {
                    return Err(Error::param(
                        format!("{name}.value"),
                        format!("given although marked not estimable ({reason})"),
                    ));
                }
            }
            if infinite_ok && v.value == f64::INFINITY {
                continue;
            }
            if name == "diffuse.lambert_exponent" {
                if !(v.value.is_finite() && v.value >= 0.0) {
                    return Err(Error::param(
                        format!("{name}.value"),
                        "must be finite and >= 0",
                    ));
                }
                continue;
            }
            if name == "diffuse.power_share" && !(v.value > 0.0 && v.value <= 1.0) {
                return Err(Error::param(format!("{name}.value"), "must be in (0, 1]"));
            }
            if !(v.value.is_finite() && v.value > 0.0) {
                return Err(Error::param(
                    format!("{name}.value"),
                    "must be finite and > 0",
                ));
            }
            if let Some((lo, hi, why)) = Self::bounds(name) {
                if !(v.value >= lo && v.value <= hi) {
                    return Err(Error::param(
                        format!("{name}.value"),
                        format!(
                            "{} {} outside [{lo:e}, {hi:e}] ({why})",
                            crate::error::short(v.value),
                            v.unit
                        ),
                    ));
                }
            }
        }
        if let Some(w) = &self.walls {
            for (mat, q) in &w.material_gamma {
                let name = format!("walls.material_gamma.{mat}");
                if q.unit != "1" {
                    return Err(Error::param(
                        format!("{name}.unit"),
                        format!("`{}` (expected `1`)", q.unit),
                    ));
                }
                check_diagnostics(&name, q, false)?;
                if !(q.value > 0.0 && q.value <= 1.0) {
                    return Err(Error::param(format!("{name}.value"), "must be in (0, 1]"));
                }
            }
        }
        if self.rays_per_cluster.value < 1.0 {
            return Err(Error::param("rays_per_cluster.value", "must be >= 1"));
        }
        Ok(())
    }

    /// The range a quantity's value must lie in, with the reason: far beyond any indoor
    /// channel, and what keeps the generators' sizes and sums finite (rays are drawn per
    /// cluster, clusters per perimeter spacing, energies scale with the RRCS).
    fn bounds(name: &str) -> Option<(f64, f64, &'static str)> {
        Some(match name {
            "inter_cluster_rate" | "intra_cluster_rate" => {
                (0.0, 100.0, "one arrival per 10 ps is far below the delay resolution")
            }
            "intra_cluster_aoa" => (0.0, 180.0, "an angle spread of at most half a turn"),
            "perimeter_offset" => (0.0, 100.0, "clusters within 100 m of a wall"),
            "perimeter_spacing" => (
                0.01,
                1e4,
                "at least 1 cm between clusters: the number of clusters drawn is perimeter / spacing",
            ),
            "cluster_decay" | "ray_decay" | "diffuse.decay" => {
                (0.0, 1e4, "a power decay within 10 µs")
            }
            "rays_per_cluster" => (1.0, 1000.0, "rays are drawn one by one for every cluster"),
            "cluster_rrcs" => (
                0.0,
                1e6,
                "above a 1 m² plate at normal incidence at 60 GHz, 5e5 m²; larger values overflow the energies",
            ),
            "diffuse.wall_rcs_per_m" => (0.0, 1e3, "a wall's diffuse return per metre"),
            "diffuse.lambert_exponent" => (0.0, 100.0, "cos^n of the incidence angle"),
            "walls.specular_gamma" => (0.0, 1.0, "a passive wall reflects at most all of the power"),
            "walls.corner_rcs" | "walls.edge_rcs" => (0.0, 1e6, "as cluster_rrcs"),
            _ => return None,
        })
    }

    /// The quantities marked not estimable, by name (`diffuse.` prefix for the dense
    /// component's).
    pub fn not_estimable(&self) -> Vec<(String, String)> {
        let mut out: Vec<(String, String)> = self
            .quantities()
            .into_iter()
            .filter_map(|(n, q, _)| q.not_estimable.clone().map(|r| (n.to_string(), r)))
            .collect();
        out.sort();
        out
    }

    /// Every quantity by its file name (`diffuse.` prefix for the dense component's), with
    /// the unit the schema fixes for it.
    fn quantities(&self) -> Vec<(&'static str, &Quantity, &'static str)> {
        let mut v = vec![
            ("inter_cluster_rate", &self.inter_cluster_rate, "1/ns"),
            ("intra_cluster_rate", &self.intra_cluster_rate, "1/ns"),
            ("intra_cluster_aoa", &self.intra_cluster_aoa, "deg"),
            ("perimeter_offset", &self.perimeter_offset, "m"),
            ("perimeter_spacing", &self.perimeter_spacing, "m"),
            ("cluster_decay", &self.cluster_decay, "ns"),
            ("ray_decay", &self.ray_decay, "ns"),
            ("rays_per_cluster", &self.rays_per_cluster, "count"),
            ("cluster_rrcs", &self.cluster_rrcs, "m2"),
        ];
        if let Some(d) = &self.diffuse {
            v.extend([
                ("diffuse.wall_rcs_per_m", &d.wall_rcs_per_m, "m2/m"),
                ("diffuse.lambert_exponent", &d.lambert_exponent, "1"),
                ("diffuse.power_share", &d.power_share, "1"),
                ("diffuse.decay", &d.decay, "ns"),
            ]);
        }
        if let Some(w) = &self.walls {
            v.push(("walls.specular_gamma", &w.specular_gamma, "1"));
            if let Some(q) = &w.corner_rcs {
                v.push(("walls.corner_rcs", q, "m2"));
            }
            if let Some(q) = &w.edge_rcs {
                v.push(("walls.edge_rcs", q, "m2"));
            }
        }
        v
    }

    /// The model with the values `supplied` (name → value, names as in the file; a supplied
    /// quantity is no longer flagged); an error naming the first quantity left without a
    /// value (a not-estimable one of a schema-1 file). What a generator (`synth`) calls
    /// before drawing; a schema-2 file's flagged quantities carry their stated values.
    pub fn require_estimable(
        &self,
        supplied: &std::collections::BTreeMap<String, f64>,
    ) -> Result<ModelConfig> {
        let mut m = self.clone();
        for (name, v) in supplied {
            let q = m.quantity_mut(name).ok_or_else(|| {
                Error::param(format!("--set {name}"), "no such quantity in the model")
            })?;
            q.value = *v;
            q.not_estimable = None;
        }
        let undrawable = m
            .quantities()
            .into_iter()
            .find(|(_, q, _)| !q.is_drawable())
            .map(|(n, q, _)| (n.to_string(), q.not_estimable.clone().unwrap_or_default()));
        if let Some((name, reason)) = undrawable {
            return Err(Error::param(
                name.clone(),
                format!(
                    "not estimable in the model ({reason}); supply a value with --set {name}=VALUE"
                ),
            ));
        }
        m.check()?;
        Ok(m)
    }

    /// The value a schema-2 file states for quantity `name` when the data cannot inform
    /// it (module docs): the paper's Table 1 where it gives one (λ 0.43/ns, AoA 16.9°,
    /// d_c 1.505 m, Λ 0.21/ns), Γ = ∞ (no excess decay: the radar equation alone), the
    /// documented defaults elsewhere ([`ModelConfig::table1_defaults`]: d_p 0.3 m, γ 3 ns,
    /// 6 rays, σ 0.01 m²; the diffuse walls' σ′ 0.05 m²/m, n 1, share 0.5, decay 10 ns;
    /// |Γ| 0.4, about concrete's at normal incidence at 60 GHz; corners and edges σ 0.1 m²).
    pub fn stated_value(name: &str) -> Option<f64> {
        let d = ModelConfig::table1_defaults();
        Some(match name {
            "cluster_decay" => f64::INFINITY,
            "diffuse.wall_rcs_per_m" => 0.05,
            "diffuse.lambert_exponent" => 1.0,
            "diffuse.power_share" => 0.5,
            "diffuse.decay" => 10.0,
            "walls.specular_gamma" => 0.4,
            "walls.corner_rcs" | "walls.edge_rcs" => 0.1,
            _ => d.quantity(name)?.value,
        })
    }

    /// A schema-2 model with every quantity flagged not estimable and without a value given
    /// its [`stated value`](Self::stated_value) (the flag and reason stay); a schema-1
    /// model is returned as it is (its flagged quantities have no value). What `fit` and
    /// the level fit return.
    pub fn with_stated_values(mut self) -> ModelConfig {
        if self.schema_version < 2 {
            return self;
        }
        let names: Vec<String> = self
            .quantities()
            .into_iter()
            .filter(|(_, q, _)| !q.is_drawable())
            .map(|(n, _, _)| n.to_string())
            .collect();
        for name in names {
            if let (Some(v), Some(q)) = (Self::stated_value(&name), self.quantity_mut(&name)) {
                q.value = v;
            }
        }
        self
    }

    /// The quantity called `name` (as in the file; `diffuse.` prefix for the dense
    /// component's).
    pub fn quantity(&self, name: &str) -> Option<&Quantity> {
        self.quantities()
            .into_iter()
            .find(|q| q.0 == name)
            .map(|q| q.1)
    }

    /// The quantity called `name` (as in the file), mutably.
    pub fn quantity_mut(&mut self, name: &str) -> Option<&mut Quantity> {
        Some(match name {
            "inter_cluster_rate" => &mut self.inter_cluster_rate,
            "intra_cluster_rate" => &mut self.intra_cluster_rate,
            "intra_cluster_aoa" => &mut self.intra_cluster_aoa,
            "perimeter_offset" => &mut self.perimeter_offset,
            "perimeter_spacing" => &mut self.perimeter_spacing,
            "cluster_decay" => &mut self.cluster_decay,
            "ray_decay" => &mut self.ray_decay,
            "rays_per_cluster" => &mut self.rays_per_cluster,
            "cluster_rrcs" => &mut self.cluster_rrcs,
            "walls.specular_gamma" => &mut self.walls.as_mut()?.specular_gamma,
            "walls.corner_rcs" => self.walls.as_mut()?.corner_rcs.as_mut()?,
            "walls.edge_rcs" => self.walls.as_mut()?.edge_rcs.as_mut()?,
            _ => {
                let d = self.diffuse.as_mut()?;
                match name {
                    "diffuse.wall_rcs_per_m" => &mut d.wall_rcs_per_m,
                    "diffuse.lambert_exponent" => &mut d.lambert_exponent,
                    "diffuse.power_share" => &mut d.power_share,
                    "diffuse.decay" => &mut d.decay,
                    _ => return None,
                }
            }
        })
    }

    /// Parse a model from a TOML value (e.g. a manifest's `[clutter]`).
    pub fn from_value(v: toml::Value, file: &Path, prefix: &str) -> Result<Self> {
        let m: ModelConfig = v.try_into().map_err(|e: toml::de::Error| {
            Error::input(file, format!("[{prefix}]: {}", one_line(&e.to_string())))
        })?;
        m.require_estimable(&Default::default())
            .map_err(|e| Error::input(file, format!("[{prefix}] {e}")))
    }

    /// Read a model file.
    pub fn load(path: &Path) -> Result<Self> {
        Self::from_str(&crate::io::read_text(path)?, path)
    }

    /// Parse and check model-file text that notionally lives at `path`.
    pub fn from_str(text: &str, path: &Path) -> Result<Self> {
        let m: ModelConfig =
            toml::from_str(text).map_err(|e| Error::input(path, one_line(&e.to_string())))?;
        m.check().map_err(|e| Error::input(path, e.to_string()))?;
        Ok(m)
    }

    /// Write a model file atomically, after a comment block ([`HEADER`]) stating what each
    /// quantity means and how it was estimated.
    pub fn save(&self, path: &Path) -> Result<()> {
        let text = toml::to_string(self).map_err(|e| Error::input(path, e.to_string()))?;
        crate::io::write_bytes(path, format!("{HEADER}{text}").as_bytes())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trip_and_validation() {
        let m = ModelConfig::table1_defaults();
        let text = toml::to_string(&m).unwrap();
        let back: ModelConfig = toml::from_str(&text).unwrap();
        assert_eq!(m, back);
        let mut bad = m.clone();
        bad.ray_decay.unit = "s".into();
        assert!(bad
            .check()
            .unwrap_err()
            .to_string()
            .contains("ray_decay.unit"));
        assert!((m.perimeter_spacing.value - 1.505).abs() < 1e-3);
    }

    #[test]
    fn schema_2_files_carry_stated_values_and_an_infinite_excess_decay() {
        let mut m = ModelConfig::table1_defaults();
        assert_eq!(m.schema_version, SCHEMA_VERSION);
        m.cluster_decay = Quantity {
            interval: Some([40.0, f64::INFINITY]),
            ..Quantity::new(f64::INFINITY, "ns", "exponential")
        };
        m.intra_cluster_aoa = Quantity::not_estimable("deg", "laplacian", "single-ray clusters");
        m.diffuse = Some(DiffuseModel {
            wall_rcs_per_m: Quantity::new(0.1, "m2/m", "constant"),
            lambert_exponent: Quantity::not_estimable("1", "constant", "no diffuse rows"),
            power_share: Quantity::new(0.5, "1", "constant"),
            decay: Quantity::new(10.0, "ns", "exponential"),
        });
        let m = m.with_stated_values();
        assert_eq!(m.intra_cluster_aoa.value, 16.9);
        assert_eq!(m.diffuse.as_ref().unwrap().lambert_exponent.value, 1.0);
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("v2.toml");
        m.save(&p).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(
            text.contains("value = inf") && text.contains("interval = [40.0, inf]"),
            "{text}"
        );
        let back = ModelConfig::load(&p).unwrap();
        assert_eq!(back, m);
        // drawable as it is: flagged, with the value synth draws
        let drawn = back.require_estimable(&Default::default()).unwrap();
        assert!(!drawn.intra_cluster_aoa.is_estimable());
        assert_eq!(drawn.intra_cluster_aoa.value, 16.9);
        // schema 1 keeps its meaning: no infinite decay, no value beside the flag
        let mut v1 = back.clone();
        v1.schema_version = 1;
        let e = v1.check().unwrap_err().to_string();
        assert!(
            e.contains("intra_cluster_aoa.value") && e.contains("not estimable"),
            "{e}"
        );
        v1.intra_cluster_aoa = Quantity::new(16.9, "deg", "laplacian");
        v1.diffuse = None;
        let e = v1.check().unwrap_err().to_string();
        assert!(e.contains("cluster_decay.interval"), "{e}");
        v1.cluster_decay.interval = None;
        let e = v1.check().unwrap_err().to_string();
        assert!(e.contains("cluster_decay.value"), "{e}");
        // an infinite value of another quantity is refused in either schema
        let mut bad = back;
        bad.ray_decay.value = f64::INFINITY;
        assert!(bad
            .check()
            .unwrap_err()
            .to_string()
            .contains("ray_decay.value"));
        let mut v3 = ModelConfig::table1_defaults();
        v3.schema_version = 3;
        assert!(v3
            .check()
            .unwrap_err()
            .to_string()
            .contains("schema_version"));
    }

    #[test]
    fn not_estimable_round_trip_and_gate() {
        // a schema-1 file: a flagged quantity has no value
        let mut m = ModelConfig::table1_defaults();
        m.schema_version = 1;
        let reason = "no inter-cluster gaps (fewer than 2 clusters at every position)";
        m.inter_cluster_rate = Quantity {
            n: Some(0),
            ..Quantity::not_estimable("1/ns", "exponential", reason)
        };
        m.check().unwrap();
        let dir = tempfile::tempdir().unwrap();
        let p = dir.path().join("partial.toml");
        m.save(&p).unwrap();
        let text = std::fs::read_to_string(&p).unwrap();
        assert!(
            text.contains(&format!("not_estimable = \"{reason}\"")),
            "{text}"
        );
        assert!(!text.to_lowercase().contains("nan"), "{text}");
        let back = ModelConfig::load(&p).unwrap();
        let q = &back.inter_cluster_rate;
        assert!(q.value.is_nan() && !q.is_estimable());
        assert_eq!(q.not_estimable.as_deref(), Some(reason));
        assert_eq!((q.unit.as_str(), q.n), ("1/ns", Some(0)));
        assert_eq!(
            back.not_estimable(),
            vec![("inter_cluster_rate".to_string(), reason.to_string())]
        );
        // the rest is unchanged, and saving again writes the same file
        assert_eq!(back.intra_cluster_rate, m.intra_cluster_rate);
        let again = dir.path().join("again.toml");
        back.save(&again).unwrap();
        assert_eq!(text, std::fs::read_to_string(&again).unwrap());
        // the generators' gate names the quantity and says how to supply it
        let e = back
            .require_estimable(&Default::default())
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("inter_cluster_rate")
                && e.contains(reason)
                && e.contains("--set inter_cluster_rate=VALUE"),
            "{e}"
        );
        let supplied = [("inter_cluster_rate".to_string(), 0.3)].into();
        let filled = back.require_estimable(&supplied).unwrap();
        assert_eq!(filled.inter_cluster_rate.value, 0.3);
        assert!(filled.not_estimable().is_empty());
        // a value beside the mark is refused
        let mut both = back.clone();
        both.inter_cluster_rate.value = 0.2;
        assert!(both
            .check()
            .unwrap_err()
            .to_string()
            .contains("inter_cluster_rate.value"));
    }
}
