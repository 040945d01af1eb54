"""Measures how much of SB3 PPO's clipped update reaches the policy, with raw and with normalised rewards.

    python python/examples/grad_share.py

For each setting it collects one rollout (8 envs × 2048 steps, SB3's defaults, `obs_type="features"`), then takes a
minibatch of 64 and prints the gradient norms of the policy loss and of the value loss, and the factor by which
`max_grad_norm = 0.5` scales their sum. Used in docs/notes/value-scale.md.
"""

import torch
from stable_baselines3 import PPO
from stable_baselines3.common.vec_env import VecNormalize

from chopperscape.integrations.sb3 import ChopperScapeVecEnv

torch.set_num_threads(1)
for normalised in (False, True):
    env = ChopperScapeVecEnv(8, seed=0, obs_type="features")
    if normalised:
        env = VecNormalize(env, gamma=0.99)
    model = PPO("MlpPolicy", env, seed=0, device="cpu")
    model.learn(model.n_steps * env.num_envs)
    data = next(model.rollout_buffer.get(64))
    policy = model.policy
    values, log_prob, _ = policy.evaluate_actions(data.observations, data.actions.long().flatten())
    adv = (data.advantages - data.advantages.mean()) / (data.advantages.std() + 1e-8)
    ratio = torch.exp(log_prob - data.old_log_prob)
    policy_loss = -torch.min(adv * ratio, adv * ratio.clamp(0.8, 1.2)).mean()
    value_loss = model.vf_coef * torch.nn.functional.mse_loss(data.returns, values.flatten())

    def grad_norm(loss: torch.Tensor, policy: torch.nn.Module = policy) -> float:
        policy.zero_grad()
        loss.backward(retain_graph=True)
        return torch.sqrt(sum((p.grad**2).sum() for p in policy.parameters() if p.grad is not None)).item()

    g_policy, g_value, g_total = grad_norm(policy_loss), grad_norm(value_loss), grad_norm(policy_loss + value_loss)
    scale = min(1.0, model.max_grad_norm / g_total)
    print(
        f"rewards {'normalised' if normalised else 'raw':>10}: mean return target {data.returns.mean():8.2f}, "
        f"|grad policy| {g_policy:.3f}, |grad value| {g_value:9.3f}, clip factor {scale:.4f}, "
        f"policy step {g_policy * scale:.4f}"
    )
