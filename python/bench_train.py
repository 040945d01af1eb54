"""Where the PPO recipe's training time goes, phase by phase, beside each phase's floor (a benchmark, not a test).

    .venv/bin/python python/bench_train.py [--steps 131072] [--case features ...] [--device cpu] [--smoke]

For each case it trains with the case's preset (``features``: the features recipe; ``fast``: ``--preset fast``;
``pixels``: ``--preset pixels``, a small CNN on 42×42×4 frames) for ``--steps`` env steps, timing every phase of the
loop (:mod:`chopperscape.learn.phases`: env, observation normalisation, rollout forward, bookkeeping, GAE, the
update's forward, backward and optimiser step, logging), and prints per phase the wall time per env step and its
share, beside the phase's floor: the same work with no Python in between (the env stepping the whole batch
natively; one forward of the network over a whole rollout at once; each minibatch's forward, backward and Adam
step run back to back, times the epochs). ``--threads N`` sets the run's torch threads (one core or both); the
header line gives the CPU seconds beside the wall seconds, and the rate without the setup and each phase's first
call (``--compile``: the network through ``torch.compile``, which compiles there). The gap between a
phase and its floor is what the loop's Python costs. On a shared machine, compare cases from one run only.
``--sb3`` adds, for each case with an MLP, Stable-Baselines3's PPO with the same network, batch, epochs and
minibatches through the native adapter (`chopperscape.integrations.sb3`, `VecNormalize`), trained for the same steps
in the same run: the anchor a user would pick instead. ``--rust PATH`` adds, for the ``fast`` and ``features``
cases, the Rust learner (``PATH train --preset CASE --phases``, ``PATH`` the ``chopperscape`` command line:
docs/rust-learner.md) at each of ``--rust-threads`` (default 1 and 2), same steps, same run: its phases, timed at
the same places, in columns beside torch's, with its wall and CPU seconds. ``--set FIELD=VALUE`` sets a recipe
setting of every case (``--set rnd_coef=0.5 --set rnd_own_value=true``: the exploration bonus, whose forward passes
and loss fall in ``bookkeeping``, its predictor's gradients in ``backward``). ``--smoke`` runs each case for a few
updates of a tiny batch (seconds: the test command runs it so that it cannot rot; its figures mean nothing).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import os
import platform
import resource
import subprocess
import sys
import tempfile
import time
from dataclasses import replace
from pathlib import Path

# This file sits beside the package's sources, which lack the compiled `_core`: import the installed package.
sys.path = [p for p in sys.path if os.path.abspath(p or ".") != os.path.dirname(os.path.abspath(__file__))]

import numpy as np  # noqa: E402
import torch  # noqa: E402

from chopperscape import NUM_ACTIONS, VectorEnv  # noqa: E402
from chopperscape.learn import networks, normalize, train  # noqa: E402
from chopperscape.learn.phases import PHASES, Phases  # noqa: E402
from chopperscape.learn.recipe import PRESETS, Recipe, check_recipe, network_of  # noqa: E402

CASES = [name for name in ("features", "fast", "pixels") if name in PRESETS]


def recipe_for(case: str, steps: int, device: str, smoke: bool) -> Recipe:
    r = Recipe(**{**PRESETS[case], "total_steps": steps, "device": device})
    if smoke:
        r = replace(r, num_envs=8, num_steps=16, num_minibatches=2, update_epochs=2)
    return r


def with_settings(recipe: Recipe, settings: list[str]) -> Recipe:
    """`recipe` with each ``FIELD=VALUE`` of `settings` (VALUE as JSON, else as text), checked as a recipe file's
    settings are; exits naming the first that is not a setting or is out of range."""
    fields = {f.name for f in dataclasses.fields(Recipe)}
    for item in settings:
        name, sep, text = item.partition("=")
        if not sep or name not in fields:
            raise SystemExit(f"--set {item!r}: expected FIELD=VALUE, FIELD one of {', '.join(sorted(fields))}")
        try:
            value = json.loads(text)
        except json.JSONDecodeError:
            value = text
        recipe = replace(recipe, **{name: value})
    try:
        check_recipe(recipe)
    except ValueError as e:
        raise SystemExit(f"--set: {e}") from None
    return recipe


def floors(recipe: Recipe, repeats: int = 3) -> dict[str, float]:
    """Wall seconds per env step of each phase's floor, each measured alone."""
    n, t_len = recipe.num_envs, recipe.num_steps
    envs = VectorEnv(n, num_threads=recipe.env_threads, obs_type=recipe.obs_type, **recipe.env_options)
    obs, _ = envs.reset(seed=0)
    actions = np.zeros(n, np.int64)
    t = time.perf_counter()
    for _ in range(repeats * 20):
        obs, *_ = envs.step(actions)
    env = (time.perf_counter() - t) / (repeats * 20 * n)
    shape = tuple(envs.single_observation_space.shape or ())
    envs.close()
    pixels = network_of(recipe) != "mlp"
    agent = networks.build_agent(network_of(recipe), shape, NUM_ACTIONS, recipe.hidden, recipe.invert_frames).to(
        recipe.device
    )
    batch = np.repeat(obs[None], t_len, axis=0).reshape(n * t_len, *shape)
    norm = normalize.ObsNormalizer(shape, recipe.norm_obs and not pixels)
    t = time.perf_counter()
    for _ in range(repeats):
        x = torch.from_numpy(batch if pixels else norm(batch, update=True)).to(recipe.device)
    obs_norm = (time.perf_counter() - t) / (repeats * n * t_len)
    with torch.inference_mode():
        agent.act(x)
        t = time.perf_counter()
        for _ in range(repeats):
            agent.act(x)
        forward = (time.perf_counter() - t) / (repeats * n * t_len)
    size = n * t_len // recipe.num_minibatches
    xb, ab = x[:size].clone(), torch.zeros(size, dtype=torch.long, device=recipe.device)
    opt = torch.optim.Adam(agent.parameters(), lr=1e-5)
    spent = dict.fromkeys(("update_forward", "backward", "optimizer"), 0.0)
    for _ in range(repeats):
        t = time.perf_counter()
        logits, value, _ = agent.heads(xb)
        dist = torch.distributions.Categorical(logits=logits)
        loss = -dist.log_prob(ab).mean() - 0.01 * dist.entropy().mean() + value.pow(2).mean()
        t1 = time.perf_counter()
        opt.zero_grad()
        loss.backward()
        t2 = time.perf_counter()
        torch.nn.utils.clip_grad_norm_(list(agent.parameters()), 0.5)
        opt.step()
        t3 = time.perf_counter()
        for k, d in zip(spent, (t1 - t, t2 - t1, t3 - t2)):
            spent[k] += d
    # Per env step: each minibatch's cost over its samples, times the epochs.
    per_step = {k: v / (repeats * size) * recipe.update_epochs for k, v in spent.items()}
    return {"env": env, "obs_norm": obs_norm, "forward": forward, **per_step}


def sb3_steps_per_second(recipe: Recipe, steps: int) -> float:
    """Env steps per second of wall time of SB3's PPO with `recipe`'s network, batch and epochs (an MLP recipe)."""
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from chopperscape.integrations.sb3 import ChopperScapeVecEnv, ppo_settings

    venv = ChopperScapeVecEnv(recipe.num_envs, seed=0, obs_type=recipe.obs_type, **recipe.env_options)
    env = VecNormalize(venv, gamma=recipe.gamma)
    model = PPO(
        "MlpPolicy", env, learning_rate=recipe.learning_rate, **ppo_settings(recipe), device=recipe.device, seed=0
    )
    wall = time.perf_counter()
    model.learn(steps)
    wall = time.perf_counter() - wall
    done = int(model.num_timesteps)
    env.close()
    return done / wall


def rust_run(cli: str, case: str, steps: int, threads: int, smoke: bool) -> dict:
    """The Rust learner on `case`'s preset for `steps` decisions at `threads` threads: its phase seconds
    (`phases`), `decisions`, and the process's `wall` and `cpu` seconds."""
    with tempfile.TemporaryDirectory() as out:
        cmd = [cli, "train", "--preset", case, "--steps", str(steps), "--threads", str(threads), "--phases"]
        cmd += ["--out", out, "--force"]
        if smoke:
            cmd += ["--num-envs", "8", "--num-steps", "16"]
        before = resource.getrusage(resource.RUSAGE_CHILDREN)
        wall = time.perf_counter()
        done = subprocess.run(cmd, capture_output=True, text=True)
        wall = time.perf_counter() - wall
        after = resource.getrusage(resource.RUSAGE_CHILDREN)
    if done.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({done.returncode}): {done.stderr.strip()[-500:]}")
    line = json.loads(done.stdout.strip().splitlines()[-1])
    cpu = after.ru_utime + after.ru_stime - before.ru_utime - before.ru_stime
    return {"phases": line["phases"], "decisions": line["decisions"], "wall": wall, "cpu": cpu, "threads": threads}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--steps", type=int, default=131_072, help="env steps per case (default 131072)")
    p.add_argument("--case", action="append", choices=CASES, help="cases to run (default all)")
    p.add_argument("--device", default="cpu", help="cpu or cuda")
    p.add_argument("--smoke", action="store_true", help="a few tiny updates per case (seconds; for the tests)")
    p.add_argument("--sb3", action="store_true", help="SB3's PPO with the same network and batch, as an anchor")
    p.add_argument("--threads", type=int, default=None, help="torch threads of the run (default the preset's)")
    p.add_argument("--network", default=None, help="the network of the CNN cases (default the preset's)")
    p.add_argument("--epochs", type=int, default=None, help="update epochs (default the preset's)")
    p.add_argument("--minibatches", type=int, default=None, help="minibatches an epoch (default the preset's)")
    p.add_argument(
        "--compile",
        action="store_true",
        help="the CNN cases' network through torch.compile (--torch-compile; the floors stay eager)",
    )
    p.add_argument(
        "--set",
        action="append",
        default=[],
        metavar="FIELD=VALUE",
        help="a recipe setting of every case, VALUE read as JSON else as text (e.g. rnd_coef=0.5); checked",
    )
    p.add_argument("--rust", metavar="PATH", help="the chopperscape command line: its learner beside torch's")
    p.add_argument("--rust-threads", default="1,2", help="the Rust learner's thread counts (default 1,2)")
    a = p.parse_args(argv)
    rust_threads = [int(t) for t in a.rust_threads.split(",")]
    steps = 256 if a.smoke else a.steps
    print(
        f"# {platform.machine()}, {os.cpu_count()} CPUs, torch {torch.__version__}, device {a.device}, "
        f"load average {os.getloadavg()[0]:.1f}; µs of wall time per env step"
    )
    for case in a.case or CASES:
        recipe = recipe_for(case, steps, a.device, a.smoke)
        if a.threads is not None:
            recipe = replace(recipe, torch_threads=a.threads)
        if a.network is not None and network_of(recipe) != "mlp":
            recipe = replace(recipe, network=a.network)
        if a.compile and network_of(recipe) != "mlp":
            recipe = replace(recipe, torch_compile=True)
        if a.epochs is not None:
            recipe = replace(recipe, update_epochs=a.epochs)
        if a.minibatches is not None:
            recipe = replace(recipe, num_minibatches=a.minibatches)
        recipe = with_settings(recipe, a.set)
        torch.set_num_threads(recipe.torch_threads)
        phases = Phases()
        with tempfile.TemporaryDirectory() as out:
            wall, cpu = time.perf_counter(), time.process_time()
            train.train(recipe, Path(out), phases=phases)
            wall, cpu = time.perf_counter() - wall, time.process_time() - cpu
        done = max(phases.steps, 1)
        floor = floors(recipe)
        print(
            f"\n## {case}: {done:,} env steps in {wall:.1f} s, {done / wall:,.0f} env steps/s "
            f"({cpu:.1f} CPU s, {recipe.torch_threads} torch threads, network {network_of(recipe)}, "
            f"{recipe.update_epochs} epochs of {recipe.num_minibatches} minibatches"
            f"{', compiled; the floors eager' if recipe.torch_compile else ''}); "
            f"{done / max(sum(phases.seconds.values()), 1e-9):,.0f} env steps/s without the setup and the first calls"
        )
        rust = [rust_run(a.rust, case, steps, t, a.smoke) for t in rust_threads] if a.rust and case != "pixels" else []
        for r in rust:
            print(
                f"Rust learner, {r['threads']} thread(s): {r['decisions']:,} env steps in {r['wall']:.1f} s, "
                f"{r['decisions'] / r['wall']:,.0f} env steps/s ({r['cpu']:.1f} CPU s; process wall and CPU)"
            )
        print(
            f"{'phase':<15} {'µs/step':>9} {'share':>7} {'floor µs':>9}"
            + "".join(f" {'rust×' + str(r['threads']):>9}" for r in rust)
        )
        for name in PHASES:
            sec = phases.seconds[name]
            f = f"{floor[name] * 1e6:9.2f}" if name in floor else f"{'–':>9}"
            cols = "".join(f" {r['phases'][name] / max(r['decisions'], 1) * 1e6:9.2f}" for r in rust)
            print(f"{name:<15} {sec / done * 1e6:9.2f} {sec / wall:7.1%} {f}{cols}")
        first = sum(phases.first.values())
        other = wall - sum(phases.seconds.values()) - first
        cols = "".join(f" {(r['wall'] - sum(r['phases'].values())) / max(r['decisions'], 1) * 1e6:9.2f}" for r in rust)
        print(f"{'(setup)':<15} {other / done * 1e6:9.2f} {other / wall:7.1%} {'–':>9}{cols}")
        # Each phase's first call (where a compiled network compiles), apart from its per-step cost.
        print(f"{'(first calls)':<15} {first / done * 1e6:9.2f} {first / wall:7.1%} {'–':>9}")
        if a.sb3 and network_of(recipe) == "mlp":
            sb3 = sb3_steps_per_second(recipe, steps)
            print(f"SB3 PPO, the same network, batch and epochs: {sb3:,.0f} env steps/s ({done / wall / sb3:.1f}x)")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
