"""Behaviour cloning baseline: a small MLP imitates the heuristic policy from a Minari features dataset, then flies
held-out seeds.

    python python/examples/bc_train.py          # 100 heuristic episodes, 30 epochs, 256 wide, 50 eval episodes
    python python/examples/bc_train.py --dataset chopperscape/heuristic-features-v0   # an existing dataset

Needs `pip install torch "minari[hdf5]" pillow` (torch on the CPU is enough). Without `--dataset` the episodes are
collected into a temporary MINARI_DATASETS_PATH first (seeds 0..N-1); evaluation uses seeds from `--eval-seed`
(default 1,000,000), which the dataset never saw, with one native VectorEnv running every evaluation episode at
once. The last line printed is a JSON summary.
"""

from __future__ import annotations

import argparse
import json
import os
import tempfile
import time

import numpy as np


def load(dataset_id: str):
    import minari

    ds = minari.load_dataset(dataset_id)
    obs, acts = [], []
    for ep in ds.iterate_episodes():
        obs.append(ep.observations[:-1])  # the observation each action was taken from
        acts.append(ep.actions)
    return ds, np.concatenate(obs).astype(np.float32), np.concatenate(acts).astype(np.int64)


def train(x: np.ndarray, y: np.ndarray, epochs: int, seed: int, hidden: int = 256):
    import torch
    from torch import nn

    torch.manual_seed(seed)
    model = nn.Sequential(
        nn.Linear(x.shape[1], hidden), nn.ReLU(), nn.Linear(hidden, hidden), nn.ReLU(), nn.Linear(hidden, 5)
    )
    opt = torch.optim.Adam(model.parameters(), lr=1e-3)
    xs, ys = torch.from_numpy(x), torch.from_numpy(y)
    g = torch.Generator().manual_seed(seed)
    for epoch in range(epochs):
        perm = torch.randperm(len(xs), generator=g)
        total, correct = 0.0, 0
        for i in range(0, len(xs), 512):
            idx = perm[i : i + 512]
            logits = model(xs[idx])
            loss = nn.functional.cross_entropy(logits, ys[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
            total += loss.item() * len(idx)
            correct += int((logits.argmax(1) == ys[idx]).sum())
        print(f"epoch {epoch + 1}/{epochs}: loss {total / len(xs):.4f}, train accuracy {correct / len(xs):.3f}")
    return model.eval()


def evaluate(act, episodes: int, seed: int, max_episode_steps: int, options: dict) -> np.ndarray:
    """Returns of the first episode of each of `episodes` envs seeded `seed + i`; `act(envs, obs)` gives actions."""
    import chopperscape

    envs = chopperscape.VectorEnv(
        episodes, obs_type="features", max_episode_steps=max_episode_steps, num_threads=1, **options
    )
    obs, _ = envs.reset(seed=seed)
    returns, done = np.zeros(episodes), np.zeros(episodes, dtype=bool)
    while not done.all():
        obs, rewards, terminated, truncated, _ = envs.step(act(envs, obs))
        returns[~done] += rewards[~done]
        done |= terminated | truncated
    return returns


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    p.add_argument("--dataset", help="an existing Minari dataset id of features observations (default: collect one)")
    p.add_argument("--episodes", type=int, default=100, help="heuristic episodes to collect (without --dataset)")
    p.add_argument("--epochs", type=int, default=30)
    p.add_argument("--eval-episodes", type=int, default=50)
    p.add_argument("--eval-seed", type=int, default=1_000_000)
    p.add_argument("--max-episode-steps", type=int, default=10_000)
    p.add_argument("--hidden", type=int, default=256, help="width of the MLP's two hidden layers")
    p.add_argument("--seed", type=int, default=0, help="seed of torch's initialisation and shuffling")
    args = p.parse_args()

    import torch

    from chopperscape import policies
    from chopperscape.integrations import datasets

    torch.set_num_threads(1)
    start = time.monotonic()
    tmp = None
    dataset_id = args.dataset
    if dataset_id is None:
        tmp = tempfile.TemporaryDirectory(prefix="bc-minari-")
        os.environ["MINARI_DATASETS_PATH"] = tmp.name
        dataset_id = "chopperscape/heuristic-features-v0"
        datasets.collect(
            dataset_id, "heuristic", args.episodes, 0, obs_type="features", max_episode_steps=args.max_episode_steps
        )
    ds, x, y = load(dataset_id)
    print(
        f"dataset {dataset_id}: {ds.total_episodes} episodes, {len(x)} steps; actions "
        f"{np.bincount(y, minlength=5).tolist()}"
    )
    model = train(x, y, args.epochs, args.seed, args.hidden)

    def bc(envs, obs):
        with torch.no_grad():
            return model(torch.from_numpy(np.asarray(obs, dtype=np.float32))).argmax(1).numpy().astype(np.int64)

    results = {}
    for name, act in [("bc", bc), ("heuristic", None), ("random", None)]:
        if act is None:
            batch = policies.VectorPolicy(name, args.eval_episodes, seed=args.eval_seed)
            act = lambda envs, obs, batch=batch: batch.act(envs)  # noqa: E731
        r = evaluate(act, args.eval_episodes, args.eval_seed, args.max_episode_steps, {})
        results[name] = {"mean": float(r.mean()), "std": float(r.std()), "episodes": len(r)}
        print(
            f"{name:>9}: mean return {r.mean():.1f} ± {r.std():.1f} over {len(r)} held-out episodes "
            f"(seeds {args.eval_seed}..{args.eval_seed + len(r) - 1})"
        )
    summary = {
        "dataset_steps": len(x),
        "dataset_episodes": int(ds.total_episodes),
        "epochs": args.epochs,
        "hidden": args.hidden,
        "seconds": round(time.monotonic() - start, 1),
        **results,
    }
    print(json.dumps(summary))
    if tmp is not None:
        tmp.cleanup()


if __name__ == "__main__":
    main()
