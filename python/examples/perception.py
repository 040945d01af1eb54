#!/usr/bin/env python3
"""Do the small pixel observations hide what a CNN needs, or is the fault in RL? A supervised perception check of
the pixel recipe's frames (grayscale, 4 stacked, frame skip 4) at one or more sizes.

    python python/examples/perception.py --size 84,42 --out perception.csv
    python python/examples/perception.py --size 84 --option hud_style='"gauge"'   # extra pixel-env options

For each size it builds a dataset in memory from heuristic and random play: each sample is a frame stack, the
features vector of the same state (a twin `obs_type="features"` env, reset with the same seed and stepped with the
same actions; determinism keeps the two in one state, and their rewards and ends are checked every step) and the
heuristic's action in that state. Training samples come from seeds 0.., held-out samples from seeds 1,000,000..

**Which states.** The heuristic avoids the states a clone drifts into, so the played action is mixed: the envs of a
batch take turns at four exploration rates, 0, 0.1, 0.3 and 1 (env `i` plays a uniformly random action with
probability `EPSILONS[i % 4]` at each decision, the heuristic's otherwise), so a quarter of the decisions each come
from pure heuristic play, lightly and heavily perturbed play, and random play. The label is the heuristic's action in
every state, whatever was played (as DAgger would ask of an expert).

Then, on the held-out samples:
(a) a CNN regressor (the pixel recipe's trunk, `build_agent("small", ..., invert_frames=True).actor[0]`, and a
    linear head) trained on the standardised features (the values of an entity slot only where the slot is filled):
    R² of `chopper_y`, `fuel`, the soonest bird's and the nearest tank's dx and dy (only where that slot is filled),
    accuracy of the presence flags and of `in_lane` (bird slot 0) and `reachable` (tank slot 0), each beside the
    trivial baseline (the training mean, the training majority class) and the share of positives; and `in_lane`
    again where the bird is more than one frame row from the lane's edge (the rows a frame cannot place);
(b) behaviour cloning of the heuristic on the same decisions, from the frames (the recipe's `CnnAgent`, `--epochs`
    like the regressor) and from the features (the recipe's features MLP, 128 wide, on standardised inputs as its
    normaliser gives them; `--features-epochs`, 30: it costs seconds): action agreement on the held-out decisions,
    then both flown greedily on `--eval-episodes` held-out seeds (from `--eval-seed`, 1,000,000; frame skip 4, the
    default 10,000-step limit), beside the heuristic and the random policy on the same seeds.

Defaults (100,000 training decisions, 25,000 held out, 4 epochs at learning rate 1e-3, batches of 256) took 8.3
CPU minutes at 84×84 and 4.5 at 42×42 on one core of a shared 2-vCPU VM; the frames of 125,000 decisions at 84×84
take 3.5 GB of memory. That budget leaves the regressor short of converged (docs/curves/perception/): `--device
cuda --samples 400000 --epochs 20` is the larger one of the results there.

Each size appends its rows to `--out` (CSV: one row per size × measurement; the header when the file is new), and
a markdown table of every size is printed at the end; the last line printed is a JSON summary. One torch thread by
default (`--threads`); the same `--seed` gives the same numbers.
"""

from __future__ import annotations

import argparse
import csv
import fcntl
import io
import json
import os
import time
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, Callable, cast

import numpy as np

if TYPE_CHECKING:
    from torch import nn

#: Exploration rate of env `i` of a collecting batch: `EPSILONS[i % 4]` (see the module docs).
EPSILONS = (0.0, 0.1, 0.3, 1.0)
#: The first held-out seed (the evaluation protocol's: no training sample comes from it or after).
HELD_OUT_SEED = 1_000_000
FEATURES_LEN = 46
#: Entity slots of the features layout (crates/core/src/features.rs): (first index, length). The slot's values
#: after its `present` flag mean something only where the slot is filled.
SLOTS = [(4 + 4 * i, 4) for i in range(4)] + [(20 + 4 * i, 4) for i in range(2)]
SLOTS += [(28 + 5 * i, 5) for i in range(2)] + [(38 + 4 * i, 4) for i in range(2)]
#: Regressed values read by R²: (name, feature index, index of the presence flag that must be 1, or None).
REGRESSED = [
    ("chopper_y", 1, None),
    ("fuel", 2, None),
    ("bird0_dx", 5, 4),
    ("bird0_dy", 6, 4),
    ("tank0_dx", 21, 20),
    ("tank0_dy", 22, 20),
]
#: Flags read by accuracy (the regressor's output above 0.5): (name, feature index, presence index or None).
FLAGS = [
    ("bird0_present", 4, None),
    ("bird0_in_lane", 7, 4),
    ("tank0_present", 20, None),
    ("tank0_reachable", 23, 20),
]
CSV_FIELDS = [
    "size",
    "measurement",
    "metric",
    "value",
    "baseline",
    "std",
    "support",
    "positive_share",
    "samples",
    "held_out",
    "epochs",
    "features_epochs",
    "lr",
    "seed",
    "options",
]


@dataclass
class Data:
    """Samples of one split: frame stacks (uint8, `(N, H, W, k)`), features of the same states (`(N, 46)`), the
    heuristic's action in each state (`(N,)`)."""

    frames: np.ndarray
    features: np.ndarray
    labels: np.ndarray


def collect(
    samples: int, num_envs: int, seed: int, pixel_options: dict[str, Any], rule_options: dict[str, Any]
) -> Data:
    """`samples` decisions from `num_envs` envs seeded `seed + i` (pixel env and features twin in lockstep; see the
    module docs for the mixed play)."""
    from gymnasium.vector import AutoresetMode

    from chopperscape import VectorEnv
    from chopperscape.policies import VectorPolicy

    steps = -(-samples // num_envs)
    kw: dict[str, Any] = dict(num_threads=1, autoreset_mode=AutoresetMode.SAME_STEP)  # every observation is a decision
    pixels = VectorEnv(num_envs, **kw, **pixel_options)
    twin = VectorEnv(num_envs, **kw, **rule_options, obs_type="features")
    heuristic = VectorPolicy("heuristic", num_envs, seed=seed)
    rng = np.random.default_rng([seed, 1])
    eps = np.asarray([EPSILONS[i % len(EPSILONS)] for i in range(num_envs)])
    obs, _ = pixels.reset(seed=seed)
    feats, _ = twin.reset(seed=seed)
    frames = np.empty((steps, *obs.shape), obs.dtype)
    features = np.empty((steps, *feats.shape), np.float32)
    labels = np.empty((steps, num_envs), np.int64)
    try:
        for t in range(steps):
            label = np.asarray(heuristic.act(twin), dtype=np.int64)
            if t == 0:  # the policy reads the game, so either env gives the same action
                assert np.array_equal(label, heuristic.act(pixels))
            explore = rng.random(num_envs) < eps
            played = np.where(explore, rng.integers(0, 5, num_envs), label)
            frames[t], features[t], labels[t] = obs, feats, label
            obs, r, term, trunc, _ = pixels.step(played)
            feats, r2, term2, trunc2, _ = twin.step(played)
            if not (np.array_equal(r, r2) and np.array_equal(term, term2) and np.array_equal(trunc, trunc2)):
                raise RuntimeError(f"the pixel env and its features twin parted at step {t}")
    finally:
        pixels.close()
        twin.close()

    def flat(a: np.ndarray) -> np.ndarray:
        return a.reshape(-1, *a.shape[2:])[:samples]

    return Data(flat(frames), flat(features), flat(labels))


def slot_mask(features: np.ndarray) -> np.ndarray:
    """1 where a feature means something: everything but the values of empty entity slots."""
    mask = np.ones_like(features, dtype=np.float32)
    for at, length in SLOTS:
        mask[:, at + 1 : at + length] = features[:, at : at + 1]
    return mask


def batches(n: int, size: int, generator: Any) -> list[Any]:
    import torch

    return list(torch.randperm(n, generator=generator).split(size))


def predict(net: nn.Module, x: np.ndarray, device: str, batch: int = 1024) -> np.ndarray:
    import torch

    with torch.no_grad():
        out = [net(torch.from_numpy(x[i : i + batch]).to(device)).cpu() for i in range(0, len(x), batch)]
        return torch.cat(out).numpy()


def fit_regressor(
    train: Data, epochs: int, seed: int, lr: float, device: str
) -> tuple[nn.Module, np.ndarray, np.ndarray]:
    """The pixel recipe's trunk and a linear head fitted to the standardised features (masked where a slot is
    empty); returns the network and the standardisation (mean, std) of its targets."""
    import torch
    from torch import nn

    from chopperscape.learn.networks import CnnAgent, build_agent

    torch.manual_seed(seed)
    mask = slot_mask(train.features)
    count = mask.sum(0)
    mean = (train.features * mask).sum(0) / np.maximum(count, 1)
    var = (((train.features - mean) * mask) ** 2).sum(0) / np.maximum(count, 1)
    std = np.where(var > 1e-12, np.sqrt(var), 1.0).astype(np.float32)
    mean = mean.astype(np.float32)
    agent = cast(CnnAgent, build_agent("small", tuple(train.frames.shape[1:]), 5, invert_frames=True))
    trunk = cast(nn.Sequential, agent.actor)[0]  # the trunk the actor and the critic share
    head = nn.Linear(agent.embedding_width, FEATURES_LEN)
    net = nn.Sequential(trunk, head).to(device)
    opt = torch.optim.Adam(net.parameters(), lr=lr)
    # The whole split on the device once (no copy on the CPU): a minibatch is then gathered where it is used.
    x = torch.from_numpy(train.frames).to(device)
    y = torch.from_numpy((train.features - mean) / std).to(device)
    m = torch.from_numpy(mask).to(device)
    g = torch.Generator().manual_seed(seed)
    for _ in range(epochs):
        for idx in batches(len(x), 256, g):
            idx = idx.to(device)
            loss = ((net(x[idx]) - y[idx]) ** 2 * m[idx]).sum() / m[idx].sum()
            opt.zero_grad()
            loss.backward()
            opt.step()
    return net.eval(), mean, std


def r2(y: np.ndarray, pred: np.ndarray) -> float:
    """The coefficient of determination; NaN where `y` is constant or empty (a tiny run may have no bird)."""
    sst = float(((y - y.mean()) ** 2).sum()) if len(y) else 0.0
    return 1.0 - float(((y - pred) ** 2).sum()) / sst if sst > 0 else float("nan")


def average(x: np.ndarray) -> float:
    """The mean of `x`, NaN where it is empty."""
    return float(x.mean()) if len(x) else float("nan")


def perception_rows(held: Data, pred: np.ndarray, train: Data, height: int) -> list[dict[str, Any]]:
    """R² and accuracies on the held-out samples (see the module docs), each with its trivial baseline; and
    `in_lane`'s accuracy where the bird's row is more than one frame pixel (`600 / height` game pixels) from the
    lane's edge (`|dy| = (32 + 64) / 2` pixels, 0.1 as a feature), which the frame's rows cannot place exactly."""
    rows = []
    edge, pixel = 48 / 480, 600 / height / 480  # features' dy is pixels / 480
    clear = np.abs(np.abs(held.features[:, 6]) - edge) > pixel
    clear_fit = np.abs(np.abs(train.features[:, 6]) - edge) > pixel
    for name, i, present in REGRESSED:
        keep = np.ones(len(held.features), bool) if present is None else held.features[:, present] == 1
        fit = np.ones(len(train.features), bool) if present is None else train.features[:, present] == 1
        y = held.features[keep, i]
        baseline = r2(y, np.full_like(y, average(train.features[fit, i])))
        rows.append(
            dict(measurement=name, metric="r2", value=r2(y, pred[keep, i]), baseline=baseline, support=int(keep.sum()))
        )
    for name, i, present in [*FLAGS, ("bird0_in_lane_off_edge", 7, 4)]:
        keep = np.ones(len(held.features), bool) if present is None else held.features[:, present] == 1
        fit = np.ones(len(train.features), bool) if present is None else train.features[:, present] == 1
        if name.endswith("_off_edge"):
            keep, fit = keep & clear, fit & clear_fit
        y = held.features[keep, i] > 0.5
        majority = average(train.features[fit, i]) > 0.5
        rows.append(
            dict(
                measurement=name,
                metric="accuracy",
                value=average((pred[keep, i] > 0.5) == y),
                baseline=average(y == majority),
                support=int(keep.sum()),
                positive_share=average(y),
            )
        )
    return rows


def fit_clone(
    net: nn.Module, x: np.ndarray, y: np.ndarray, epochs: int, seed: int, lr: float, device: str
) -> nn.Module:
    """Behaviour cloning: cross-entropy of `net`'s logits against the heuristic's actions."""
    import torch

    net.to(device)
    opt = torch.optim.Adam(net.parameters(), lr=lr)
    xt, yt = torch.from_numpy(x).to(device), torch.from_numpy(y).to(device)
    g = torch.Generator().manual_seed(seed)
    for _ in range(epochs):
        for idx in batches(len(xt), 256, g):
            idx = idx.to(device)
            loss = torch.nn.functional.cross_entropy(net(xt[idx]), yt[idx])
            opt.zero_grad()
            loss.backward()
            opt.step()
    return net


def clone_rows(
    train: Data,
    held: Data,
    args: argparse.Namespace,
    pixel_options: dict[str, Any],
    rule_options: dict[str, Any],
) -> list[dict[str, Any]]:
    """Clones from frames and from features: held-out agreement, then greedy flights on held-out seeds."""
    import torch

    from chopperscape.learn import episodes
    from chopperscape.learn.networks import build_agent
    from chopperscape.policies import VectorPolicy

    majority = int(np.bincount(train.labels, minlength=5).argmax())
    base = float((held.labels == majority).mean())
    torch.manual_seed(args.seed)
    frames_agent = build_agent("small", tuple(train.frames.shape[1:]), 5, invert_frames=True)
    frames_net = fit_clone(frames_agent.actor, train.frames, train.labels, args.epochs, args.seed, args.lr, args.device)
    frames_net.eval()
    # The features MLP reads standardised inputs, clipped to ±10, as the recipe's normaliser gives them.
    mean = train.features.mean(0)
    std = np.sqrt(train.features.var(0) + 1e-8)

    def norm(f: np.ndarray) -> np.ndarray:
        return np.clip((f - mean) / std, -10.0, 10.0).astype(np.float32)

    torch.manual_seed(args.seed)
    mlp = build_agent("mlp", (FEATURES_LEN,), 5, hidden=128)
    feats_net = fit_clone(
        mlp.actor, norm(train.features), train.labels, args.features_epochs, args.seed, args.features_lr, args.device
    )
    feats_net.eval()
    rows = []
    for name, net, x in (
        ("clone_frames", frames_net, held.frames),
        ("clone_features", feats_net, norm(held.features)),
    ):
        agree = float((predict(net, x, args.device).argmax(-1) == held.labels).mean())
        rows.append(dict(measurement=f"{name}_agreement", metric="accuracy", value=agree, baseline=base))

    def greedy(net: nn.Module, prepare: Callable[[np.ndarray], np.ndarray]) -> Callable[..., np.ndarray]:
        def act(obs: np.ndarray, _envs: Any) -> np.ndarray:
            with torch.no_grad():
                return net(torch.from_numpy(prepare(obs)).to(args.device)).argmax(-1).cpu().numpy()

        return act

    def builtin(name: str) -> Any:
        class Player:
            policy: Any = None

            def start_chunk(self, n: int, seed: int) -> None:
                self.policy = VectorPolicy(name, n, seed=seed)

            def __call__(self, _obs: np.ndarray, envs: Any) -> np.ndarray:
                return np.asarray(self.policy.act(envs))

        return Player()

    features_env = {**rule_options, "obs_type": "features"}
    flights: list[tuple[str, Any, dict[str, Any]]] = [
        ("clone_frames_flown", greedy(frames_net, np.asarray), pixel_options),
        ("clone_features_flown", greedy(feats_net, norm), features_env),
        ("heuristic_flown", builtin("heuristic"), features_env),
        ("random_flown", builtin("random"), features_env),
    ]
    t0 = time.monotonic()
    for name, act, options in flights:
        s = episodes.summary(episodes.play_episodes(act, args.eval_episodes, args.eval_seed, options))
        rows.append(
            dict(
                measurement=name,
                metric="mean_return",
                value=s["mean_return"],
                std=s["std_return"],
                support=s["episodes"],
                positive_share=s["causes"].get("bird", 0.0),
            )
        )
    rows.append(dict(measurement="fly_seconds", metric="seconds", value=round(time.monotonic() - t0, 1)))
    return rows


def run_size(size: int, args: argparse.Namespace, extra: dict[str, Any]) -> list[dict[str, Any]]:
    from chopperscape.options import RULE_OPTIONS

    t0, c0 = time.monotonic(), time.process_time()
    pixel_options: dict[str, Any] = dict(obs_type="grayscale", frame_stack=4, frame_skip=4)
    pixel_options.update(extra)
    pixel_options["obs_size"] = [size, size]
    rule_options = {k: v for k, v in pixel_options.items() if k in RULE_OPTIONS}
    held_n = max(args.samples // 4, 1)
    train = collect(args.samples, args.num_envs, args.seed, pixel_options, rule_options)
    held = collect(held_n, args.num_envs, HELD_OUT_SEED + args.seed, pixel_options, rule_options)
    t_collect = time.monotonic() - t0
    net, mean, std = fit_regressor(train, args.epochs, args.seed, args.lr, args.device)
    pred = predict(net, held.frames, args.device) * std + mean
    rows = perception_rows(held, pred, train, size)
    t_regress = time.monotonic() - t0 - t_collect
    rows += clone_rows(train, held, args, pixel_options, rule_options)
    wall, cpu = time.monotonic() - t0, time.process_time() - c0
    for name, value in (
        ("collect_seconds", t_collect),
        ("regress_seconds", t_regress),
        ("wall_seconds", wall),
        ("cpu_seconds", cpu),
    ):
        rows.append(dict(measurement=name, metric="seconds", value=round(value, 1)))
    shared = dict(
        size=f"{size}x{size}",
        samples=len(train.labels),
        held_out=len(held.labels),
        epochs=args.epochs,
        features_epochs=args.features_epochs,
        lr=args.lr,
        seed=args.seed,
        options=json.dumps(extra, sort_keys=True),
    )
    out = []
    for row in rows:
        full: dict[str, Any] = dict.fromkeys(CSV_FIELDS, "")
        full.update(shared)
        full.update({k: round(v, 4) if isinstance(v, float) else v for k, v in row.items()})
        out.append(full)
    return out


def append_csv(path: str, rows: list[dict[str, Any]]) -> None:
    """Appends `rows` in one write under an exclusive lock (the header when the file is empty), so concurrent runs
    on one file do not interleave."""
    buf = io.StringIO()
    writer = csv.DictWriter(buf, CSV_FIELDS, lineterminator="\n")
    for row in rows:
        writer.writerow(row)
    body = buf.getvalue()
    fd = os.open(path, os.O_WRONLY | os.O_APPEND | os.O_CREAT, 0o644)
    try:
        fcntl.flock(fd, fcntl.LOCK_EX)
        data = body if os.fstat(fd).st_size else ",".join(CSV_FIELDS) + "\n" + body
        os.write(fd, data.encode())
        os.fsync(fd)
    finally:
        os.close(fd)


def markdown(rows: list[dict[str, Any]]) -> str:
    """One line per measurement, one column per size: `value (baseline …)`."""
    sizes = list(dict.fromkeys(r["size"] for r in rows))
    names = list(dict.fromkeys(r["measurement"] for r in rows))
    cell: dict[tuple[str, str], str] = {}
    for r in rows:
        if r["metric"] == "r2":
            text = f"R² {r['value']:.3f} (mean: {r['baseline']:.3f}; n {r['support']})"
        elif r["metric"] == "accuracy" and r["positive_share"] != "":
            share = 100 * r["positive_share"]
            text = f"{100 * r['value']:.1f} % (majority {100 * r['baseline']:.1f} %, positives {share:.1f} %)"
        elif r["metric"] == "accuracy":
            text = f"{100 * r['value']:.1f} % (majority action {100 * r['baseline']:.1f} %)"
        elif r["metric"] == "mean_return":
            text = f"{r['value']:,.0f} ± {r['std']:,.0f} ({r['support']} ep., bird {100 * r['positive_share']:.0f} %)"
        else:
            text = f"{r['value']:,.1f}"
        cell[(r["measurement"], r["size"])] = text
    lines = ["| measurement | " + " | ".join(sizes) + " |", "|---|" + "---|" * len(sizes)]
    lines += [f"| {n} | " + " | ".join(cell.get((n, s), "") for s in sizes) + " |" for n in names]
    return "\n".join(lines)


def main() -> None:
    p = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    p.add_argument("--size", action="append", help="frame size, repeatable or a comma list (default 84,42)")
    p.add_argument(
        "--option", action="append", default=[], metavar="K=V", help="a pixel-env option (JSON value), repeatable"
    )
    p.add_argument("--samples", type=int, default=100_000, help="training decisions per size (held out: a quarter)")
    p.add_argument("--epochs", type=int, default=4, help="epochs of the CNN regressor and of the frames clone")
    p.add_argument("--lr", type=float, default=1e-3, help="Adam's learning rate for the CNNs")
    p.add_argument("--features-epochs", type=int, default=30, help="epochs of the features clone (cheap)")
    p.add_argument("--features-lr", type=float, default=1e-3, help="Adam's learning rate for the features clone")
    p.add_argument("--num-envs", type=int, default=64, help="envs of a collecting batch")
    p.add_argument("--eval-episodes", type=int, default=50)
    p.add_argument("--eval-seed", type=int, default=HELD_OUT_SEED)
    p.add_argument("--seed", type=int, default=0)
    p.add_argument("--threads", type=int, default=1, help="torch threads (default 1)")
    p.add_argument("--device", default="cpu", help="torch device of the networks, e.g. cuda (default cpu)")
    p.add_argument("--out", help="CSV file to append one row per size × measurement to")
    a = p.parse_args()
    sizes = [int(s) for item in (a.size or ["84,42"]) for s in item.split(",") if s.strip()]
    extra: dict[str, Any] = {}
    for item in a.option:
        key, sep, value = item.partition("=")
        if not sep or not key.strip():
            p.error(f"--option {item!r}: expected K=V")
        try:
            extra[key.strip()] = json.loads(value)
        except ValueError:
            extra[key.strip()] = value  # plain text: the env reads it as a string
    import torch

    torch.set_num_threads(a.threads)
    rows: list[dict[str, Any]] = []
    for size in sizes:
        done = run_size(size, a, extra)
        if a.out:
            append_csv(a.out, done)
        rows += done
        print(markdown(done), flush=True)
    print(markdown(rows))
    summary = {r["size"] + ":" + r["measurement"]: r["value"] for r in rows}
    print(json.dumps(summary))


if __name__ == "__main__":
    main()
