//! Generalised advantage estimation over a rollout stored time-major (`[t][env]`), as Python's loop computes it
//! with NEXT_STEP autoreset: the step after an episode's end (its reset step) neither bootstraps nor is learned
//! from, and truncation counts as termination.

/// Advantages and returns (`advantage + value`) of a rollout of `num_steps` × `num_envs` steps, in `f32` as torch
/// computes them. `done[t][i]`: step `t` of env `i` ended its episode; `valid[t][i]`: it was a real step, not a
/// reset step; `next_value[i]`: the value of the observation after the last step.
#[allow(clippy::too_many_arguments)]
pub fn gae(
    num_envs: usize,
    rewards: &[f32],
    values: &[f32],
    done: &[bool],
    valid: &[bool],
    next_value: &[f32],
    gamma: f32,
    lambda: f32,
) -> (Vec<f32>, Vec<f32>) {
    let len = rewards.len();
    let steps = len / num_envs;
    let mut adv = vec![0.0f32; len];
    let mut last = vec![0.0f32; num_envs];
    for t in (0..steps).rev() {
        for i in 0..num_envs {
            let k = t * num_envs + i;
            let nv = if t + 1 == steps { next_value[i] } else { values[k + num_envs] };
            let nonterminal = if done[k] { 0.0 } else { 1.0 };
            let delta = rewards[k] + gamma * nv * nonterminal - values[k];
            let mut l = delta + gamma * lambda * nonterminal * last[i];
            if !valid[k] {
                l = 0.0;
            }
            last[i] = l;
            adv[k] = l;
        }
    }
    let returns = adv.iter().zip(values).map(|(a, v)| a + v).collect();
    (adv, returns)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn by_hand_one_env() {
        // Three steps; the second ends the episode; the next value bootstraps only the third.
        let (adv, ret) =
            gae(1, &[1.0, 2.0, 3.0], &[0.5, 0.25, 1.0], &[false, true, false], &[true; 3], &[2.0], 0.5, 0.5);
        let d2 = 3.0 + 0.5 * 2.0 - 1.0; // 3
        let d1 = 2.0 - 0.25; // done: no bootstrap, no carry
        let d0 = 1.0 + 0.5 * 0.25 - 0.5;
        let expected = [d0 + 0.25 * d1, d1, d2];
        for (a, e) in adv.iter().zip(expected) {
            assert!((a - e).abs() < 1e-6, "{adv:?} != {expected:?}");
        }
        assert!((ret[2] - 4.0).abs() < 1e-6);
    }

    #[test]
    fn a_reset_step_carries_nothing() {
        // Env 0's step 1 is a reset step: its advantage is 0 and step 0 does not see it.
        let (adv, _) = gae(1, &[1.0, 0.0], &[0.0, 5.0], &[true, false], &[true, false], &[9.0], 0.9, 0.9);
        assert_eq!(adv, vec![1.0, 0.0]);
    }
}
