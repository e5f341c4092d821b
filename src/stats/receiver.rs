//! Receiver statistics: each cell's value, σ, VOV, degrees of freedom and status from
//! the tallies (eqs. 6–11), and the receiver's mean and its error over its cells.

use super::*;

/// Values, errors and hits of one receiver.
#[derive(Clone, Debug, Default)]
pub struct ReceiverStats {
    pub values: Vec<f64>,
    /// NaN where the cell's error is unknown (nothing scored there).
    pub sigma: Vec<f64>,
    pub hits: Vec<u64>,
    /// Histories that scored in each cell.
    pub scoring_histories: Vec<u64>,
    /// Each cell's VOV ([`cell_vov`]; 1 where nothing is known).
    pub vov: Vec<f64>,
    /// Each cell's effective degrees of freedom ([`cell_dof`]; 0 where nothing scored).
    pub dof: Vec<f64>,
    pub status: Vec<CellStatus>,
    /// Upper bound of each dark or unreliable cell's value ([`dark_upper_bound`],
    /// [`unreliable_upper_bound`]; NaN for the others).
    pub upper_bound: Vec<f64>,
    pub mean: f64,
    /// Eq. 9 over all cells: NaN while some cell's error is unknown.
    pub rel_error: Averaged,
    /// Eq. 9 over the cells whose error is known.
    pub rel_error_known: Averaged,
    /// Cells whose error is unknown: dark and unknown cells.
    pub unknown_cells: usize,
    pub unreliable_cells: usize,
    pub dark_cells: usize,
    /// Largest upper bound of a dark cell (0 without).
    pub dark_bound: f64,
    /// RMS σ over the cells (eq. 9's numerator), in the receiver's unit; NaN while some
    /// cell's error is unknown.
    pub rms_sigma: f64,
    /// The σ a target judges each cell by: its σ if reliable, [`widened_sigma`] if
    /// unreliable, NaN for dark and unknown cells; eq. 9 (quadratic), the RMS σ and the
    /// quadratic mean value over the cells it is known for.
    pub judged_sigma: Vec<f64>,
    pub rel_error_judged: f64,
    pub rms_sigma_judged: f64,
    pub quadratic_mean_judged: f64,
}

/// Per-cell values and σ of a receiver's cells `cells`, a grid of `shape` = [nu, nv]
/// cells stored j·nu + i: the value as [`cell_value`], the σ with the photons' variance
/// from [`pooled_variance`] over the cell's neighbours. Cells where nothing scored keep
/// an unknown σ.
pub fn cell_values(cells: &[CellSums], shape: [u32; 2], counts: Counts) -> (Vec<f64>, Vec<f64>) {
    let (values, sigmas, _) = cell_values_and_parts(cells, shape, counts);
    (values, sigmas)
}

/// A cell's estimate as daylight coefficients (the annual run) take it: the value and
/// variance of the whole estimate and of its sampled direct part, in the receiver's unit
/// (and its square), and the contributions scored.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct CellEstimate {
    pub value: f64,
    pub var: f64,
    pub direct: f64,
    pub direct_var: f64,
    pub hits: u64,
    /// Photon histories that scored here (of the run's photons).
    pub scoring_histories: u64,
}

/// Every cell's [`CellEstimate`] (variances as [`cell_values`]' σ, with the pooled photon
/// variance; where nothing scored, the value 0 with its neighbours' variance).
pub fn cell_estimates(cells: &[CellSums], shape: [u32; 2], counts: Counts) -> Vec<CellEstimate> {
    let (values, _, vars) = cell_values_and_parts(cells, shape, counts);
    let unit2 = counts.unit * counts.unit;
    (cells.iter().zip(values).zip(vars))
        .map(|((c, value), (photon_var, direct_var))| CellEstimate {
            value,
            var: (photon_var + direct_var) * unit2,
            direct: direct_part(c, counts).0 * counts.unit,
            direct_var: direct_var * unit2,
            hits: c.hits,
            scoring_histories: c.scoring_histories,
        })
        .collect()
}

/// [`cell_values`], with each cell's photon and direct variances as reported (in the
/// score unit).
fn cell_values_and_parts(
    cells: &[CellSums],
    shape: [u32; 2],
    counts: Counts,
) -> (Vec<f64>, Vec<f64>, Vec<(f64, f64)>) {
    use rayon::prelude::*;
    // Cells are independent, each computed the same way on any thread (same bits); a
    // 10⁶-cell receiver took ≈ 100 ms per epoch on one thread. Run inside the run's pool.
    const MIN_CELLS_PER_TASK: usize = 4096;
    let (nu, nv) = (shape[0] as usize, shape[1] as usize);
    debug_assert_eq!(nu * nv, cells.len());
    let parts: Vec<PhotonPart> = cells
        .par_iter()
        .with_min_len(MIN_CELLS_PER_TASK)
        .map(|c| photon_part(c, counts))
        .collect();
    let own: Vec<f64> = parts.iter().map(|p| p.var).collect();
    let per_cell: Vec<(f64, f64, (f64, f64))> = cells
        .par_iter()
        .zip(&parts)
        .enumerate()
        .with_min_len(MIN_CELLS_PER_TASK)
        .map(|(k, (c, p))| {
            let pooled = neighbour_median(&own, nu, nv, k % nu, k / nu);
            if c.hits == 0 {
                // σ unknown; the variance its neighbours saw is what it should have drawn.
                let var = if counts.dark { 0.0 } else { pooled };
                return (0.0, if counts.dark { 0.0 } else { f64::NAN }, (var, 0.0));
            }
            let (direct_value, direct_var) = direct_part(c, counts);
            let photon_var = pooled_variance(p.var, p.var_sd, pooled);
            let sigma = if counts.photon_variance_known() {
                (photon_var + direct_var).sqrt() * counts.unit
            } else {
                f64::NAN
            };
            (
                (p.value + direct_value) * counts.unit,
                sigma,
                (photon_var, direct_var),
            )
        })
        .collect();
    let mut values = Vec::with_capacity(cells.len());
    let mut sigmas = Vec::with_capacity(cells.len());
    let mut vars = Vec::with_capacity(cells.len());
    for (v, s, p) in per_cell {
        values.push(v);
        sigmas.push(s);
        vars.push(p);
    }
    (values, sigmas, vars)
}

/// Per-cell statistics of a receiver's cells `cells` ([`cell_values`]), a grid of
/// `shape` cells, summarised over the cells `picked` (local indices; `None`: all).
/// Each cell's VOV, degrees of freedom and [`CellStatus`] too: eq. 9 is reported over
/// all cells and over those whose error is known (not dark, not unknown).
pub fn receiver_stats(
    cells: &[CellSums],
    shape: [u32; 2],
    counts: Counts,
    picked: Option<&[usize]>,
) -> ReceiverStats {
    use rayon::prelude::*;
    let (values, sigmas, vars) = cell_values_and_parts(cells, shape, counts);
    // Local index of the `i`-th cell summarised (a whole receiver needs no list).
    let count = picked.map_or(cells.len(), <[usize]>::len);
    let index = |i: usize| picked.map_or(i, |p| p[i]);
    let receiver_scored = cells.iter().any(|c| c.hits > 0);
    // Each cell's VOV and degrees of freedom, in parallel as the values above.
    let vov_dof: Vec<(f64, f64)> = (0..count)
        .into_par_iter()
        .with_min_len(4096)
        .map(|i| {
            let k = index(i);
            let c = &cells[k];
            if c.hits > 0 || counts.dark {
                let dof = cell_dof(c, counts, vars[k].0, vars[k].1);
                (cell_vov(c, counts), dof)
            } else {
                (1.0, 0.0)
            }
        })
        .collect();
    // The same bound for every dark cell, computed only when there is one.
    let dark_bound = std::cell::OnceCell::new();
    let mut s = ReceiverStats::default();
    for (i, &(vov, dof)) in vov_dof.iter().enumerate() {
        let k = index(i);
        let c = &cells[k];
        let status = cell_status(c, counts, receiver_scored, vov, dof);
        s.values.push(values[k]);
        s.sigma.push(sigmas[k]);
        s.hits.push(c.hits);
        s.scoring_histories.push(c.scoring_histories);
        s.vov.push(vov);
        s.dof.push(dof);
        s.status.push(status);
        s.upper_bound.push(match status {
            CellStatus::Dark => {
                *dark_bound.get_or_init(|| dark_upper_bound(counts, typical_scores(cells, counts)))
            }
            CellStatus::Unreliable => unreliable_upper_bound(values[k], sigmas[k], vov, dof),
            _ => f64::NAN,
        });
    }
    // Eq. 9 in the score unit (exact: a power of two), where squares stay finite.
    let unit = counts.unit;
    let pairs = || (s.values.iter().zip(&s.sigma)).map(|(v, sigma)| (v / unit, sigma / unit));
    let all = mean_error_of(pairs());
    (s.mean, s.rel_error, s.rms_sigma) = (all.0 * unit, all.1, all.2 * unit);
    let known = mean_error_of(pairs().filter(|(_, sigma)| !sigma.is_nan()));
    s.rel_error_known = known.1;
    // The lit cells with the σ a target judges them by: widened where unreliable.
    s.judged_sigma = (0..s.values.len())
        .map(|k| match s.status[k] {
            CellStatus::Unreliable => widened_sigma(s.sigma[k], s.vov[k], s.dof[k]),
            CellStatus::Reliable => s.sigma[k],
            _ => f64::NAN,
        })
        .collect();
    let judged = (s.values.iter().zip(&s.judged_sigma))
        .filter(|(_, sigma)| !sigma.is_nan())
        .map(|(v, sigma)| (v / unit, sigma / unit));
    let judged = mean_error_of(judged);
    s.rel_error_judged = judged.1.quadratic;
    s.rms_sigma_judged = judged.2 * unit;
    s.quadratic_mean_judged = judged.3 * unit;
    s.unknown_cells = s.sigma.iter().filter(|sigma| sigma.is_nan()).count();
    let count = |status| s.status.iter().filter(|&&x| x == status).count();
    s.unreliable_cells = count(CellStatus::Unreliable);
    s.dark_cells = count(CellStatus::Dark);
    s.dark_bound = dark_bound.get().copied().unwrap_or(0.0);
    s
}

/// A cell's [`CellStatus`] from its VOV and degrees of freedom, `receiver_scored` when
/// any cell of its receiver scored. In a scene that emits nothing every cell is an
/// exact 0 ± 0: reliable.
fn cell_status(
    c: &CellSums,
    counts: Counts,
    receiver_scored: bool,
    vov: f64,
    dof: f64,
) -> CellStatus {
    if counts.dark {
        CellStatus::Reliable
    } else if c.hits > 0 {
        if dof >= MIN_RELIABLE_DOF && vov <= MAX_RELIABLE_VOV {
            CellStatus::Reliable
        } else {
            CellStatus::Unreliable
        }
    } else if receiver_scored {
        CellStatus::Dark
    } else {
        CellStatus::Unknown
    }
}
