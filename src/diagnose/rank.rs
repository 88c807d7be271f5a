//! How a round orders its candidates: significant ones first, kinds not
//! yet in the model before more of a kind already added, each by evidence
//! ([`rank`]); of candidates that explain the same, the one with fewer
//! model columns first ([`prefer_simpler`], Occam's rule); and the
//! candidates one explains the same as ([`alike`]; the wider "not
//! separable" measure is [`super::confound`]'s).
//!
//! Two candidates explain the same when their least-squares fits to the
//! centred CV residuals ([`fitted`]: the projection on an orthonormal basis
//! of their centred columns) have cosine similarity ([`similarity`]) of at
//! least [`SAME_FIT`], pooled over the axes, and the other's score is at
//! least [`SAME_SCORE`] of the first's.

use super::scan::{self, GridPoint, Tested};

/// Significant candidates first: kinds of effect not in the model yet
/// (`seen` false) before more of a kind already added (so that a cap of a
/// few effects is not spent on harmonic after harmonic while a drift the
/// data shows clearly waits), each by evidence (what the data shows most
/// clearly, not the largest share of a large misfit); the others by score.
pub(super) fn rank(
    tested: &mut [Tested],
    significant: &dyn Fn(&Tested) -> bool,
    seen: &dyn Fn(&Tested) -> bool,
) {
    tested.sort_by(|a, b| match (significant(a), significant(b)) {
        (true, false) => std::cmp::Ordering::Less,
        (false, true) => std::cmp::Ordering::Greater,
        (true, true) => seen(a)
            .cmp(&seen(b))
            .then(b.evidence.total_cmp(&a.evidence))
            .then(b.score.total_cmp(&a.score)),
        (false, false) => b
            .score
            .total_cmp(&a.score)
            .then(a.p_value.total_cmp(&b.p_value)),
    });
}

/// The significant candidates of `tested` other than `k` that explain what
/// `k` explains: a score at least [`SAME_SCORE`] of its, and a fitted
/// component of the residuals within cosine [`SAME_FIT`] of its.
pub(super) fn alike(
    tested: &[scan::Tested],
    fams: &[scan::Family],
    residuals: &[[f64; 3]],
    k: usize,
    significant: &dyn Fn(&scan::Tested) -> bool,
) -> Vec<usize> {
    let fit = |t: &scan::Tested| fitted(t.point(&fams[t.family]), residuals);
    let top = fit(&tested[k]);
    (0..tested.len())
        .filter(|&i| {
            i != k && significant(&tested[i]) && tested[i].score >= SAME_SCORE * tested[k].score
        })
        .filter(|&i| similarity(&top, &fit(&tested[i])) >= SAME_FIT)
        .collect()
}

/// Occam's rule for the first candidate of `tested` (in its ranked order):
/// of the candidates [`alike`] it, one that adds fewer model columns (its
/// features' names) goes first — a temperature drift is "temp_c", one
/// input, not "temp_c × one joint angle", whose three trend columns happen
/// to carry it as well. Returns the new first's index and the label it
/// overtook.
pub(super) fn prefer_simpler(
    tested: &mut Vec<scan::Tested>,
    fams: &[scan::Family],
    residuals: &[[f64; 3]],
    significant: &dyn Fn(&scan::Tested) -> bool,
) -> Option<(usize, String)> {
    let size = |t: &scan::Tested| -> usize {
        t.point(&fams[t.family])
            .add
            .iter()
            .map(|f| f.names().len())
            .sum()
    };
    let first = tested
        .iter()
        .position(|t| significant(t) && t.score > 0.0)?;
    let simpler = alike(tested, fams, residuals, first, significant)
        .into_iter()
        .filter(|&i| size(&tested[i]) < size(&tested[first]))
        .min_by_key(|&i| (size(&tested[i]), i))?;
    let over = fams[tested[first].family].label.clone();
    let t = tested.remove(simpler);
    tested.insert(first, t);
    Some((first, over))
}

/// Cosine similarity of fitted components above which two candidates
/// explain the same.
const SAME_FIT: f64 = 0.9;
/// Share of the first candidate's score a simpler one needs to go first.
const SAME_SCORE: f64 = 0.8;

/// Orthonormal basis (modified Gram–Schmidt, twice) of centred columns;
/// dependent columns are dropped (the intercept is implied).
pub(super) fn orthonormal<C: AsRef<[f64]>>(columns: &[C]) -> Vec<Vec<f64>> {
    extend_orthonormal(Vec::new(), columns)
}

/// `basis` (orthonormal, centred) extended by the columns' centred parts
/// orthogonal to it, as [`orthonormal`] does column by column: the
/// vectors after `basis.len()` span what the columns add to it.
pub(super) fn extend_orthonormal<C: AsRef<[f64]>>(
    mut basis: Vec<Vec<f64>>,
    columns: &[C],
) -> Vec<Vec<f64>> {
    for c in columns {
        let c = c.as_ref();
        let mu = c.iter().sum::<f64>() / c.len() as f64;
        let mut v: Vec<f64> = c.iter().map(|x| x - mu).collect();
        let n0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        for _ in 0..2 {
            for b in &basis {
                let d: f64 = v.iter().zip(b).map(|(x, y)| x * y).sum();
                v.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
            }
        }
        let nv = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if n0 > 0.0 && nv > 1e-8 * n0 {
            v.iter_mut().for_each(|x| *x /= nv);
            basis.push(v);
        }
    }
    basis
}

/// The least-squares fit of the centred residuals of each axis on the
/// centred columns of `point` that are regressors of that axis
/// ([`GridPoint::on_axis`]) (m × 3), for comparing what two candidates
/// explain.
pub fn fitted(point: &GridPoint, resid: &[[f64; 3]]) -> Vec<[f64; 3]> {
    let m = resid.len();
    let mean: [f64; 3] =
        std::array::from_fn(|a| resid.iter().map(|r| r[a]).sum::<f64>() / m as f64);
    let mut out = vec![[0.0; 3]; m];
    for a in 0..3 {
        for b in orthonormal(&point.on_axis(a)) {
            let d: f64 = b.iter().zip(resid).map(|(x, r)| x * (r[a] - mean[a])).sum();
            for (o, x) in out.iter_mut().zip(&b) {
                o[a] += d * x;
            }
        }
    }
    out
}

/// Cosine similarity of two fitted components (pooled over the axes).
pub fn similarity(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    let dot = |u: &[[f64; 3]], v: &[[f64; 3]]| -> f64 {
        u.iter()
            .zip(v)
            .map(|(x, y)| x[0] * y[0] + x[1] * y[1] + x[2] * y[2])
            .sum()
    };
    let d = (dot(a, a) * dot(b, b)).sqrt();
    if d > 0.0 { dot(a, b) / d } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::diagnose::EffectKind;
    use crate::features::Feature;
    use scan::{Family, GridPoint};
    use std::collections::BTreeMap;

    fn family(label: &str, columns: Vec<Vec<f64>>, add: Vec<Feature>) -> Family {
        Family {
            kind: EffectKind::Covariate,
            source: vec!["t".into()],
            label: label.into(),
            grid: vec![GridPoint::new(BTreeMap::new(), columns, add)],
            zoom: None,
        }
    }

    /// Occam's rule: of two significant candidates that explain the same
    /// residual, the one with fewer model columns goes first; one that
    /// explains something else, or is not significant, does not.
    #[test]
    fn a_simpler_candidate_that_explains_the_same_is_ranked_first() {
        let m = 40;
        let t: Vec<f64> = (0..m).map(|i| i as f64 / m as f64).collect();
        let wiggle: Vec<f64> = (0..m).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
        let resid: Vec<[f64; 3]> = t.iter().map(|v| [*v, -*v, 0.5 * v]).collect();
        let cov = |name: &str| Feature::Covariate {
            name: name.into(),
            reference: None,
        };
        let fams = vec![
            // three columns (the drift among them) against one
            family(
                "t × joint angles",
                vec![t.clone(), t.iter().map(|v| v * v).collect(), wiggle.clone()],
                vec![cov("a"), cov("b"), cov("c")],
            ),
            family("t (alone)", vec![t.clone()], vec![cov("t")]),
            family("something else", vec![wiggle], vec![cov("w")]),
        ];
        let all = |_: &Tested| true;
        let mut order = vec![Tested::for_test(0, 0.90), Tested::for_test(1, 0.85)];
        let moved = prefer_simpler(&mut order, &fams, &resid, &all);
        assert_eq!(moved, Some((0, "t × joint angles".to_string())));
        assert_eq!(order[0].family, 1);
        // not significant: it stays where it is
        let mut order = vec![Tested::for_test(0, 0.90), Tested::for_test(1, 0.85)];
        let only_first = |x: &Tested| x.family == 0;
        assert_eq!(prefer_simpler(&mut order, &fams, &resid, &only_first), None);
        assert_eq!(order[0].family, 0);
        // fewer columns, but it explains another part of the residual
        let mut order = vec![Tested::for_test(0, 0.90), Tested::for_test(2, 0.85)];
        assert_eq!(prefer_simpler(&mut order, &fams, &resid, &all), None);
        // too weak a score to stand in for the first
        let mut order = vec![Tested::for_test(0, 0.90), Tested::for_test(1, 0.50)];
        assert_eq!(prefer_simpler(&mut order, &fams, &resid, &all), None);
    }
}
