//! Joint space and extended joint space.
//!
//! The direction coefficient of seed 003 eq 5: `λi = +1` for forward motion,
//! `−1` for backward motion of joint i into the pose. For a visited sequence
//! `θ(k)` (DESIGN.md §3):
//!
//! `λi(k) = sign(θi(k) − θi(k−1))`; a joint that did not move keeps its
//! previous λ; the first pose's λ comes from the start pose (and is +1 where the
//! joint did not move from it, or when no start pose is known).

/// Joint moves smaller than this (degrees or mm) count as "did not move".
pub const MOVE_EPS: f64 = 1e-9;

/// Direction coefficients (±1) for a sequence of joint vectors visited in order.
///
/// `start` is the pose the robot came from before `q[0]`; `None` means unknown,
/// in which case the first pose gets +1 on every joint (the convention of the
/// public UR10 data set). Rows of `q` must all have the same length.
pub fn derive_directions(q: &[Vec<f64>], start: Option<&[f64]>) -> Vec<Vec<f64>> {
    let n = q.first().map_or(0, Vec::len);
    let mut prev_dir = vec![1.0; n];
    let mut prev_q: Option<&[f64]> = start;
    let mut out = Vec::with_capacity(q.len());
    for row in q {
        let mut dir = prev_dir.clone();
        if let Some(p) = prev_q {
            for i in 0..n {
                let step = row[i] - p[i];
                if step > MOVE_EPS {
                    dir[i] = 1.0;
                } else if step < -MOVE_EPS {
                    dir[i] = -1.0;
                }
            }
        }
        prev_q = Some(row);
        prev_dir.clone_from(&dir);
        out.push(dir);
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn directions_follow_sign_of_motion_and_hold_when_still() {
        let q = vec![
            vec![0.0, 5.0],
            vec![1.0, 5.0],
            vec![0.5, 5.0],
            vec![0.5, 6.0],
        ];
        let d = derive_directions(&q, Some(&[1.0, 5.0]));
        assert_eq!(d[0], vec![-1.0, 1.0]);
        assert_eq!(d[1], vec![1.0, 1.0]);
        assert_eq!(d[2], vec![-1.0, 1.0]);
        assert_eq!(d[3], vec![-1.0, 1.0]);
        let d = derive_directions(&q, None);
        assert_eq!(d[0], vec![1.0, 1.0]);
    }
}
