//! PPO's loss on one minibatch, as Python's loop writes it: advantages standardised over the minibatch
//! (unbiased std + 1e-8), the clipped surrogate, half the squared value error (no value clipping), the policy's
//! entropy; and the update's diagnostics (approximate KL `(ratio − 1) − log ratio`, clip fraction).

use candle_core::{D, Device, Result, Tensor};

/// A minibatch's loss and its parts.
#[derive(Debug)]
pub struct Loss {
    /// `policy − ent_coef · entropy + vf_coef · value`, what is differentiated.
    pub total: Tensor,
    /// The clipped surrogate (a scalar).
    pub policy: f32,
    /// Half the mean squared value error.
    pub value: f32,
    /// The mean entropy of the policy.
    pub entropy: f32,
    /// Schulman's low-variance estimate of KL(old ‖ new).
    pub approx_kl: f32,
    /// The share of samples whose ratio left `1 ± clip`.
    pub clip_frac: f32,
}

/// The minibatch's samples, beside the network's outputs.
#[derive(Debug)]
pub struct Batch<'a> {
    /// The action taken in each sample.
    pub actions: &'a [u32],
    /// Its log-probability when it was taken.
    pub old_logp: &'a [f32],
    /// Its advantage (standardised here).
    pub advantages: &'a [f32],
    /// Its return (the value target).
    pub returns: &'a [f32],
}

/// `(x − mean) / (std + 1e-8)` with the unbiased std, as torch's `a.std()`.
pub fn standardise(x: &[f32]) -> Vec<f32> {
    let n = x.len() as f64;
    let mean = x.iter().map(|&a| f64::from(a)).sum::<f64>() / n;
    let var = x.iter().map(|&a| (f64::from(a) - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    let std = var.sqrt() + 1e-8;
    x.iter().map(|&a| ((f64::from(a) - mean) / std) as f32).collect()
}

/// Log-softmax over the last axis (the max held constant, as torch's own gradient has it).
///
/// # Errors
/// Candle's.
pub fn log_softmax(logits: &Tensor) -> Result<Tensor> {
    let z = logits.broadcast_sub(&logits.max_keepdim(D::Minus1)?.detach())?;
    z.broadcast_sub(&z.exp()?.sum_keepdim(D::Minus1)?.log()?)
}

/// The loss of `logits` `(n, actions)` and `values` `(n,)` on `batch`.
///
/// # Errors
/// Candle's: shapes that do not match.
pub fn ppo_loss(
    logits: &Tensor,
    values: &Tensor,
    batch: &Batch<'_>,
    clip: f64,
    ent_coef: f64,
    vf_coef: f64,
) -> Result<Loss> {
    let (n, actions) = logits.dims2()?;
    let dev = &Device::Cpu;
    let mut onehot = vec![0.0f32; n * actions];
    for (i, &a) in batch.actions.iter().enumerate() {
        onehot[i * actions + a as usize] = 1.0;
    }
    let logp_all = log_softmax(logits)?;
    let logp = (&logp_all * Tensor::from_vec(onehot, (n, actions), dev)?)?.sum(D::Minus1)?;
    let entropy = (logp_all.exp()? * &logp_all)?.sum(D::Minus1)?.neg()?.mean_all()?;
    let log_ratio = (logp - Tensor::from_slice(batch.old_logp, n, dev)?)?;
    let ratio = log_ratio.exp()?;
    let adv = Tensor::from_vec(standardise(batch.advantages), n, dev)?;
    let surrogate = (adv.neg()? * &ratio)?;
    let clipped = (adv.neg()? * ratio.clamp((1.0 - clip) as f32, (1.0 + clip) as f32)?)?;
    let policy = surrogate.maximum(&clipped)?.mean_all()?;
    let value = ((values - Tensor::from_slice(batch.returns, n, dev)?)?.sqr()?.mean_all()? * 0.5)?;
    let total = ((&policy - (&entropy * ent_coef)?)? + (&value * vf_coef)?)?;
    let (r, lr): (Vec<f32>, Vec<f32>) = (ratio.to_vec1()?, log_ratio.to_vec1()?);
    let approx_kl = r.iter().zip(&lr).map(|(r, l)| f64::from(r - 1.0 - l)).sum::<f64>() / n as f64;
    let clip_frac = r.iter().filter(|&&r| f64::from((r - 1.0).abs()) > clip).count() as f64 / n as f64;
    Ok(Loss {
        policy: policy.to_scalar()?,
        value: value.to_scalar()?,
        entropy: entropy.to_scalar()?,
        approx_kl: approx_kl as f32,
        clip_frac: clip_frac as f32,
        total,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn by_hand_two_samples() {
        // Uniform logits over 5 actions: logp = −ln 5, entropy ln 5; old logp equal, so ratio 1 and the
        // surrogate is −mean(standardised advantages) = 0.
        let dev = &Device::Cpu;
        let logits = Tensor::zeros((2, 5), candle_core::DType::F32, dev).unwrap();
        let values = Tensor::from_slice(&[1.0f32, 2.0], 2, dev).unwrap();
        let l5 = -(5f32.ln());
        let batch = Batch { actions: &[0, 3], old_logp: &[l5, l5], advantages: &[1.0, 3.0], returns: &[2.0, 2.0] };
        let loss = ppo_loss(&logits, &values, &batch, 0.2, 0.01, 0.5).unwrap();
        assert!(loss.policy.abs() < 1e-6);
        assert!((loss.value - 0.25).abs() < 1e-6); // 0.5 · mean(1, 0)
        assert!((loss.entropy - 5f32.ln()).abs() < 1e-6);
        assert!(loss.approx_kl.abs() < 1e-6 && loss.clip_frac == 0.0);
        let total: f32 = loss.total.to_scalar().unwrap();
        assert!((total - (-0.01 * 5f32.ln() + 0.125)).abs() < 1e-6);
        assert_eq!(
            standardise(&[1.0, 3.0]),
            vec![(-1.0f64 / (2f64.sqrt() + 1e-8)) as f32, (1.0 / (2f64.sqrt() + 1e-8)) as f32]
        );
    }
}
