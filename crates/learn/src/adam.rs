//! torch's Adam (β 0.9, 0.999; the recipe's ε 1e-5) and its gradient-norm clipping, on plain vectors: the state
//! is plain data, so a checkpoint holds it and `--resume` goes on exactly.

use serde::{Deserialize, Serialize};

/// Adam's state over a list of parameter tensors.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Adam {
    /// First moments, one vector per parameter tensor.
    pub m: Vec<Vec<f32>>,
    /// Second moments.
    pub v: Vec<Vec<f32>>,
    /// Steps taken.
    pub t: u64,
}

/// Adam's ε in the recipe (torch's default is 1e-8).
pub const ADAM_EPS: f32 = 1e-5;
const BETA1: f64 = 0.9;
const BETA2: f64 = 0.999;

impl Adam {
    /// Zero state for tensors of these sizes.
    pub fn new(sizes: &[usize]) -> Adam {
        Adam {
            m: sizes.iter().map(|&n| vec![0.0; n]).collect(),
            v: sizes.iter().map(|&n| vec![0.0; n]).collect(),
            t: 0,
        }
    }

    /// One step of `lr` on `params` with their gradients `grads` (torch's update, in `f32`).
    pub fn step(&mut self, params: &mut [Vec<f32>], grads: &[Vec<f32>], lr: f64) {
        self.t += 1;
        let bc1 = 1.0 - BETA1.powi(self.t as i32);
        let bc2_sqrt = (1.0 - BETA2.powi(self.t as i32)).sqrt() as f32;
        let step = (lr / bc1) as f32;
        let (b1, b2) = (BETA1 as f32, BETA2 as f32);
        for (((p, g), m), v) in params.iter_mut().zip(grads).zip(&mut self.m).zip(&mut self.v) {
            for j in 0..p.len() {
                m[j] = b1 * m[j] + (1.0 - b1) * g[j];
                v[j] = b2 * v[j] + (1.0 - b2) * g[j] * g[j];
                let denom = v[j].sqrt() / bc2_sqrt + ADAM_EPS;
                p[j] -= step * m[j] / denom;
            }
        }
    }
}

/// Scales `grads` so their global L2 norm is at most `max_norm` (torch's `clip_grad_norm_`: the factor
/// `max_norm / (norm + 1e-6)`, capped at 1); returns the norm before.
pub fn clip_grad_norm(grads: &mut [Vec<f32>], max_norm: f64) -> f64 {
    let norm = grads.iter().flatten().map(|&g| f64::from(g) * f64::from(g)).sum::<f64>().sqrt();
    let coef = (max_norm / (norm + 1e-6)).min(1.0) as f32;
    grads.iter_mut().flatten().for_each(|g| *g *= coef);
    norm
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_step_moves_each_weight_by_the_rate() {
        // After one step m̂ = g and v̂ = g², so the step is lr · g / (|g| + ε).
        let mut adam = Adam::new(&[2]);
        let mut p = vec![vec![1.0f32, 1.0]];
        adam.step(&mut p, &[vec![0.5, -2.0]], 0.1);
        assert!((p[0][0] - (1.0 - 0.1 * 0.5 / (0.5 + 1e-5))).abs() < 1e-6);
        assert!((p[0][1] - (1.0 + 0.1 * 2.0 / (2.0 + 1e-5))).abs() < 1e-6);
    }

    #[test]
    fn clipping_scales_to_the_norm() {
        let mut g = vec![vec![3.0f32], vec![4.0]];
        assert_eq!(clip_grad_norm(&mut g, 0.5), 5.0);
        assert!((g[0][0] - 0.3).abs() < 1e-6 && (g[1][0] - 0.4).abs() < 1e-6);
        let mut small = vec![vec![0.1f32]];
        clip_grad_norm(&mut small, 0.5);
        assert!((small[0][0] - 0.1).abs() < 1e-6);
    }
}
