//! The multi-fidelity search: the envelope model (level 0) screens the design space — every
//! design when the space is small enough, a particle swarm (argmin) over the fill fractions of
//! every categorical choice otherwise — and the time simulation (level 1) verifies a budget of
//! designs: the best screened half first, then a discrete local search that moves from the best
//! verified design to its neighbour with the best screening value until the budget is spent.
//! Every verified design carries both levels' values, so the screening's error is measured on
//! the designs that matter.

use crate::DesignError;
use crate::fidelity::{Evaluation, envelope_evaluation, time_evaluation};
use crate::space::{Choice, Design, Space};
use crate::study::Screening;
use argmin::core::{CostFunction, Executor};
use argmin::solver::particleswarm::ParticleSwarm;
use rand_chacha::ChaCha8Rng;
use rand_chacha::rand_core::SeedableRng;
use rayon::prelude::*;
use serde::Serialize;
use std::collections::{BTreeMap, HashMap};
use std::sync::Mutex;

/// A design with what each level said of it.
#[derive(Debug, Clone, Serialize)]
pub struct Candidate {
    /// The design.
    pub design: Design,
    /// Level 0 (envelope).
    pub envelope: Evaluation,
    /// Level 1 (time simulation), for verified designs.
    pub time: Option<Evaluation>,
    /// Order in which it was verified (0-based), for verified designs.
    pub verified_as: Option<usize>,
}

impl Candidate {
    /// The highest-fidelity cost known.
    pub fn best_cost(&self) -> f64 {
        self.time.as_ref().map_or(self.envelope.cost, |t| t.cost)
    }
}

/// What the search did.
#[derive(Debug, Clone, Serialize)]
pub struct SearchOutcome {
    /// Screened designs with their levels, verified designs first (by level-1 cost), then the
    /// screened ones by level-0 cost.
    pub candidates: Vec<Candidate>,
    /// Designs in the space (before constraints).
    pub space_size: f64,
    /// Envelope evaluations (level 0).
    pub envelope_evaluations: usize,
    /// Time simulations (level 1).
    pub time_evaluations: usize,
    /// How the space was screened (`enumerate` or `swarm`).
    pub screening: &'static str,
    /// Wall time of the screening, s.
    pub screening_wall_s: f64,
    /// Wall time of the verification, s.
    pub verification_wall_s: f64,
}

/// Level-0 evaluation of a design.
///
/// # Errors
/// A damper spec the structure refuses.
pub fn screen(space: &Space, d: &Design) -> Result<Evaluation, DesignError> {
    let dampers = space.coupled_dampers(d)?;
    envelope_evaluation(space.study, space.structure(d.choice), &dampers)
}

/// Level-1 evaluation of a design.
///
/// # Errors
/// Solver errors.
pub fn verify(space: &Space, d: &Design) -> Result<Evaluation, DesignError> {
    let dampers = space.coupled_dampers(d)?;
    Ok(time_evaluation(space.study, space.structure(d.choice), &dampers)?.0)
}

/// Cost the swarm sees: level 0 of the rounded design (cached), a penalty for infeasible ones.
struct SwarmProblem<'a, 'b> {
    space: &'a Space<'b>,
    choice: Choice,
    cache: &'a Mutex<HashMap<Design, Evaluation>>,
}

const INFEASIBLE: f64 = 1e100;

impl CostFunction for SwarmProblem<'_, '_> {
    type Param = Vec<f64>;
    type Output = f64;
    fn cost(&self, fill: &Vec<f64>) -> Result<f64, argmin::core::Error> {
        let d = self.space.from_fill(self.choice, fill);
        if !self.space.feasible(&d) {
            return Ok(INFEASIBLE);
        }
        if let Some(e) = self.cache.lock().expect("cache").get(&d) {
            return Ok(e.cost);
        }
        let e = screen(self.space, &d).map_err(|e| argmin::core::Error::msg(e.to_string()))?;
        let c = e.cost;
        self.cache.lock().expect("cache").insert(d, e);
        Ok(c)
    }
}

/// Screens the space with level 0.
/// Screened designs with their level-0 evaluations, and how they were screened.
type Screened = (Vec<(Design, Evaluation)>, &'static str);

fn screen_space(space: &Space) -> Result<Screened, DesignError> {
    let s = &space.study.file.search;
    let size = space.size();
    let enumerate = match s.screening {
        Screening::Enumerate => true,
        Screening::Swarm => false,
        Screening::Auto => size <= s.max_enumerated as f64,
    };
    if enumerate {
        if size > 1e7 {
            return Err(DesignError::Input {
                path: space.study.path.clone(),
                key: "search.screening".into(),
                message: format!(
                    "{size:.3e} designs are too many to enumerate; use screening = \"swarm\" or \
                     \"auto\", coarser particle_count_step or fewer candidates"
                ),
            });
        }
        let designs: Vec<Design> = space
            .choices()
            .into_iter()
            .flat_map(|c| space.enumerate(c))
            .collect();
        let evals: Vec<Evaluation> = designs
            .par_iter()
            .map(|d| screen(space, d))
            .collect::<Result<_, _>>()?;
        return Ok((designs.into_iter().zip(evals).collect(), "enumerate"));
    }
    let cache = Mutex::new(HashMap::new());
    let layers = space.study.file.damper.layers;
    for (i, choice) in space.choices().into_iter().enumerate() {
        let problem = SwarmProblem {
            space,
            choice,
            cache: &cache,
        };
        let rng = ChaCha8Rng::seed_from_u64(s.seed.wrapping_add(i as u64));
        let solver = ParticleSwarm::new((vec![0.0; layers], vec![1.0; layers]), s.swarm_particles)
            .with_rng_generator(rng);
        Executor::new(problem, solver)
            .configure(|st| st.max_iters(s.swarm_iterations))
            .run()
            .map_err(|e| DesignError::Solver(format!("particle swarm: {e}")))?;
    }
    let map = cache.into_inner().expect("cache");
    let mut v: Vec<(Design, Evaluation)> = map.into_iter().collect();
    v.sort_by(|a, b| a.0.cmp(&b.0));
    Ok((v, "swarm"))
}

/// Default number of time simulations: 10 % of the screened designs, within [2, 60].
pub fn default_verifications(screened: usize) -> usize {
    (screened as f64 * 0.1).ceil().clamp(2.0, 60.0) as usize
}

/// Runs the search.
///
/// # Errors
/// No feasible design; solver errors.
pub fn run_search(space: &Space) -> Result<SearchOutcome, DesignError> {
    let t0 = std::time::Instant::now();
    let (mut screened, how) = screen_space(space)?;
    if screened.is_empty() {
        return Err(DesignError::Empty(format!(
            "{:.0} designs in the space, none with particles within constraints.max_bed_mass_kg \
             / min_clearance_m",
            space.size()
        )));
    }
    let mut envelope_evaluations = screened.len();
    screened.sort_by(|a, b| a.1.cost.total_cmp(&b.1.cost).then(a.0.cmp(&b.0)));
    let screening_wall_s = t0.elapsed().as_secs_f64();
    let t1 = std::time::Instant::now();
    let budget = space
        .study
        .file
        .search
        .verifications
        .unwrap_or_else(|| default_verifications(screened.len()));
    let mut level0: BTreeMap<Design, Evaluation> = screened.iter().cloned().collect();
    let mut verified: BTreeMap<Design, (Evaluation, usize)> = BTreeMap::new();
    // phase A: the best screened half of the budget (in parallel, recorded in screening order)
    let first: Vec<Design> = screened
        .iter()
        .take(budget.div_ceil(2))
        .map(|(d, _)| d.clone())
        .collect();
    let evals: Vec<Evaluation> = first
        .par_iter()
        .map(|d| verify(space, d))
        .collect::<Result<_, _>>()?;
    for (d, e) in first.into_iter().zip(evals) {
        let n = verified.len();
        verified.insert(d, (e, n));
    }
    // phase B: local search on level 1, guided by level 0
    let mut next_screened = 0;
    while verified.len() < budget {
        let incumbent = verified
            .iter()
            .min_by(|a, b| a.1.0.cost.total_cmp(&b.1.0.cost).then(a.0.cmp(b.0)))
            .map(|(d, _)| d.clone())
            .expect("at least one verified design");
        let mut pick: Option<(Design, f64)> = None;
        for n in space.neighbours(&incumbent) {
            if verified.contains_key(&n) {
                continue;
            }
            let cost = match level0.get(&n) {
                Some(e) => e.cost,
                None => {
                    let e = screen(space, &n)?;
                    envelope_evaluations += 1;
                    let c = e.cost;
                    level0.insert(n.clone(), e);
                    c
                }
            };
            if pick.as_ref().is_none_or(|p| cost < p.1) {
                pick = Some((n, cost));
            }
        }
        let d = match pick {
            Some((d, _)) => d,
            None => {
                // the incumbent is a local optimum on level 1: continue down the screening list
                while next_screened < screened.len()
                    && verified.contains_key(&screened[next_screened].0)
                {
                    next_screened += 1;
                }
                match screened.get(next_screened) {
                    Some((d, _)) => d.clone(),
                    None => break,
                }
            }
        };
        let e = verify(space, &d)?;
        let n = verified.len();
        verified.insert(d, (e, n));
    }
    let time_evaluations = verified.len();
    let mut candidates: Vec<Candidate> = level0
        .into_iter()
        .map(|(design, envelope)| {
            let v = verified.get(&design).cloned();
            Candidate {
                design,
                envelope,
                time: v.as_ref().map(|x| x.0.clone()),
                verified_as: v.map(|x| x.1),
            }
        })
        .collect();
    candidates.sort_by(|a, b| {
        b.time
            .is_some()
            .cmp(&a.time.is_some())
            .then(a.best_cost().total_cmp(&b.best_cost()))
            .then(a.design.cmp(&b.design))
    });
    Ok(SearchOutcome {
        candidates,
        space_size: space.size(),
        envelope_evaluations,
        time_evaluations,
        screening: how,
        screening_wall_s,
        verification_wall_s: t1.elapsed().as_secs_f64(),
    })
}

/// Spearman rank correlation of two samples (ties get the mean rank); `None` below 3 points.
pub fn spearman(a: &[f64], b: &[f64]) -> Option<f64> {
    if a.len() != b.len() || a.len() < 3 {
        return None;
    }
    fn ranks(v: &[f64]) -> Vec<f64> {
        let mut idx: Vec<usize> = (0..v.len()).collect();
        idx.sort_by(|&i, &j| v[i].total_cmp(&v[j]));
        let mut r = vec![0.0; v.len()];
        let mut i = 0;
        while i < idx.len() {
            let mut j = i;
            while j + 1 < idx.len() && v[idx[j + 1]] == v[idx[i]] {
                j += 1;
            }
            for &k in &idx[i..=j] {
                r[k] = 0.5 * (i + j) as f64;
            }
            i = j + 1;
        }
        r
    }
    let (ra, rb) = (ranks(a), ranks(b));
    let n = a.len() as f64;
    let ma = ra.iter().sum::<f64>() / n;
    let mb = rb.iter().sum::<f64>() / n;
    let cov: f64 = ra.iter().zip(&rb).map(|(x, y)| (x - ma) * (y - mb)).sum();
    let va: f64 = ra.iter().map(|x| (x - ma).powi(2)).sum();
    let vb: f64 = rb.iter().map(|y| (y - mb).powi(2)).sum();
    (va > 0.0 && vb > 0.0).then(|| cov / (va * vb).sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spearman_of_monotone_and_reversed_samples() {
        let a = [1.0, 2.0, 3.0, 4.0];
        assert_eq!(spearman(&a, &[10.0, 20.0, 30.0, 40.0]), Some(1.0));
        assert_eq!(spearman(&a, &[4.0, 3.0, 2.0, 1.0]), Some(-1.0));
        assert_eq!(spearman(&a[..2], &a[..2]), None);
        assert_eq!(default_verifications(455), 46);
        assert_eq!(default_verifications(13), 2);
        assert_eq!(default_verifications(5000), 60);
    }
}
