//! Running statistics: [`RunningMeanStd`] (Gymnasium's, which Python's recipe uses), the observation
//! normaliser [`ObsNorm`] and the reward scaling by the running std of the discounted return ([`RewardScale`]).

use serde::{Deserialize, Serialize};

/// The observation normaliser's clip (±10) and the ε under every square root (1e-8), as Python's.
pub const OBS_CLIP: f64 = 10.0;
/// The ε added to a variance before its square root.
pub const EPSILON: f64 = 1e-8;

/// Running mean and variance per element, with Chan et al.'s parallel update (Gymnasium's `RunningMeanStd`:
/// starts at mean 0, variance 1, count 1e-4; batch variances are population variances).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RunningMeanStd {
    /// The mean of each element.
    pub mean: Vec<f64>,
    /// The variance of each element.
    pub var: Vec<f64>,
    /// How many samples (plus the initial 1e-4).
    pub count: f64,
}

impl RunningMeanStd {
    /// Statistics of `dim` elements, before any sample.
    pub fn new(dim: usize) -> RunningMeanStd {
        RunningMeanStd { mean: vec![0.0; dim], var: vec![1.0; dim], count: 1e-4 }
    }

    /// Adds a batch of `rows` samples (`batch.len() == rows * dim`, row-major).
    pub fn update(&mut self, batch: &[f64], rows: usize) {
        let dim = self.mean.len();
        if rows == 0 {
            return;
        }
        debug_assert_eq!(batch.len(), rows * dim);
        let n = rows as f64;
        let mut bmean = vec![0.0; dim];
        for row in batch.chunks_exact(dim) {
            for (m, x) in bmean.iter_mut().zip(row) {
                *m += x;
            }
        }
        bmean.iter_mut().for_each(|m| *m /= n);
        let mut bvar = vec![0.0; dim];
        for row in batch.chunks_exact(dim) {
            for ((v, x), m) in bvar.iter_mut().zip(row).zip(&bmean) {
                *v += (x - m) * (x - m);
            }
        }
        bvar.iter_mut().for_each(|v| *v /= n);
        let total = self.count + n;
        for j in 0..dim {
            let delta = bmean[j] - self.mean[j];
            let m2 = self.var[j] * self.count + bvar[j] * n + delta * delta * self.count * n / total;
            self.mean[j] += delta * n / total;
            self.var[j] = m2 / total;
        }
        self.count = total;
    }
}

/// Observations standardised with running statistics and clipped to ±[`OBS_CLIP`] (Python's `ObsNormalizer`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct ObsNorm {
    /// The statistics.
    pub rms: RunningMeanStd,
    /// Off: observations pass unchanged (`norm_obs` false).
    pub enabled: bool,
}

impl ObsNorm {
    /// A normaliser of `dim`-element observations.
    pub fn new(dim: usize, enabled: bool) -> ObsNorm {
        ObsNorm { rms: RunningMeanStd::new(dim), enabled }
    }

    /// Writes the batch `raw` (`rows` observations) standardised into `out`, first adding it to the
    /// statistics when `update`.
    pub fn apply(&mut self, raw: &[f32], rows: usize, update: bool, out: &mut [f32]) {
        if !self.enabled {
            out.copy_from_slice(raw);
            return;
        }
        let wide: Vec<f64> = raw.iter().map(|&x| f64::from(x)).collect();
        if update {
            self.rms.update(&wide, rows);
        }
        let dim = self.rms.mean.len();
        for (i, (o, x)) in out.iter_mut().zip(&wide).enumerate() {
            let j = i % dim;
            let z = (x - self.rms.mean[j]) / (self.rms.var[j] + EPSILON).sqrt();
            *o = z.clamp(-OBS_CLIP, OBS_CLIP) as f32;
        }
    }
}

/// Rewards divided by the running std of each env's discounted return (Gymnasium's `NormalizeReward`, as
/// Python's loop does it with NEXT_STEP autoreset: reset steps neither add to the return nor to the statistics).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct RewardScale {
    /// The statistics of the discounted returns.
    pub rms: RunningMeanStd,
    /// Each env's discounted return so far.
    pub returns: Vec<f64>,
    /// Off: rewards pass unchanged (`norm_reward` false).
    pub enabled: bool,
}

impl RewardScale {
    /// Scaling for `num_envs` envs.
    pub fn new(num_envs: usize, enabled: bool) -> RewardScale {
        RewardScale { rms: RunningMeanStd::new(1), returns: vec![0.0; num_envs], enabled }
    }

    /// The scaled rewards of one step (`valid[i]`: env `i` stepped, not reset; `done[i]`: its episode ended);
    /// invalid steps give 0.
    pub fn scale(&mut self, gamma: f64, rewards: &[f32], valid: &[bool], done: &[bool]) -> Vec<f32> {
        let mut out: Vec<f64> = rewards.iter().map(|&r| f64::from(r)).collect();
        if self.enabled {
            let mut seen = Vec::new();
            for i in 0..out.len() {
                self.returns[i] = if valid[i] { self.returns[i] * gamma + out[i] } else { 0.0 };
                if valid[i] {
                    seen.push(self.returns[i]);
                }
            }
            let n = seen.len();
            self.rms.update(&seen, n);
            let std = (self.rms.var[0] + EPSILON).sqrt();
            out.iter_mut().for_each(|r| *r /= std);
            for (ret, _) in self.returns.iter_mut().zip(done).filter(|(_, d)| **d) {
                *ret = 0.0;
            }
        }
        out.iter().zip(valid).map(|(&r, &v)| if v { r as f32 } else { 0.0 }).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn running_statistics_by_hand() {
        let mut rms = RunningMeanStd::new(1);
        rms.update(&[1.0, 3.0], 2);
        // count 2.0001; delta 2; mean 2·2/2.0001; M2 = 1e-4 + 1·2 + 4·1e-4·2/2.0001.
        let total = 2.0001;
        assert!((rms.mean[0] - 4.0 / total).abs() < 1e-12);
        assert!((rms.var[0] - (1e-4 + 2.0 + 8e-4 / total) / total).abs() < 1e-12);
        assert_eq!(rms.count, total);
    }

    #[test]
    fn observations_are_standardised_and_clipped() {
        let mut norm = ObsNorm::new(2, true);
        norm.rms = RunningMeanStd { mean: vec![1.0, 0.0], var: vec![4.0, 1e-6], count: 10.0 };
        let mut out = [0.0; 2];
        norm.apply(&[3.0, 1.0], 1, false, &mut out);
        assert!((out[0] - (2.0 / (4.0f64 + 1e-8).sqrt()) as f32).abs() < 1e-7);
        assert_eq!(out[1], 10.0);
    }

    #[test]
    fn reset_steps_neither_scale_nor_count() {
        let mut s = RewardScale::new(2, true);
        let r = s.scale(0.5, &[1.0, 1.0], &[true, false], &[true, false]);
        assert_eq!(r[1], 0.0);
        // One return (1.0) seen: var = (1e-4·1 + 0 + 1·1e-4·1/1.0001) / 1.0001.
        let var = (1e-4 + 1e-4 / 1.0001) / 1.0001;
        assert!((r[0] - (1.0 / (var + EPSILON).sqrt()) as f32).abs() < 1e-3);
        assert_eq!(s.returns, vec![0.0, 0.0]);
    }
}
