//! The statistical backscatter channel model (DESIGN §2 "Statistical channel model"):
//! `pradar synth`.
//!
//! Takes a model file ([`ModelConfig`](crate::model::file::ModelConfig), fitted by `fit` or written by hand), a campaign (layout,
//! trajectory, directions, band, array, noise, processing; no `[sweeps]` needed) and a seed;
//! gives an energy table in the energy-matrix schema (the same columns and metadata as
//! `pradar energy`, plus `source = synth`) and its ground truth (`rays.parquet`,
//! `clusters.csv`, same schemas as `simulate`'s `truth/`, and `model.toml`: the model as
//! read, written back unchanged).
//!
//! The model, drawn once per run from the seed (so every pose sees the same clusters):
//! * **clusters along the perimeter** ([`perimeter_walk`](crate::simulate::perimeter_walk), shared with the simulator's
//!   clutter): arc-length spacings ~ `perimeter_spacing` (d_c, its family), centroid offsets
//!   ~ `perimeter_offset` (d_p) into the room, capped at 1.5 m as the simulator's clutter
//!   (an exponential 0.4 m keeps a mean of 0.4·(1 − e^{−3.75}) = 0.391 m); Λ is not drawn
//!   — it follows from the geometry seen from each pose. A centre outside the free space
//!   is dropped;
//! * **rays per cluster**: 1 + Poisson(`rays_per_cluster` − 1); excess delays τ_k with
//!   exponential gaps of rate λ (`intra_cluster_rate`), τ_0 = 0; AoA offsets φ_k Laplacian
//!   with std `intra_cluster_aoa` (scale b = std/√2), φ_0 = 0 (the reference ray);
//!   pose-independent (a cluster is a fixed object);
//! * **where a cluster is**: the model's d_p is the offset of the cluster *centroid*, the
//!   point the fit measures (mean position of its MPCs); so seen from a pose at distance r,
//!   the first arrival is at range r − m, m = mean_k(c·τ_k/2) (the members' mean extra
//!   depth), and ray k arrives at T + τ_k, T = 2(r − m)/c, from θ + φ_k (θ the bearing of
//!   the centroid). A cluster is seen when the segment pose → centroid crosses no wall;
//! * **powers** (a Saleh–Valenzuela profile on top of the radar equation): at each pose
//!   let T_0 be the first arrival of the first visible cluster in the scanned half-plane.
//!   Ray k of cluster l, first arrival T_l at range r_l = c·T_l/2, has
//!   |A|² = σ_l · e^{−(T_l − T_0)/Γ} · e^{−τ_k/γ} / ((4π)³ r_l⁴), σ_l = `cluster_rrcs` ×
//!   log-normal shadowing (3 dB, as the simulator's clutter). So every cluster follows
//!   the radar equation at its own range (a single scatterer is `simulate`'s point
//!   target), Γ is the decay in excess of it (∞: none) and rays decay with γ — the slopes
//!   `fit` measures. A schema-1 model file keeps its meaning: every cluster at the first
//!   cluster's range d_0 = c·T_0/2, Γ the total decay ([`file`] module docs);
//! * **diffuse walls** (when the model has `[diffuse]`; [`diffuse`]): one point scatterer
//!   per range cell c/(2B) of every wall, uniform in its cell, complex Gaussian with
//!   E|x|² = `wall_rcs_per_m` × cell length and a uniform phase; seen from the free side
//!   through no wall with |A|² = |x|²·cos^n ψ / ((4π)³ d⁴) (the radar equation, absolute;
//!   n = `lambert_exponent`, ψ the incidence from the wall normal); their own ChaCha
//!   stream, so a model without `[diffuse]` gives the bytes it gave before; truth kind
//!   `diffuse`, cluster −1;
//! * **array**: each ray is seen through the campaign's array as
//!   a = ḡ(θ_arr)·|A|·e^{−j2πf_c(τ + τ_g)}, ḡ the window-weighted band average of |F|²λ
//!   (33 frequency knots) and τ_g the antenna group delay (slope of arg F² over the band,
//!   matters for the 1-bit transmitarray); mechanical or electronic steering as the campaign;
//! * **delay domain**: the windowed, zero-padded IFFT of a flat echo is
//!   e^{jπBt}·e^{−j2πf_cτ}·r(t − τ) with r the real window kernel (symmetric window),
//!   periodic in delay with the sweep's period T = 1/Δf (r(t + T) = (−1)^{K−1}·r(t) for K
//!   points: anti-periodic for an even K); so every ray, at any delay, adds coherently on
//!   the energy stage's oversampled grid through its images τ + kT that reach the span, at
//!   the level of its own path loss (an echo beyond c·T/2, 20 m for 801 points over 6 GHz,
//!   folds in as a measurement's does); r is tabulated at T_b/64 over ±16 bins
//!   ([`response`]);
//! * **the receiver**: per pulse, complex white Gaussian noise per frequency point (the
//!   `[noise]` floor, or the variance that reads the given N0) through the same window and
//!   zero-padded IFFT as `energy`, the rays' CIR added to it, the coupling gate applied and
//!   each bin's energy the mean of |h|² over its L samples, averaged over the N_p pulses:
//!   the measurement's own noise, coloured across neighbouring bins, with mean N0·TW +
//!   E_s and variance about (N0²·TW + 2·N0·E_s)/N_p per bin (DESIGN §2) ([`synth`](mod@synth)).
//!
//! Every draw comes from ChaCha streams keyed by the seed (the model) and by (seed,
//! position, direction) (the noise), so the bytes do not depend on the thread count.
//!
//! Layout: [`params`] (the run's options), [`channel`] (the drawn clusters and the rays a
//! pose sees), [`diffuse`] (the drawn wall points and the rays a pose sees), [`response`] (band-averaged pattern, periodic window kernel), [`synth`](mod@synth)
//! (the run: profiles, noise, truth and the energy table).

pub mod channel;
pub mod diffuse;
pub use pradar_formats::model_file as file;
pub mod levels;
pub mod params;
pub mod response;
pub mod synth;
pub mod walls;

pub use channel::{ChannelModel, ModelCluster, ModelRay, RaySource, SeenRay};
pub use diffuse::{DiffusePoint, DiffuseWalls};
pub use params::{SynthParams, SynthValid};
pub use response::BandPattern;
pub use synth::{
    default_truth_dir, synth, synth_channel, EnergySimulator, LayoutRays, SynthReport,
};
