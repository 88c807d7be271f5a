//! Genetic algorithm over bit strings (seed 004 §III.B, Fig 1): a population
//! of chromosomes (one bit per candidate), fitness to minimise (the caller's
//! closure, e.g. a K-fold CV RMSE, eq 17), elite and anti-elite selection,
//! crossover and mutation, stopping on stall or a generation cap.
//!
//! Per generation: the `elite` best chromosomes pass unchanged; the
//! `anti_elite` worst are replaced by fresh random chromosomes (diversity);
//! the rest are children of two tournament-selected parents by uniform
//! crossover and bit-flip mutation. Every chromosome has between `min_ones`
//! and `max_ones` bits set (a size cap, e.g. C ≤ (K−1)m/K), repaired by
//! random flips. Fitness is evaluated in parallel (rayon) and cached per
//! chromosome; all random draws happen sequentially from one seeded stream, so
//! the result does not depend on the number of threads.

use rand::RngExt;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;

/// Options of [`ga`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GaOptions {
    /// Chromosomes per generation (raised to at least `elite + anti_elite + 2`).
    pub population: usize,
    /// Best chromosomes copied unchanged into the next generation.
    pub elite: usize,
    /// Worst chromosomes replaced each generation by fresh random ones (diversity).
    pub anti_elite: usize,
    /// Tournament size for parent selection.
    pub tournament: usize,
    /// Probability of taking each bit from the first parent in crossover.
    pub crossover_bias: f64,
    /// Per-bit mutation probability (default: 1 / bits when 0).
    pub mutation: f64,
    /// Probability that a bit is set in a fresh random chromosome.
    pub density: f64,
    /// Fewest bits set in any chromosome (e.g. terms selected).
    pub min_ones: usize,
    /// Most bits set in any chromosome: the size cap, e.g. C ≤ (K−1)m/K.
    pub max_ones: usize,
    /// Generation cap.
    pub max_generations: usize,
    /// Stop after this many generations without improvement of the best.
    pub stall: usize,
    /// Seed of the GA's random stream ([`crate::stats::rng_for`], stream `"ga"`).
    pub seed: u64,
}

impl Default for GaOptions {
    fn default() -> Self {
        GaOptions {
            population: 32,
            elite: 2,
            anti_elite: 4,
            tournament: 3,
            crossover_bias: 0.5,
            mutation: 0.0,
            density: 0.2,
            min_ones: 1,
            max_ones: usize::MAX,
            max_generations: 60,
            stall: 12,
            seed: 1,
        }
    }
}

/// Result of [`ga`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaResult {
    /// Best chromosome found: one bit per candidate, `true` = selected.
    pub best: Vec<bool>,
    /// Its fitness (the minimised value, e.g. K-fold CV RMSE).
    pub fitness: f64,
    /// Best fitness after each generation (seed 004 Fig 10).
    pub history: Vec<f64>,
    /// Distinct chromosomes evaluated.
    pub evaluations: usize,
    /// Generations run (≤ `max_generations`; fewer on stall).
    pub generations: usize,
}

/// Minimise `fitness` over bit strings of length `bits`. `on_generation` is
/// called after each generation with (generation, best fitness) — for
/// progress display.
pub fn ga<F, P>(bits: usize, fitness: F, opts: &GaOptions, mut on_generation: P) -> GaResult
where
    F: Fn(&[bool]) -> f64 + Sync,
    P: FnMut(usize, f64),
{
    let mut rng = crate::stats::rng_for(opts.seed, "ga");
    let n = opts.population.max(opts.elite + opts.anti_elite + 2);
    let pm = if opts.mutation > 0.0 {
        opts.mutation
    } else {
        1.0 / bits.max(1) as f64
    };
    let (lo, hi) = (
        opts.min_ones.min(bits),
        opts.max_ones.min(bits).max(opts.min_ones.min(bits)),
    );
    let mut cache: HashMap<Vec<bool>, f64> = HashMap::new();
    let random = |rng: &mut rand::rngs::StdRng| {
        let mut c: Vec<bool> = (0..bits)
            .map(|_| rng.random::<f64>() < opts.density)
            .collect();
        repair(&mut c, lo, hi, rng);
        c
    };
    let mut pop: Vec<Vec<bool>> = (0..n).map(|_| random(&mut rng)).collect();
    let mut history = Vec::new();
    let mut best: (Vec<bool>, f64) = (Vec::new(), f64::INFINITY);
    let mut stalled = 0;
    let mut generations = 0;
    while generations < opts.max_generations {
        generations += 1;
        let scores = evaluate(&pop, &fitness, &mut cache);
        let mut order: Vec<usize> = (0..n).collect();
        order.sort_by(|&a, &b| scores[a].total_cmp(&scores[b]).then(a.cmp(&b)));
        if scores[order[0]] < best.1 {
            best = (pop[order[0]].clone(), scores[order[0]]);
            stalled = 0;
        } else {
            stalled += 1;
        }
        history.push(best.1);
        on_generation(generations, best.1);
        if stalled >= opts.stall {
            break;
        }
        let mut next: Vec<Vec<bool>> = order[..opts.elite]
            .iter()
            .map(|&i| pop[i].clone())
            .collect();
        while next.len() < n - opts.anti_elite {
            let a = tournament(&scores, opts.tournament, &mut rng);
            let b = tournament(&scores, opts.tournament, &mut rng);
            let mut child = Vec::with_capacity(bits);
            for (&va, &vb) in pop[a].iter().zip(&pop[b]) {
                let v = if rng.random::<f64>() < opts.crossover_bias {
                    va
                } else {
                    vb
                };
                child.push(if rng.random::<f64>() < pm { !v } else { v });
            }
            repair(&mut child, lo, hi, &mut rng);
            next.push(child);
        }
        while next.len() < n {
            next.push(random(&mut rng));
        }
        pop = next;
    }
    GaResult {
        best: best.0,
        fitness: best.1,
        history,
        evaluations: cache.len(),
        generations,
    }
}

/// Fitness of every chromosome, new ones evaluated in parallel.
fn evaluate<F: Fn(&[bool]) -> f64 + Sync>(
    pop: &[Vec<bool>],
    fitness: &F,
    cache: &mut HashMap<Vec<bool>, f64>,
) -> Vec<f64> {
    let mut todo: Vec<&Vec<bool>> = pop.iter().filter(|c| !cache.contains_key(*c)).collect();
    todo.sort();
    todo.dedup();
    let fresh: Vec<f64> = todo.par_iter().map(|c| fitness(c)).collect();
    for (c, f) in todo.into_iter().zip(fresh) {
        cache.insert(c.clone(), if f.is_nan() { f64::INFINITY } else { f });
    }
    pop.iter().map(|c| cache[c]).collect()
}

fn tournament(scores: &[f64], k: usize, rng: &mut impl rand::Rng) -> usize {
    let mut best = rng.random_range(0..scores.len());
    for _ in 1..k.max(1) {
        let c = rng.random_range(0..scores.len());
        if scores[c] < scores[best] || (scores[c] == scores[best] && c < best) {
            best = c;
        }
    }
    best
}

/// Flip random bits until the number of ones is within [lo, hi].
fn repair(c: &mut [bool], lo: usize, hi: usize, rng: &mut impl rand::Rng) {
    let mut ones = c.iter().filter(|b| **b).count();
    while ones > hi {
        let i = rng.random_range(0..c.len());
        if c[i] {
            c[i] = false;
            ones -= 1;
        }
    }
    while ones < lo {
        let i = rng.random_range(0..c.len());
        if !c[i] {
            c[i] = true;
            ones += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn finds_a_hidden_subset_respects_the_size_cap_and_is_deterministic() {
        let target: Vec<bool> = (0..40).map(|i| i % 7 == 0 || i == 11).collect();
        // misses and extras both cost; extras a little less
        let f = |c: &[bool]| {
            c.iter()
                .zip(&target)
                .map(|(a, b)| {
                    if a == b {
                        0.0
                    } else if *b {
                        1.0
                    } else {
                        0.7
                    }
                })
                .sum::<f64>()
        };
        let opts = GaOptions {
            max_generations: 200,
            stall: 40,
            max_ones: 10,
            ..GaOptions::default()
        };
        let mut gens = 0;
        let r = ga(40, f, &opts, |g, _| gens = g);
        assert_eq!(r.fitness, 0.0, "{r:?}");
        assert_eq!(r.best, target);
        assert_eq!(gens, r.generations);
        assert!(
            r.history.windows(2).all(|w| w[1] <= w[0]),
            "history must not get worse"
        );
        let r2 = ga(40, f, &opts, |_, _| {});
        assert_eq!(r, r2);
        // the cap binds: with max_ones = 3 no chromosome may carry the 7 target bits
        let capped = ga(
            40,
            f,
            &GaOptions {
                max_ones: 3,
                ..opts
            },
            |_, _| {},
        );
        assert!(capped.best.iter().filter(|b| **b).count() <= 3);
    }
}
