//! EKF mapper over the root radar cross section (DESIGN §2 "Mapping").
//!
//! Takes an [`ObservationModel`](crate::grid::ObservationModel), a run's [`EnergyMatrix`](crate::energy::EnergyMatrix) (profiles and `n0`, `tw`,
//! `pulses` metadata), the run's window kernel and [`EkfParams`]; gives per cell the
//! posterior mean of the RRCS x_i (m), its standard deviation, a soft map
//! p_i = P(x_i > μ0 | data) and a binary map ([`EkfMap`]) after the arc explanation (below).
//!
//! State and prior: x_i = RRCS of cell i (x = √σ), independent Gaussian prior N(μ0, σ0²),
//! μ0 > 0 because the Jacobian 2·c·x vanishes at x = 0 (a cell started at 0 would never be
//! updated). Defaults μ0 = 0.01 m (σ = 1e-4 m², −40 dBsm: a weak cell, about a tenth of the
//! RRCS of a 0.1 m stretch of diffuse wall) and σ0 = 0.1 m (a wall cell, x ≈ 0.05, lies
//! within one σ0 and a corner, x ≈ 0.7, within 7 σ0).
//!
//! Observation of (pose, direction): the energy vector over the usable bins k ≥ `min_bin`
//! that have at least one illuminated cell (main and side lobes down to the observation
//! model's floor; soft input), truncated after the occluder (the strongest echo, or an
//! earlier one on a mapped surface): with the run's
//! [`Sight`] (the OG's detector and [`crate::grid::visibility`]), only the bins up
//! to the beam's occluder plus the guard g are observed, so late energy (multipath, echoes
//! from behind the wall) is never explained by RRCS behind the surface; the rows within
//! the kernel's half-width of a detection before the occluder (weaker, or explained by a
//! side lobe: leakage of an echo at another bearing, withheld by the OG too; every
//! detection of a beam without an occluder) are dropped, except the occluder's own; and only the cells visible
//! from the pose (depth behind the visibility polygon ≤ g) enter H — a shadowed cell's
//! coefficient is 0 (a direction without an occluder leaves the polygon at the maximum
//! range). The occluders are confirmed against the filter's own binary map
//! before the previous pose. The cost of removing shadowed cells (measured,
//! `docs/mapping.md`): a wall's bin is explained by the in-room part of its range ring
//! only, so more room cells rise above μ0 than when the cells behind share it; keeping them
//! instead fills the space behind the walls on model data. Prediction
//!   h_k(x) = Σ_i c̃_{k,i}·x_i² + N0·TW,
//!   c̃_{k,i} = Σ_m c_{m,i}·K(k − m),
//! c_{m,i} the observation model's radar-equation coefficient of cell i in bin m (share of its
//! sub-samples whose delay rounds to bin m) and K(j) the bin-averaged energy of a unit point
//! echo at the centre of a bin, j bins away ([`crate::job::window_kernel`], the
//! simulator's and `energy`'s own window, IFFT and bin integration), kept for |j| ≤ J where
//! K(j) ≥ `kernel_floor_db` relative to K(0) (−30 dB: the Hann kernel's main lobe). So a point
//! target of RRCS x at the centre of bin m predicts exactly `point_echo_energy(c·x², τ_m)`,
//! which is what `energy` computes from a simulated point echo (checked in the tests).
//! Jacobian H_{k,i} = 2·c̃_{k,i}·x_i over every illuminated cell. Measurement noise R
//! diagonal from the energy-detector statistics of a bin averaged over N_p pulses
//! (`energy`'s module docs), with the predicted signal energy Ê_k = Σ_i c̃_{k,i}·x_i²:
//!   R_k = (N0²·TW + 2·N0·Ê_k)/N_p + (ε·Ê_k)²,
//! ε = `model_error` (relative standard deviation of the model error of a bin's energy:
//! speckle of a cell holding several scatterers, the centre-frequency pattern; default 0.5;
//! 0 gives the detector statistics alone).
//!
//! Update of one (pose, direction), linearised once at the mean x⁻ before it (standard EKF):
//!   ν = z − h(x⁻), S = H P Hᵀ + R, K = P Hᵀ S⁻¹, x⁺ = x⁻ + K ν, P⁺ = P − K S Kᵀ.
//! After each update the sign symmetry of the model (h depends on x²) is used: a cell whose
//! mean went negative is reflected, x_i → −x_i with row and column i of P negated (an exact
//! change of variables, not an approximation), and means are kept ≥ 1e-3·μ0 so the
//! Jacobian never vanishes ([`RrcsFilter::project_positive`]).
//!
//! Update (`--ekf-update`, [`EkfUpdate`]). The observation is quadratic in the state and
//! the default prior reaches far below zero, where the first-order expansion at μ0 fails:
//! at x⁻ = μ0 the prediction c̃·μ0² ignores the prior's own power c̃·σ0², the Jacobian is
//! tiny, and one strong bin throws a cell far past its truth with a variance that has
//! collapsed (average NEES per cell 97–220 times its expectation, `docs/mapping.md`).
//! `second-order` is the Gaussian second-order filter (Jazwinski 1970; Bar-Shalom, Li &
//! Kirubarajan 2001, §10.3): per row the prediction gains Σ_i c̃_i·P_ii and R_k gains
//! 2·Σ_ij c̃_i·c̃_j·P_ij² ([`Linearized::second_order`]; the tiled filter's pairs within a
//! tile, the covariance it keeps), the exact mean and variance of the quadratic form under
//! N(x⁻, P); the rows' mutual quadratic covariance is left out (it would need the m × m S,
//! which the push-through update avoids). It is the remedy kept of the four measured
//! (the iterated EKF, a full second-order S, the noise averaged over the state; figures in
//! `docs/mapping.md`, "Issue 48"): NEES 2.2 against the EKF's 97. It is not the default:
//! under the default prior every cell predicts the prior's power c̃·(μ0² + σ0²), so the
//! cells climb slowly and keep honest, wide variances, and the binary rule x̂ − κσ̂ > μ0
//! finds 0.48–0.56 of the observable walls against the first order's 0.81–0.88.
//!
//! Two implementations of [`RrcsFilter`]:
//! * [`DenseEkf`] — exact, full n × n covariance (row-major, 8n² bytes: the reference up to a
//!   few thousand cells; refused above `max_dense_cells`). Only the na illuminated cells have
//!   nonzero columns of H (m rows = bins), so with Y = P[A, :] the update is done as a
//!   rank-r downdate, r = min(m, na):
//!   - m ≤ na: Uᵀ = H_A·Y (sparse rows of H times rows of P), S = Uᵀ[:, A]·H_Aᵀ + R,
//!     S = L·Lᵀ (Cholesky), Wᵀ = L⁻¹Uᵀ, x += Wᵀᵀ·L⁻¹ν, P −= W·Wᵀ;
//!   - m > na: M = H_Aᵀ·S⁻¹·H_A (na × na) without forming the m × m matrix S, by the
//!     push-through identity H_Aᵀ(H_A P_AA H_Aᵀ + R)⁻¹H_A = G(I + P_AA G)⁻¹,
//!     G = H_Aᵀ R⁻¹ H_A (R diagonal). In a symmetric, well-conditioned form: P_AA = L·Lᵀ,
//!     C = I + Lᵀ·G·L (eigenvalues ≥ 1), M = L⁻ᵀ·(I − C⁻¹)·L⁻¹, and the gain applied to
//!     ν is Yᵀ·L⁻ᵀ·C⁻¹·Lᵀ·H_Aᵀ R⁻¹ ν; then P −= Yᵀ·(M·Y). Cost O(nnz + na³) instead of
//!     O(m³ + m²·na) (timings: `docs/mapping.md`). If P_AA or C is not
//!     numerically positive definite the update goes through S instead:
//!     S = H_A·P_AA·H_Aᵀ + R, V = L⁻¹H_A, M = VᵀV, x += Yᵀ·Vᵀ·L⁻¹ν, P −= Yᵀ·(M·Y).
//!
//!   All bins of the observation are processed together (one batch per (pose, direction)).
//!   The downdate is computed on the upper triangle in blocks of 64 rows (matrix products of
//!   `ndarray`/matrixmultiply, blocks in parallel) and mirrored, so P is exactly symmetric
//!   (the symmetric form P − W·Wᵀ rather than the Joseph form, whose cost is n³ per update);
//!   S is symmetrised before its Cholesky factorisation.
//! * [`TiledEkf`] — scalable: the covariance is kept block-diagonal over square tiles of
//!   `tile` × `tile` cells (4 × 4 by default): the covariances among neighbouring cells (the
//!   ones a range ring couples most strongly and that shape a wall's outline) are kept, the
//!   cross-tile ones are dropped. The bins of an observation are processed one at a time as
//!   scalar measurements of the same linearisation (frozen at x⁻: innovation
//!   ν'_k = z_k − h_k(x⁻) − H_k·(x − x⁻)), which for a full covariance is exactly the batch
//!   update above (R is diagonal). Dropping the cross-tile covariances alone (the plain
//!   update) makes the filter overconfident: later bins of a ring count the other tiles'
//!   contribution as fresh noise again. So each bin's information is split over the tiles
//!   it touches: tile T takes the bin with its noise variance
//!   divided by its share ω_T = a_T/Σa of H·P·Hᵀ (a_T = H_{k,T}·P_T·H_{k,T}ᵀ),
//!   s_T = a_T + (s − a_T)/ω_T, x_T += g_T·ν'_k/s_T, P_T −= g_T·g_Tᵀ/s_T with
//!   g_T = P_T·H_{k,T}ᵀ; the reasons, the alternatives measured and the NEES are in
//!   [`tiled`]'s docs. The cost per bin is Σ_T (|T|·nnz + |T|²), so a campaign costs
//!   O(nnz(H)·tile²) and memory O(n·tile²). With one tile covering the grid it equals
//!   [`DenseEkf`] (tested).
//!
//! Order and determinism: runs, poses and directions in order; the observations of a pose's
//! directions are built in parallel (beam, kernel convolution) and applied in direction
//! order; the dense products split P in fixed blocks, so maps are identical for any number
//! of threads.
//!
//! Free-space evidence. The energy observation
//! h = Σ c̃ x² + N0·TW says little about a cell near x = 0 (its Jacobian 2 c̃ x vanishes
//! there), so a bin with only noise barely lowers the cells in front of an echo, while the
//! echo's bin raises every cell of its range ring in the main lobe: the ring. The bins
//! before the occluder that hold no echo are read as what they are, free space: in each
//! such bin (below the detector's threshold T, no detection within the kernel half-width J,
//! k + J before the occluder) each cell whose largest coefficient in the observation is in
//! that bin and within −3 dB of the bin's largest (the main lobe at that range) is observed
//! directly, z = x_i = 0 with variance x_max²/3, x_max² = (T − N0·TW)/c̃_{k,i}: a cell of
//! RRCS x_max would by itself have lifted the bin to the threshold, and a belief uniform on
//! [−x_max, x_max] has that variance (the sign symmetry below). The pseudo-measurement comes
//! from the same bins as the energy rows, which stay in the update, so it is not independent
//! evidence: it is the EKF's counterpart of the occupancy grid's free-space update. Measured
//! (`docs/mapping.md`): it cuts the room cells marked occupied on the corridor at
//! N = 100 from 18.3 % to 10.1 %.
//!
//! Binary map: occupied when x̂_i − κ·σ̂_i > μ0 (the data raised the cell above the prior
//! mean by κ posterior standard deviations), i.e. p_i > η = Φ(κ) with
//! p_i = Φ((x̂_i − μ0)/σ̂_i). κ = Φ⁻¹(1 − 10⁻³) = 3.09 by default ([`params::KAPPA`]): the
//! false-alarm rate per cell of the occupancy grid's detector (P_fa = 10⁻³), so both mappers
//! call a cell occupied at the same rate under their own models (it was 2, a 2.3 % rate per
//! cell, about 50 false cells in a 2,000-cell building). The rule uses the prior and the
//! posterior only, never the reference map; cells never illuminated stay at the prior and
//! read as free.
//!
//! Arc explanation (`arc_explain` = γ, [`params::ARC_EXPLAIN`] by default; 0 =
//! off). Once the runs are filtered, each detected echo's range ring (the cells with a
//! coefficient in the bin of a kept row that holds a detection, main and side lobes:
//! [`EchoArcs`], recorded by [`ekf_run_with_arcs`]) is explained by its cells in proportion to
//! c̃_i·x̂_i²; a cell is occupied only if on some ring its share is at least γ times the
//! ring's strongest cell's ([`EkfMap::explain`]). The filter updates the whole ring with an
//! echo, so the cells it cannot tell apart keep confident means (measured: the false room
//! cells have z = (x̂ − μ0)/σ̂ of 13–36, so no κ separates them); what the final map tells
//! apart is which cells the echo needs. γ = −26.5 dB is the two-way peak side-lobe level of
//! the (uniform) array: a cell as strong as the ring's strongest at a first side-lobe peak
//! still explains it. A cell on no detected ring (raised only by bins without a
//! detection) explains no echo and is not occupied. Measured (`docs/mapping.md`,
//! "Item 2 (continued)"): in all four scenes of `tests/occlusion.rs` building wrong cells
//! −9 to −18 %, room cells marked occupied 6.0–8.5 % → 3.4–4.4 %, cells beyond the walls
//! ≤ 4.3 %, F1 within one cell up, walls found −0.005 to −0.038; the variants not kept (the
//! −3 dB arcs only, κ, the mirror ghost rule, a ring without the detected-ring requirement)
//! are there too. The binary map (below) is taken with the explanation; the soft map of an
//! unexplained cell is capped at η; the occluders confirmed during the run use the rule
//! without it.
//!
//! Negative means are reflected (above), not clamped to zero (the projection onto x ≥ 0,
//! measured in `docs/mapping.md`): a clamped mean sits where the Jacobian vanishes, so
//! later rows cannot move it, while its variance stays that of the unconstrained estimate.
//!
//! Layout: [`params`] ([`EkfParams`] → [`EkfValid`]), [`observation`] (noise model, kernel,
//! [`Observation`], [`Linearized`]), [`dense`] ([`DenseEkf`]) over [`linalg`], [`tiled`]
//! ([`TiledEkf`]), [`run`] ([`ekf_run`], [`EkfMap`]). The `map --method ekf` job that
//! writes the files is [`crate::job`] (it uses this module, never the other way).
//!
//! ```
//! use pradar_mapping::ekf::{DenseEkf, EkfParams, Linearized, NoiseModel, Observation, RrcsFilter};
//! use pradar_formats::params::ParamGuard;
//! let params = EkfParams::default().check().unwrap();
//! let mut f = DenseEkf::new(2, &params).unwrap();
//! // one bin seeing both cells (c̃ = 1e-3), measured energy well above the prediction
//! let obs = Observation { bin: vec![10], z: vec![1e-6], ptr: vec![0, 2], cell: vec![0, 1], coef: vec![1e-3, 1e-3] };
//! let noise = NoiseModel { n0: 1e-9, tw: 1.0, pulses: 1.0, model_error: 0.5 };
//! let lin = Linearized::new(&obs, f.mean(), &noise);
//! f.update(&obs, &lin).unwrap();
//! assert!(f.mean()[0] > params.mu0 && f.variances()[0] < params.sigma0.powi(2));
//! ```

pub mod dense;
pub mod linalg;
pub mod observation;
pub mod params;
pub mod run;
pub mod tiled;

pub use dense::DenseEkf;
pub use linalg::cholesky;
pub use observation::{truncate_kernel, Linearized, NoiseModel, Observation};
pub use params::{normal_cdf, EkfParams, EkfUpdate, EkfValid, EkfVariant};
pub use run::{
    ekf_run, ekf_run_with_arcs, mean_grey, std_grey, EchoArcs, EkfMap, EkfReport, EkfStats, Sight,
};
pub use tiled::TiledEkf;

use crate::error::Result;

/// The interface of both EKF implementations.
pub trait RrcsFilter: Send {
    /// Cells.
    fn len(&self) -> usize;
    /// True for an empty grid.
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Posterior means.
    fn mean(&self) -> &[f64];
    /// Posterior variances P_ii.
    fn variances(&self) -> Vec<f64>;
    /// Covariance P_ij if the filter keeps it (always for the dense filter).
    fn covariance(&self, i: usize, j: usize) -> Option<f64>;
    /// One EKF update with an observation linearised at the current mean.
    fn update(&mut self, obs: &Observation, lin: &Linearized) -> Result<()>;
    /// `obs` linearised at the current mean with the Gaussian second-order terms of the
    /// filter's own covariance ([`Linearized::second_order`]).
    fn linearize_second_order(&self, obs: &Observation, noise: &NoiseModel) -> Linearized;
    /// Reflect negative means (x_i → −x_i, row/column i of P negated), then keep means
    /// ≥ `x_min`; returns the cells reflected.
    fn project_positive(&mut self, x_min: f64) -> usize;
    /// Name (`dense`, `scalable`).
    fn name(&self) -> &'static str;
}

/// Build the filter of `params.variant` for `cells` cells in a `rows` × `cols` grid.
pub fn new_filter(params: &EkfValid, rows: usize, cols: usize) -> Result<Box<dyn RrcsFilter>> {
    Ok(match params.variant {
        EkfVariant::Dense => Box::new(DenseEkf::new(rows * cols, params)?),
        EkfVariant::Scalable => Box::new(TiledEkf::new(rows, cols, params.tile, params)?),
    })
}
