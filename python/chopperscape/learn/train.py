"""PPO for ChopperScape: the training loop and its command line (CleanRL-style sections, PyTorch).

Run it with ``python -m chopperscape.learn.train --steps 15000000 --out runs/ppo`` once the package and torch are
installed. It steps the native :class:`chopperscape.VectorEnv` (one Rust call per batch), normalises observations with
running statistics and rewards by the running standard deviation of the discounted return (the two things that made
the difference: see ``docs/learning.md``), and writes as it goes:

- ``OUT/progress.csv``: one row per update (the schema: :mod:`chopperscape.learn.progress`, the format
  ``python -m chopperscape.learn.plot`` draws): the return and length of the last 100 finished episodes (empty until
  one has ended), the update's diagnostics (learning rate,
  policy entropy, approximate KL, clip fraction, explained variance, value and policy losses) and how the episodes
  that ended during the update ended (shares of ``bird``, ``fuel`` and ``limit``, the 10,000-step truncation);
- ``OUT/model.pt``: the policy, its observation statistics and the options it was trained on, loadable by
  ``python -m chopperscape.learn.evaluate OUT/model.pt``. It is saved at every checkpoint interval, at the end and on
  Ctrl-C. It holds tensors and plain data only, so it is read with ``torch.load(weights_only=True)``.

Training seeds are ``seed, seed + 1, …`` (one per env); evaluate on other seeds (``evaluate --seed 1000000``).

Runs are reproducible: every schedule (the learning rate) follows env steps over the step budget ``--steps``, never
the wall clock, so the same seed and budget give the same curve on any host; ``--minutes`` only stops a run early.
A folder that already holds a run is refused unless ``--force``, which first moves that run whole into
``OUT/replaced-N`` (the first free N; stderr says where) and only then starts the new run there: a run folder never
mixes files of two runs, even if the new run is killed before its first save, and the old run is never lost.
``recipe.json`` and ``model.pt`` are written whole or not at all (:mod:`chopperscape._atomic`); a file that cannot be
written (a read-only folder, a full disk) ends the run with one line naming it (exit 1). Every setting is
checked before anything is written; a loss that is not finite stops the run before the optimiser step, so the saved
model is never a NaN one. Ctrl-C (SIGINT, SIGTERM, SIGHUP) stops the run after the current update, saves the model
reached so far atomically, and exits with 130, 143, 129.
Several seeds, each evaluated and all summarised as the field does: ``python -m chopperscape.learn.seeds``.
``--preset pixels --torch-compile --torch-threads 2`` learns from the frames alone (the 42×42 agent view; 12 M
decisions, 36–43 minutes of two Zen 5 cores); ``--preset pixels-teacher --teacher models/ppo-features-fs4.pt`` is the
privileged route (see :class:`chopperscape.learn.recipe.Recipe`, ``teacher``, and ``docs/learning.md``).
"""

from __future__ import annotations

import json
import sys
from pathlib import Path

from .._cli import print_line, run_command
from . import flags, progress
from .phases import OFF, Phases
from .ppo import UpdateStats, entropy_coef, learning_rate
from .recipe import Recipe, check_minutes, check_recipe, check_until
from .rollout import Rollout, advantages
from .run import Run, RunWriteError

try:
    import torch
    from torch import nn
except ImportError as err:  # pragma: no cover - exercised only without torch
    raise ImportError(
        "chopperscape.learn.train needs PyTorch: pip install 'chopperscape[train]' (the CPU build is enough)"
    ) from err

__all__ = ["CSV_COLUMNS", "RunWriteError", "main", "train"]

#: Columns of the progress CSV (the schema and its meaning: :mod:`chopperscape.learn.progress`).
CSV_COLUMNS = list(progress.COLUMNS)
#: How the update's statistics are written in the progress CSV.
FORMATS = {"entropy": ".4f", "approx_kl": ".5f", "clip_frac": ".4f", "value_loss": ".5f", "policy_loss": ".5f"}


def train(
    recipe: Recipe,
    out: Path,
    minutes: float | None = None,
    force: bool = False,
    phases: Phases = OFF,
    resume: bool = False,
    until: int | None = None,
) -> Path:
    """Runs PPO for `recipe.total_steps` env steps, or until `minutes` of wall time if that comes first (the
    schedules still follow `recipe.total_steps`, so a run cut short is the prefix of the full one); returns the
    model path. `phases` (a :class:`~chopperscape.learn.phases.Phases`) collects where the wall time went.
    With `resume`, continues the run in `out` from its last checkpoint (`resume.pt`): the curve goes on as the
    uninterrupted run's would. `ValueError` for a setting out of range or a folder that holds a run (unless `force`
    or `resume`), before anything is written; `_signals.Interrupted` after a signal, once the model reached so far
    is saved. `until` stops the run at that many env steps (the schedules still follow `total_steps`). The run's
    folder, state and variants are :class:`~.run.Run`'s; this is PPO."""
    check_recipe(recipe)
    check_minutes(minutes)
    check_until(until)
    r = recipe
    with Run(r, Path(out), force=force, resume=resume) as run:
        s, p = run.state, run.parts
        agent, optimizer, guide = s.agent, s.optimizer, p.guide
        params = [q for group in optimizer.param_groups for q in group["params"]]
        buf = Rollout(r.num_steps, r.num_envs, p.obs_shape, p.obs_dtype, p.device)

        def optimize() -> None:
            nn.utils.clip_grad_norm_(params, r.max_grad_norm)
            optimizer.step()

        # What the loop calls, each timed by `phases` (OFF gives them back as they are).
        act = phases.timed("forward", p.net.act)
        env_step = phases.timed("env", run.envs.step)
        encode = phases.timed("obs_norm", p.encode)
        gae = phases.timed("gae", advantages)
        heads = phases.timed("update_forward", p.net.heads)
        backward = phases.timed("backward", torch.Tensor.backward)
        optimize, log = phases.timed("optimizer", optimize), phases.timed("logging", run.log)
        phases.start()
        end = r.total_steps if until is None else min(until, r.total_steps)
        while s.env_steps < end and not run.stopping(minutes):
            lr = optimizer.param_groups[0]["lr"] = learning_rate(r, s.env_steps)
            ent_coef = entropy_coef(r, s.env_steps)
            p.novelty.schedule(s.env_steps)

            # --- Rollout: NEXT_STEP autoreset; the step after an episode's end is a reset step (not valid) ---------
            s.episodes.new_update()
            for t in range(r.num_steps):
                valid = ~s.next_done
                with torch.inference_mode():
                    action, logp, _, value, h = act(s.next_obs)
                buf.store(t, s.next_obs, action, logp, value, valid)
                actions = action.cpu().numpy()
                guide.store(t)
                raw, reward, term, trunc, info = env_step(actions)
                guide.step(actions, reward, term, trunc)
                s.env_steps += int(valid.sum())
                s.episodes.record(reward, valid, term, trunc, info)
                done = term | trunc
                buf.outcome(t, s.rewards(reward, valid, done) + p.novelty.bonus(t, h, raw, valid), done)
                s.next_done = done
                s.next_obs = encode(raw)

            # --- Advantages: GAE over the valid steps -----------------------------------------------------------
            batch = p.novelty.advantages(gae(buf, agent, s.next_obs, r.gamma, r.gae_lambda), buf, s.next_obs)
            guide.flatten(batch.mask)

            # --- Optimisation ---------------------------------------------------------------------------------
            stats = UpdateStats()
            for _ in range(r.update_epochs):
                for idx in batch.minibatches(s.rng, r.num_minibatches):
                    x = p.augment(batch.obs[idx])
                    logits, value, h = heads(x)
                    dist = torch.distributions.Categorical(logits=logits)
                    logp, entropy = dist.log_prob(batch.actions[idx]), dist.entropy()
                    log_ratio = logp - batch.logp[idx]
                    ratio = log_ratio.exp()
                    a = batch.advantages[idx]
                    a = (a - a.mean()) / (a.std() + 1e-8)
                    pg = torch.max(-a * ratio, -a * ratio.clamp(1 - r.clip_coef, 1 + r.clip_coef)).mean()
                    v_loss = 0.5 * ((value - batch.returns[idx]) ** 2).mean()
                    ent = entropy.mean()
                    extra, guided = guide.loss(idx, logits, h, s.env_steps)
                    own, learned = p.frames_loss.loss(x, h)
                    predictor, novel = p.novelty.loss(x, h, idx)
                    loss = pg - ent_coef * ent + r.vf_coef * v_loss + extra + own + predictor
                    if not torch.isfinite(loss):
                        raise FloatingPointError(f"loss became {loss.item()} at update {s.update}")
                    optimizer.zero_grad()
                    backward(loss)
                    optimize()
                    with torch.no_grad():  # Schulman's low-variance KL estimator, as CleanRL logs it
                        kl = ((ratio - 1) - log_ratio).mean()
                        clipped = ((ratio - 1).abs() > r.clip_coef).float().mean()
                    stats.add(
                        {
                            "entropy": ent.item(),
                            "approx_kl": kl.item(),
                            "clip_frac": clipped.item(),
                            "value_loss": v_loss.item(),
                            "policy_loss": pg.item(),
                            **guided,
                            **learned,
                            **novel,
                        }
                    )
            s.update += 1

            # --- Logging: one row per update, a checkpoint every `run.CHECKPOINT_EVERY` -------------------------
            log(
                {
                    "env_steps": s.env_steps,
                    "learning_rate": f"{lr:.6g}",
                    "explained_var": f"{batch.explained_variance():.4f}",
                    **s.episodes.columns(),
                    **stats.columns(FORMATS),
                }
            )
        phases.finish(s.env_steps)
    return run.model_path


def main(argv: list[str] | None = None) -> int:
    a, recipe = flags.parse(sys.argv[1:] if argv is None else argv)

    def command() -> int:
        try:
            path = train(recipe, a.out, a.minutes, force=a.force, resume=a.resume is not None, until=a.until)
        except (FloatingPointError, RuntimeError) as e:  # a loss that is not finite, a twin env out of step
            raise RuntimeError(f"training stopped: {e}; the model saved last is kept") from None
        return print_line(json.dumps({"model": str(path), "progress": str(a.out / "progress.csv")}))

    return run_command(command)


if __name__ == "__main__":
    sys.exit(main())
