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
``--preset pixels`` learns from the frames alone (the 42×42 agent view; about two hours of one core to pass 3,000
held out); ``--preset pixels-teacher --teacher models/ppo-features-fs4.pt`` is the faster, privileged route (see
:class:`chopperscape.learn.recipe.Recipe`, ``teacher``, and ``docs/learning.md``).
"""

from __future__ import annotations

import contextlib
import json
import math
import os
import sys
import time
from collections import deque
from collections.abc import Iterator
from dataclasses import asdict
from pathlib import Path

import numpy as np

from .. import _atomic, _signals
from .._cli import print_line, run_command
from ..vector import VectorEnv
from . import flags, progress
from .guidance import Guidance, env_state, load_teacher, set_env_state
from .model import CnnAgent, ObsNormalizer, RunningMeanStd, build_agent, random_shift, save, shift_pad
from .phases import OFF, Phases
from .recipe import (
    LR_FLOOR,
    MAX_PARAMETERS,
    MAX_ROLLOUT_BYTES,
    RUN_FILES,
    Recipe,
    check_minutes,
    check_recipe,
    check_run_folder,
    network_of,
)
from .rundir import RECIPE_KEY, check_recipe_hash, locked, recipe_hash, remove_stale_parts

try:
    import torch
    from torch import nn
except ImportError as err:  # pragma: no cover - exercised only without torch
    raise ImportError(
        "chopperscape.learn.train needs PyTorch: pip install 'chopperscape[train]' (the CPU build is enough)"
    ) from err

#: Columns of the progress CSV (the schema and its meaning: :mod:`chopperscape.learn.progress`).
CSV_COLUMNS = list(progress.COLUMNS)


class RunWriteError(OSError):
    """A file of the run could not be written (a read-only folder, a full disk): the message names it."""


@contextlib.contextmanager
def _writing(path: Path, after: str = "") -> Iterator[None]:
    """`OSError` in the block as a `RunWriteError` naming `path` (and what is kept, `after`)."""
    try:
        yield
    except RunWriteError:
        raise
    except OSError as e:
        raise RunWriteError(f"cannot write {path}: {e.strerror or e}{after}") from None


def _next_aside(out: Path) -> Path:
    """The first free `OUT/replaced-N` (N = 1, 2, …): where `--force` keeps the run it replaces."""
    n = 1
    while os.path.lexists(out / f"replaced-{n}"):
        n += 1
    return out / f"replaced-{n}"


def start_run(out: Path, recipe: Recipe) -> tuple[progress.Writer, Path | None]:
    """Makes the run folder `out` ready for a new run and writes its `recipe.json` and the progress header:
    a run already there (`--force`) is first moved whole into `OUT/replaced-N`, so that `out` never holds files of
    two runs. Returns the progress writer and where the old run went (None if there was none). On a write
    error (`RunWriteError`, `ValueError` for an `out` that cannot be a folder), nothing new is left behind and an
    old run is moved back."""
    made = not os.path.lexists(out)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise ValueError(f"--out {out}: cannot make the folder: {e.strerror or e}") from None
    old = [name for name in RUN_FILES if os.path.lexists(out / name)]
    aside = _next_aside(out) if old else None
    moved: list[str] = []
    try:
        if aside is not None:
            with _writing(aside):
                aside.mkdir()
                for name in old:
                    os.replace(out / name, aside / name)
                    moved.append(name)
        with _writing(out / "recipe.json"):
            _atomic.write_text(out / "recipe.json", json.dumps(asdict(recipe), indent=2) + "\n")
        with _writing(out / "progress.csv"):
            return progress.Writer(out / "progress.csv"), aside
    except BaseException:
        for name in ("progress.csv", "recipe.json"):
            with contextlib.suppress(OSError):
                if name not in old or name in moved:
                    os.unlink(out / name)
        for name in moved:
            with contextlib.suppress(OSError):
                os.replace(aside / name, out / name)  # type: ignore[operator]
        with contextlib.suppress(OSError):
            if aside is not None:
                aside.rmdir()
            if made:
                out.rmdir()
        raise


def _read_resume(out: Path) -> dict:
    """The state `OUT/resume.pt` holds (tensors and plain data, read with `weights_only=True`); `ValueError` naming
    the file when it is missing or not one this trainer wrote."""
    from .model import read_checkpoint

    path = out / "resume.pt"
    what = f"resume state {str(path)!r}"
    if not os.path.lexists(path):
        raise ValueError(f"--resume {out}: no resume.pt there (a run saves one at each checkpoint, every 50 updates)")
    state = read_checkpoint(path, what)
    if not isinstance(state, dict) or state.get("format") != RESUME_FORMAT:
        raise ValueError(f"{what} is not a resume state of this trainer (format {RESUME_FORMAT})")
    return state


#: The format of `OUT/resume.pt`.
RESUME_FORMAT = "chopperscape-ppo-resume/1"
#: Updates between checkpoints (`model.pt` and `resume.pt`).
CHECKPOINT_EVERY = 50


@locked  # the run folder is locked for the run's life (rundir.RunLock): a second writer is refused
def train(
    recipe: Recipe,
    out: Path,
    minutes: float | None = None,
    force: bool = False,
    phases: Phases = OFF,
    resume: bool = False,
) -> Path:
    """Runs PPO for `recipe.total_steps` env steps, or until `minutes` of wall time if that comes first (the
    schedules still follow `recipe.total_steps`, so a run cut short is the prefix of the full one); returns the
    model path. `phases` (a :class:`~chopperscape.learn.phases.Phases`) collects where the wall time went.
    With `resume`, continues the run in `out` from its last checkpoint (`resume.pt`): the curve goes on as the
    uninterrupted run's would (the envs, the statistics, the optimiser and both random streams are restored).
    `ValueError` for a setting out of range or a folder that holds a run (unless `force` or `resume`), before
    anything is written; `_signals.Interrupted` after a signal, once the model reached so far is saved."""
    out = Path(out)
    check_recipe(recipe)
    check_minutes(minutes)
    saved = _read_resume(out) if resume else None
    check_recipe_hash(saved, recipe, out)  # a checkpoint resumes only the run that saved it
    if not resume:
        check_run_folder(out, force)
    teacher = load_teacher(recipe) if recipe.teacher else None
    torch.manual_seed(recipe.seed)
    torch.set_num_threads(recipe.torch_threads)
    rng = np.random.default_rng(recipe.seed)

    envs = VectorEnv(recipe.num_envs, num_threads=recipe.env_threads, obs_type=recipe.obs_type, **recipe.env_options)
    obs_shape = tuple(envs.single_observation_space.shape or ())
    network = network_of(recipe)
    device = torch.device(recipe.device)
    size = 0
    if network != "mlp":  # a CNN's size grows with the frames: measured on the meta device, taking no memory
        with torch.device("meta"):
            size = sum(p.numel() for p in build_agent(network, obs_shape, 5, recipe.hidden).parameters())
    if size > MAX_PARAMETERS:
        envs.close()
        raise ValueError(
            f"the {network} network on observations of shape {obs_shape} would have {size:,} parameters, more than "
            f"{MAX_PARAMETERS:,}: smaller observations (obs_size), fewer stacked frames or a smaller network"
        )
    agent = build_agent(network, obs_shape, 5, recipe.hidden, recipe.invert_frames).to(device)
    pixels = network != "mlp"
    # Training-only guidance from the features (a separate part: plain PPO has none; see guidance.py).
    guide: Guidance | None = None
    if recipe.aux_coef > 0 or teacher is not None:
        if not isinstance(agent, CnnAgent):
            envs.close()
            raise ValueError("the auxiliary loss and the teacher are for CNN recipes (pixel observations) only")
        guide = Guidance(recipe, agent, teacher, recipe.num_steps, device)
    params = list(agent.parameters()) + (guide.params if guide else [])
    optimizer = torch.optim.Adam(params, lr=recipe.learning_rate, eps=1e-5)
    # Vector observations are standardised with running statistics; frames are scaled by the network itself.
    obs_norm = ObsNormalizer(obs_shape, recipe.norm_obs and not pixels)
    ret_rms = RunningMeanStd(())
    disc_return = np.zeros(recipe.num_envs)
    pad = shift_pad(obs_shape) if recipe.augment == "shift" else 0

    def encode(raw: np.ndarray) -> torch.Tensor:
        """A batch of observations as the network takes them (frames stay uint8: a quarter of the memory)."""
        return torch.from_numpy(raw if pixels else obs_norm(raw, update=True)).to(device)

    # --- Rollout storage -------------------------------------------------------------------------------------
    n, t_len = recipe.num_envs, recipe.num_steps
    feat_dim = guide.feat_dim if guide else 0
    # Each stored step: its observation (twice: the buffer and the update's batch), the twin's features, the
    # teacher's log-probabilities and seven numbers.
    per_step = 2 * math.prod(obs_shape) * (1 if pixels else 4) + 4 * (2 * feat_dim + 5 + 7)
    if n * t_len * per_step > MAX_ROLLOUT_BYTES:
        envs.close()
        if guide is not None:
            guide.close()
        raise ValueError(
            f"invalid values {n} and {t_len} for options `num_envs` and `num_steps`: an update's rollout would take "
            f"{n * t_len * per_step / 2**30:.1f} GiB, more than {MAX_ROLLOUT_BYTES >> 30} GiB: fewer envs or steps"
        )
    buf_obs = torch.zeros((t_len, n, *obs_shape), dtype=torch.uint8 if pixels else torch.float32, device=device)
    buf_act = torch.zeros((t_len, n), dtype=torch.long, device=device)
    buf_logp, buf_rew, buf_done, buf_val = (torch.zeros((t_len, n), device=device) for _ in range(4))
    # With NEXT_STEP autoreset, the step after an episode's end is the reset step: no transition to learn from.
    buf_valid = torch.zeros((t_len, n), device=device)

    # --- The run's state: what a checkpoint saves and `--resume` restores -------------------------------------
    next_done = np.zeros(n, bool)  # the previous step ended an episode: this step is a reset step
    ep_return, ep_len = np.zeros(n), np.zeros(n, np.int64)
    finished: deque[tuple[float, int]] = deque(maxlen=100)
    episodes = env_steps = update = 0
    wall_before = 0.0  # wall seconds of the run before this process (a resumed run's curve keeps counting)
    if saved is None:
        raw, _ = envs.reset(seed=recipe.seed)
        next_obs = encode(raw)
        if guide is not None:
            guide.reset(recipe.seed)
    else:
        try:
            agent.load_state_dict(saved["agent"])
            optimizer.load_state_dict(saved["optimizer"])
            set_env_state(envs, saved["envs"])
            if guide is not None:
                guide.load_state(saved["guidance"])
            obs_norm.rms = RunningMeanStd.from_state(saved["obs_rms"])
            ret_rms = RunningMeanStd.from_state(saved["ret_rms"])
            next_obs = saved["next_obs"].to(device)
            next_done = saved["next_done"].numpy().astype(bool)
            disc_return, ep_return = saved["disc_return"].numpy().copy(), saved["ep_return"].numpy().copy()
            ep_len = saved["ep_len"].numpy().astype(np.int64)
            finished.extend((float(r), int(k)) for r, k in saved["finished"])
            episodes, env_steps, update = int(saved["episodes"]), int(saved["env_steps"]), int(saved["update"])
            wall_before = float(saved["wall_s"])
            rng.bit_generator.state = json.loads(saved["numpy_rng"])
            torch.set_rng_state(saved["torch_rng"])
        except (KeyError, TypeError, ValueError, RuntimeError, AttributeError) as e:
            envs.close()
            if guide is not None:
                guide.close()
            raise ValueError(f"--resume {out}: resume.pt does not fit this run's recipe ({e})") from None

    def checkpoint_state() -> dict:
        return {
            "format": RESUME_FORMAT,
            RECIPE_KEY: recipe_hash(recipe),
            "agent": agent.state_dict(),
            "optimizer": optimizer.state_dict(),
            "envs": env_state(envs),
            "guidance": guide.state() if guide is not None else None,
            "obs_rms": obs_norm.rms.state(),
            "ret_rms": ret_rms.state(),
            "next_obs": next_obs.cpu(),
            "next_done": torch.from_numpy(next_done.copy()),
            "disc_return": torch.from_numpy(disc_return.copy()),
            "ep_return": torch.from_numpy(ep_return.copy()),
            "ep_len": torch.from_numpy(ep_len.copy()),
            "finished": [[r, k] for r, k in finished],
            "episodes": episodes,
            "env_steps": env_steps,
            "update": update,
            "wall_s": wall_before + time.monotonic() - start,
            "numpy_rng": json.dumps(rng.bit_generator.state),
            "torch_rng": torch.get_rng_state(),
        }

    def save_resume(state: dict) -> None:
        path = out / "resume.pt"
        with _writing(path, kept), _signals.deferred(f"the resume state is saved in {path}"):
            with _atomic.replacing(path) as tmp:
                torch.save(state, tmp)

    remove_stale_parts(out)  # what a killed run of this folder left half-written
    start = time.monotonic()
    model_path = out / "model.pt"
    csv_path = out / "progress.csv"
    if resume:
        writer, aside = progress.Writer.resume(csv_path, env_steps), None
    else:
        writer, aside = start_run(out, recipe)
    if aside is not None:
        print(f"note: --force: the run that was in {out} is kept in {aside}", file=sys.stderr)
    kept = "; the model saved last is kept"
    stop = _signals.defer()  # Ctrl-C ends the run after the current update, which is then saved
    phases.start()
    try:
        while env_steps < recipe.total_steps:
            if stop.pending is not None:
                break
            if minutes is not None and time.monotonic() - start >= minutes * 60:
                break
            # The learning rate follows env steps only: the same run on a busy host is the same run.
            lr = recipe.learning_rate
            if recipe.anneal_lr:
                lr *= max(1.0 - env_steps / recipe.total_steps, LR_FLOOR)
            optimizer.param_groups[0]["lr"] = lr

            # --- Rollout ---------------------------------------------------------------------------------------
            ends = {"bird": 0, "fuel": 0, "limit": 0}
            for t in range(t_len):
                valid = ~next_done
                with torch.no_grad():
                    action, logp, _, value = agent.act(next_obs)
                phases.lap("forward")
                buf_obs[t], buf_act[t], buf_logp[t], buf_val[t] = next_obs, action, logp, value
                buf_valid[t] = torch.from_numpy(valid.astype(np.float32)).to(device)
                actions = action.cpu().numpy()
                if guide is not None:
                    guide.store(t)
                phases.lap("bookkeeping")
                raw, reward, term, trunc, info = envs.step(actions)
                phases.lap("env")
                if guide is not None:
                    guide.step(actions, reward, term, trunc)
                env_steps += int(valid.sum())
                done = term | trunc
                # Episode statistics, on real (not reset) steps.
                ep_return += np.where(valid, reward, 0)
                ep_len += valid
                for i in np.flatnonzero(done):
                    finished.append((float(ep_return[i]), int(ep_len[i])))
                    episodes += 1
                    ends[str(info["cause"][i]) if term[i] else "limit"] += 1
                ep_return[done], ep_len[done] = 0, 0
                # Reward scaling by the std of the discounted return (Gymnasium's NormalizeReward).
                r = reward.astype(np.float64)
                if recipe.norm_reward:
                    disc_return = np.where(valid, disc_return * recipe.gamma + r, 0.0)
                    if valid.any():
                        ret_rms.update(disc_return[valid])
                    r = r / math.sqrt(ret_rms.var + 1e-8)
                    disc_return[done] = 0.0
                buf_rew[t] = torch.from_numpy(np.where(valid, r, 0.0).astype(np.float32)).to(device)
                # Truncation is treated as termination (10,000 steps is ten horizons of γ = 0.999).
                buf_done[t] = torch.from_numpy(done.astype(np.float32)).to(device)
                next_done = done
                phases.lap("bookkeeping")
                next_obs = encode(raw)
                phases.lap("obs_norm")

            # --- Advantages: GAE over valid steps; a reset step neither bootstraps nor is learned from ------------
            with torch.no_grad():
                next_value = agent.value(next_obs)
                adv = torch.zeros((t_len, n), device=device)
                last = torch.zeros(n, device=device)
                for t in reversed(range(t_len)):
                    nv = next_value if t == t_len - 1 else buf_val[t + 1]
                    nonterminal = 1.0 - buf_done[t]
                    delta = buf_rew[t] + recipe.gamma * nv * nonterminal - buf_val[t]
                    last = delta + recipe.gamma * recipe.gae_lambda * nonterminal * last
                    # The row after an episode's end is its reset step: it carries nothing across.
                    last = last * buf_valid[t]
                    adv[t] = last
                returns = adv + buf_val
            mask = buf_valid.reshape(-1).bool()
            b_obs = buf_obs.reshape(-1, *obs_shape)[mask]
            b_act, b_logp = buf_act.reshape(-1)[mask], buf_logp.reshape(-1)[mask]
            b_adv, b_ret = adv.reshape(-1)[mask], returns.reshape(-1)[mask]
            b_val = buf_val.reshape(-1)[mask]
            if guide is not None:
                guide.flatten(mask)
            size = b_obs.shape[0]
            phases.lap("gae")

            # --- Optimisation ------------------------------------------------------------------------------------
            # entropy, approx_kl, clip_frac, value_loss, policy_loss, minibatches, aux_loss, teacher_kl
            stats = np.zeros(8)
            for _ in range(recipe.update_epochs):
                # Even minibatches (no tiny remainder, whose advantage std would be undefined).
                for idx in torch.from_numpy(rng.permutation(size)).to(device).tensor_split(recipe.num_minibatches):
                    mb_obs = random_shift(b_obs[idx], pad) if pad else b_obs[idx]
                    logits, value, h = agent.heads(mb_obs)
                    dist = torch.distributions.Categorical(logits=logits)
                    logp, entropy = dist.log_prob(b_act[idx]), dist.entropy()
                    log_ratio = logp - b_logp[idx]
                    ratio = log_ratio.exp()
                    a = b_adv[idx]
                    a = (a - a.mean()) / (a.std() + 1e-8)
                    pg = torch.max(-a * ratio, -a * ratio.clamp(1 - recipe.clip_coef, 1 + recipe.clip_coef)).mean()
                    v_loss = 0.5 * ((value - b_ret[idx]) ** 2).mean()
                    ent = entropy.mean()
                    loss = pg - recipe.ent_coef * ent + recipe.vf_coef * v_loss
                    aux_loss = teacher_kl = 0.0
                    if guide is not None:
                        extra, aux_loss, teacher_kl = guide.loss(idx, logits, h, env_steps)
                        loss = loss + extra
                    if not torch.isfinite(loss):
                        raise FloatingPointError(f"loss became {loss.item()} at update {update}")
                    optimizer.zero_grad()
                    loss.backward()
                    nn.utils.clip_grad_norm_(params, recipe.max_grad_norm)
                    optimizer.step()
                    with torch.no_grad():
                        # Schulman's low-variance KL estimator, as CleanRL logs it.
                        kl = ((ratio - 1) - log_ratio).mean()
                        clipped = ((ratio - 1).abs() > recipe.clip_coef).float().mean()
                    stats += [ent.item(), kl.item(), clipped.item(), v_loss.item(), pg.item(), 1, aux_loss, teacher_kl]
            update += 1
            phases.lap("update")
            var_ret = b_ret.var().item()
            explained = float("nan") if var_ret == 0 else 1 - (b_ret - b_val).var().item() / var_ret

            # --- Logging -----------------------------------------------------------------------------------------
            # One row per update; the return columns stay empty until the first episode has ended.
            rets = np.array([r for r, _ in finished])
            lens = np.array([n for _, n in finished])
            ended = sum(ends.values())
            m = stats / max(stats[5], 1)
            row = {
                "env_steps": env_steps,
                "wall_s": f"{wall_before + time.monotonic() - start:.1f}",
                "episodes": episodes,
                "learning_rate": f"{lr:.6g}",
                "entropy": f"{m[0]:.4f}",
                "approx_kl": f"{m[1]:.5f}",
                "clip_frac": f"{m[2]:.4f}",
                "explained_var": f"{explained:.4f}",
                "value_loss": f"{m[3]:.5f}",
                "policy_loss": f"{m[4]:.5f}",
                "ended": ended,
            }
            if finished:
                row.update(
                    mean_return=f"{rets.mean():.1f}", std_return=f"{rets.std():.1f}", mean_length=f"{lens.mean():.1f}"
                )
            if ended:
                row.update({k: f"{ends[k] / ended:.3f}" for k in ("bird", "fuel", "limit")})
            if guide is not None and guide.aux_head is not None:
                row["aux_loss"] = f"{m[6]:.5f}"
            if guide is not None and guide.teacher is not None:
                row["teacher_kl"] = f"{m[7]:.5f}"
            with _writing(csv_path, kept):
                writer.row(row)
            if update % CHECKPOINT_EVERY == 0:
                with _writing(model_path, kept):
                    save(model_path, agent, obs_norm, recipe, obs_shape, env_steps)
                save_resume(checkpoint_state())
            phases.lap("logging")
            phases.steps = env_steps
        # The end, a signal or --minutes: the model and the state to go on from, both as they are now.
        with _writing(model_path, kept):
            save(model_path, agent, obs_norm, recipe, obs_shape, env_steps)
        save_resume(checkpoint_state())
    finally:
        with contextlib.suppress(OSError):
            writer.close()
        envs.close()
        if guide is not None:
            guide.close()
        stop.restore()
    stop.check(f"the model reached so far ({env_steps} env steps) is saved in {model_path}")
    return model_path


def main(argv: list[str] | None = None) -> int:
    a, recipe = flags.parse(sys.argv[1:] if argv is None else argv)

    def command() -> int:
        try:
            path = train(recipe, a.out, a.minutes, force=a.force, resume=a.resume is not None)
        except (FloatingPointError, RuntimeError) as e:  # a loss that is not finite, a twin env out of step
            raise RuntimeError(f"training stopped: {e}; the model saved last is kept") from None
        return print_line(json.dumps({"model": str(path), "progress": str(a.out / "progress.csv")}))

    return run_command(command)


if __name__ == "__main__":
    sys.exit(main())
