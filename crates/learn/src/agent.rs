//! The recipe's MLP agent (Python's `networks.Agent`): separate actor and critic networks, each two tanh layers of
//! `hidden` units, orthogonal weights (gain √2, then 0.01 for the actor's head and 1 for the critic's) and zero
//! biases. Weights are candle [`Var`]s stored `(inputs, outputs)`, so a layer is `x · W + b`.

use candle_core::{CpuStorage, CustomOp1, CustomOp2, D, DType, Device, Layout, Result, Shape, Tensor, Var};
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

/// `eˣ` for `x` in [−40, 40], without a call into libm, so that a loop over a slice of it vectorises:
/// `eˣ = 2ᵏ · eʳ`, `k = round(x / ln 2)` (rounded by adding 1.5 · 2²³, and read from those bits), `r = x − k · ln 2` in two parts (Cody–Waite),
/// `eʳ` by its Taylor series to `r⁷` (|r| ≤ 0.35: relative error below 1e-8 before rounding), `2ᵏ` from its bits.
#[inline]
pub fn exp(x: f32) -> f32 {
    const ROUND: f32 = 12_582_912.0; // 1.5 · 2²³
    const LN2_HI: f32 = 0.693_145_75;
    const LN2_LO: f32 = 1.428_606_8e-6;
    let t = x * std::f32::consts::LOG2_E + ROUND;
    let k = t - ROUND;
    // k as an integer from t's low mantissa bits (not `k as i32`, whose saturating conversion does not vectorise).
    let ki = t.to_bits() as i32 - ROUND.to_bits() as i32;
    let r = x - k * LN2_HI - k * LN2_LO;
    let p = 1.0
        + r * (1.0
            + r * (1.0 / 2.0
                + r * (1.0 / 6.0 + r * (1.0 / 24.0 + r * (1.0 / 120.0 + r * (1.0 / 720.0 + r * (1.0 / 5040.0)))))));
    p * f32::from_bits(((ki + 127) as u32) << 23)
}

/// tanh through [`exp`], branch-free so that a loop over a slice vectorises (libm's scalar `tanhf`, then a scalar
/// `expf` per value, were a quarter of a run's time); within 3e-7 of libm's. Below |x| = 0.004 it is `x − x³/3`
/// (no cancellation).
#[inline]
pub fn tanh(x: f32) -> f32 {
    let e = exp(2.0 * x.clamp(-20.0, 20.0));
    let big = (e - 1.0) / (e + 1.0);
    let small = x - x * x * x / 3.0;
    if x.abs() < 0.004 { small } else { big }
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
        Ok(Some(res.contiguous()?.apply_op2_no_bwd(&grad_res.contiguous()?, &TanhGrad)?))
    }
}

/// tanh's gradient, `g · (1 − t²)` of the output `t` and the output's gradient `g`, in one pass (four candle ops,
/// each allocating its own output, before).
struct TanhGrad;

impl CustomOp2 for TanhGrad {
    fn name(&self) -> &'static str {
        "fast-tanh-grad"
    }

    fn cpu_fwd(&self, s1: &CpuStorage, l1: &Layout, s2: &CpuStorage, l2: &Layout) -> Result<(CpuStorage, Shape)> {
        let (CpuStorage::F32(t), CpuStorage::F32(g)) = (s1, s2) else { candle_core::bail!("fast-tanh-grad takes f32") };
        let (Some((a, b)), Some((c, d))) = (l1.contiguous_offsets(), l2.contiguous_offsets()) else {
            candle_core::bail!("fast-tanh-grad takes contiguous tensors")
        };
        if l1.shape() != l2.shape() {
            candle_core::bail!("fast-tanh-grad: shapes {:?} and {:?}", l1.shape(), l2.shape());
        }
        let out: Vec<f32> = t[a..b].iter().zip(&g[c..d]).map(|(&t, &g)| g * (1.0 - t * t)).collect();
        Ok((CpuStorage::F32(out), l1.shape().clone()))
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

    /// `x · W + b`. With gradients, the bias is added as `1 · bᵀ` (a column of ones times the bias row), whose
    /// gradient is one matrix product: candle's gradient of a broadcast add sums over the batch with a generic
    /// strided reduction, which was a sixth of a run's time.
    fn forward(&self, x: &Tensor, detach: bool) -> Result<Tensor> {
        let (w, b) = (self.weight.as_tensor(), self.bias.as_tensor());
        if detach {
            return x.matmul(&w.detach())?.broadcast_add(&b.detach());
        }
        let ones = Tensor::ones((x.dim(0)?, 1), DType::F32, x.device())?;
        x.matmul(w)? + ones.matmul(&b.unsqueeze(0)?)?
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
    fn exp_is_libms() {
        for i in -40_000..40_000 {
            let x = i as f32 * 0.001;
            let (ours, libm) = (exp(x), x.exp());
            assert!(((ours - libm) / libm).abs() < 4e-7, "{x}: {ours} != {libm}");
        }
    }

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
