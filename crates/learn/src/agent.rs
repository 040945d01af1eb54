//! The recipe's MLP agent (Python's `networks.Agent`): separate actor and critic networks, each two tanh layers of
//! `hidden` units, orthogonal weights (gain √2, then 0.01 for the actor's head and 1 for the critic's) and zero
//! biases. Weights are candle [`Var`]s stored `(inputs, outputs)`, so a layer is `x · W + b`.

use candle_core::{CpuStorage, CustomOp1, D, DType, Device, Layout, Result, Shape, Tensor, Var};
use chopperscape::Rng;

/// One dense layer.
#[derive(Debug)]
pub struct Dense {
    /// Weights, `(inputs, outputs)`.
    pub weight: Var,
    /// Biases, `(outputs,)`.
    pub bias: Var,
}

/// Three dense layers with tanh between them.
#[derive(Debug)]
pub struct Mlp {
    /// Input, hidden and output layers.
    pub layers: [Dense; 3],
}

/// The actor (action logits) and the critic (the value).
#[derive(Debug)]
pub struct Agent {
    /// Observation to the logits of the five actions.
    pub actor: Mlp,
    /// Observation to the value.
    pub critic: Mlp,
}

/// tanh through `expf`: glibc's scalar `tanhf` (through `expm1f`) was half the run's time; this one, in a loop
/// the compiler vectorises, is within 2e-7 of it. Below |x| = 0.004 it is `x − x³/3` (no cancellation).
#[inline]
pub fn tanh(x: f32) -> f32 {
    if x.abs() < 0.004 {
        return x - x * x * x / 3.0;
    }
    let e = (2.0 * x.clamp(-20.0, 20.0)).exp();
    (e - 1.0) / (e + 1.0)
}

/// [`tanh`] as a candle op, with its gradient `1 − tanh²`.
struct Tanh;

impl CustomOp1 for Tanh {
    fn name(&self) -> &'static str {
        "fast-tanh"
    }

    fn cpu_fwd(&self, storage: &CpuStorage, layout: &Layout) -> Result<(CpuStorage, Shape)> {
        let CpuStorage::F32(v) = storage else { candle_core::bail!("fast-tanh takes f32") };
        let out: Vec<f32> = match layout.contiguous_offsets() {
            Some((start, end)) => v[start..end].iter().map(|&x| tanh(x)).collect(),
            None => candle_core::bail!("fast-tanh takes contiguous tensors"),
        };
        Ok((CpuStorage::F32(out), layout.shape().clone()))
    }

    fn bwd(&self, _arg: &Tensor, res: &Tensor, grad_res: &Tensor) -> Result<Option<Tensor>> {
        Ok(Some(grad_res.mul(&(res.sqr()?.neg()? + 1.0)?)?))
    }
}

/// A standard normal draw (Box–Muller on two uniform draws).
pub fn normal(rng: &mut Rng) -> f64 {
    let u1 = 1.0 - rng.unit(); // (0, 1]
    let u2 = rng.unit();
    (-2.0 * u1.ln()).sqrt() * (std::f64::consts::TAU * u2).cos()
}

/// An orthogonal `(rows, cols)` matrix times `gain`, row-major (torch's `orthogonal_`: QR of a Gaussian matrix,
/// signs fixed so R's diagonal is positive, here by Gram–Schmidt, which gives that QR).
pub fn orthogonal(rows: usize, cols: usize, gain: f64, rng: &mut Rng) -> Vec<f32> {
    // Orthonormal vectors of length `long`, `short` of them.
    let (long, short) = (rows.max(cols), rows.min(cols));
    let mut q: Vec<Vec<f64>> = Vec::with_capacity(short);
    for _ in 0..short {
        let mut v: Vec<f64> = (0..long).map(|_| normal(rng)).collect();
        for _ in 0..2 {
            for u in &q {
                let dot: f64 = v.iter().zip(u).map(|(a, b)| a * b).sum();
                v.iter_mut().zip(u).for_each(|(a, b)| *a -= dot * b);
            }
        }
        let norm = v.iter().map(|a| a * a).sum::<f64>().sqrt();
        v.iter_mut().for_each(|a| *a /= norm);
        q.push(v);
    }
    let mut out = vec![0.0f32; rows * cols];
    for r in 0..rows {
        for c in 0..cols {
            // Orthonormal columns when rows ≥ cols, orthonormal rows otherwise.
            let x = if rows >= cols { q[c][r] } else { q[r][c] };
            out[r * cols + c] = (x * gain) as f32;
        }
    }
    out
}

impl Dense {
    /// A layer of `inputs` → `outputs`, orthogonal weights of `gain`, zero biases.
    ///
    /// # Errors
    /// Candle's, never in practice.
    pub fn new(inputs: usize, outputs: usize, gain: f64, rng: &mut Rng) -> Result<Dense> {
        // torch's weight is (outputs, inputs); ours is its transpose.
        let w = orthogonal(outputs, inputs, gain, rng);
        let mut t = vec![0.0f32; w.len()];
        for o in 0..outputs {
            for i in 0..inputs {
                t[i * outputs + o] = w[o * inputs + i];
            }
        }
        Ok(Dense {
            weight: Var::from_vec(t, (inputs, outputs), &Device::Cpu)?,
            bias: Var::zeros(outputs, DType::F32, &Device::Cpu)?,
        })
    }

    fn forward(&self, x: &Tensor, detach: bool) -> Result<Tensor> {
        let (w, b) = (self.weight.as_tensor(), self.bias.as_tensor());
        if detach { x.matmul(&w.detach())?.broadcast_add(&b.detach()) } else { x.matmul(w)?.broadcast_add(b) }
    }
}

impl Mlp {
    /// `inputs` → `hidden` → `hidden` → `outputs`, the last layer's gain `head_gain`.
    ///
    /// # Errors
    /// Candle's, never in practice.
    pub fn new(inputs: usize, hidden: usize, outputs: usize, head_gain: f64, rng: &mut Rng) -> Result<Mlp> {
        let gain = std::f64::consts::SQRT_2;
        Ok(Mlp {
            layers: [
                Dense::new(inputs, hidden, gain, rng)?,
                Dense::new(hidden, hidden, gain, rng)?,
                Dense::new(hidden, outputs, head_gain, rng)?,
            ],
        })
    }

    /// The output for a batch `x` `(n, inputs)`; `detach`: no gradient is tracked (the rollout).
    ///
    /// # Errors
    /// Candle's: `x` of the wrong width.
    pub fn forward(&self, x: &Tensor, detach: bool) -> Result<Tensor> {
        let h = self.layers[0].forward(x, detach)?.apply_op1(Tanh)?;
        let h = self.layers[1].forward(&h, detach)?.apply_op1(Tanh)?;
        self.layers[2].forward(&h, detach)
    }

    /// The weights and biases in a fixed order (layer by layer, weight then bias).
    pub fn vars(&self) -> Vec<&Var> {
        self.layers.iter().flat_map(|l| [&l.weight, &l.bias]).collect()
    }
}

impl Agent {
    /// The agent for `obs_dim` features and `actions` actions, initialised from `rng` (actor first).
    ///
    /// # Errors
    /// Candle's, never in practice.
    pub fn new(obs_dim: usize, actions: usize, hidden: usize, rng: &mut Rng) -> Result<Agent> {
        let critic = Mlp::new(obs_dim, hidden, 1, 1.0, rng)?;
        let actor = Mlp::new(obs_dim, hidden, actions, 0.01, rng)?;
        Ok(Agent { actor, critic })
    }

    /// Every parameter (actor's, then critic's), the order of the optimiser's state and of checkpoints.
    pub fn vars(&self) -> Vec<&Var> {
        let mut v = self.actor.vars();
        v.extend(self.critic.vars());
        v
    }

    /// Logits `(n, actions)` and values `(n,)` of a batch.
    ///
    /// # Errors
    /// Candle's: `x` of the wrong width.
    pub fn heads(&self, x: &Tensor, detach: bool) -> Result<(Tensor, Tensor)> {
        Ok((self.actor.forward(x, detach)?, self.critic.forward(x, detach)?.squeeze(D::Minus1)?))
    }

    /// Every parameter's values, flattened, in [`Agent::vars`]' order.
    ///
    /// # Errors
    /// Candle's, never in practice.
    pub fn params(&self) -> Result<Vec<Vec<f32>>> {
        self.vars().iter().map(|v| v.as_tensor().flatten_all()?.to_vec1()).collect()
    }

    /// Sets every parameter from [`Agent::params`]' form.
    ///
    /// # Errors
    /// A list of the wrong count or sizes.
    pub fn set_params(&self, params: &[Vec<f32>]) -> Result<()> {
        let vars = self.vars();
        if vars.len() != params.len() {
            candle_core::bail!("{} parameter tensors where the agent has {}", params.len(), vars.len());
        }
        for (v, p) in vars.iter().zip(params) {
            if v.elem_count() != p.len() {
                candle_core::bail!("a parameter of {} values where the agent has {}", p.len(), v.elem_count());
            }
            v.set(&Tensor::from_slice(p, v.shape(), &Device::Cpu)?)?;
        }
        Ok(())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tanh_is_libms() {
        for i in -4000..4000 {
            let x = i as f32 * 0.0037;
            assert!((tanh(x) - x.tanh()).abs() < 3e-7, "{x}: {} != {}", tanh(x), x.tanh());
        }
        assert_eq!((tanh(50.0), tanh(-50.0)), (1.0, -1.0));
    }

    #[test]
    fn orthogonal_matrices_are_orthogonal() {
        let mut rng = Rng::seed_from_u64(1);
        for (rows, cols) in [(5, 8), (8, 5), (6, 6)] {
            let m = orthogonal(rows, cols, 2.0, &mut rng);
            // M Mᵀ = 4 I (rows ≤ cols) or Mᵀ M = 4 I (rows ≥ cols).
            let (n, k) = if rows <= cols { (rows, cols) } else { (cols, rows) };
            for a in 0..n {
                for b in 0..n {
                    let dot: f64 = (0..k)
                        .map(|j| {
                            let at = |x: usize, y: usize| if rows <= cols { m[x * cols + y] } else { m[y * cols + x] };
                            f64::from(at(a, j)) * f64::from(at(b, j))
                        })
                        .sum();
                    let want = if a == b { 4.0 } else { 0.0 };
                    assert!((dot - want).abs() < 1e-5, "{rows}x{cols}: ({a},{b}) = {dot}");
                }
            }
        }
    }
}
