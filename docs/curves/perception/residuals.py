#!/usr/bin/env python3
"""Side probe of the perception check (README.md beside this file): where the regressor's dx/dy error comes from.

    python residuals.py fit 84 600000 30 OUTDIR --device cuda   # the regressor only; held-out values + predictions
    python residuals.py analyse OUTDIR 84                         # share of the error in gross misses, per slot case

`fit` uses `python/examples/perception.py` (the same dataset, regressor and defaults) and saves the held-out values
and predictions of the columns below as float16 `.npy` files; `analyse` reads them back.
"""

from __future__ import annotations

import argparse
import os
import sys

import numpy as np

#: Saved columns of the features vector: chopper_y, fuel, bird slots 0 and 1, tank slots 0 and 1.
COLUMNS = [1, 2, *range(4, 12), *range(20, 28)]


def fit(size: int, samples: int, epochs: int, out: str, device: str) -> None:
    import torch

    sys.path.insert(0, os.path.join(os.path.dirname(__file__), "..", "..", "..", "python", "examples"))
    import perception as p

    torch.set_num_threads(4)
    options = dict(obs_type="grayscale", frame_stack=4, frame_skip=4, obs_size=[size, size])
    train = p.collect(samples, 64, 0, options, {"frame_skip": 4})
    held = p.collect(samples // 4, 64, p.HELD_OUT_SEED, options, {"frame_skip": 4})
    net, mean, std = p.fit_regressor(train, epochs, 0, 1e-3, device)
    pred = p.predict(net, held.frames, device) * std + mean
    for row in p.perception_rows(held, pred, train, size):
        print(row, flush=True)
    np.save(os.path.join(out, f"held{size}.npy"), held.features[:, COLUMNS].astype(np.float16))
    np.save(os.path.join(out, f"pred{size}.npy"), pred[:, COLUMNS].astype(np.float16))


def r2(y: np.ndarray, q: np.ndarray) -> float:
    return float(1 - ((y - q) ** 2).sum() / ((y - y.mean()) ** 2).sum())


def analyse(out: str, size: int) -> None:
    held = np.load(os.path.join(out, f"held{size}.npy")).astype(np.float64)
    pred = np.load(os.path.join(out, f"pred{size}.npy")).astype(np.float64)
    at = {c: i for i, c in enumerate(COLUMNS)}
    print(f"{size}x{size}: one frame row is {600 / size / 480:.4f} of dy, one column {1 / size:.4f} of dx")
    for name, present, col, other_present in (
        ("bird0_dx", 4, 5, 8),
        ("bird0_dy", 4, 6, 8),
        ("tank0_dx", 20, 21, 24),
        ("tank0_dy", 20, 22, 24),
    ):
        keep = held[:, at[present]] == 1
        y, q = held[keep, at[col]], pred[keep, at[col]]
        err = q - y
        gross = np.abs(err) > 0.1
        two = held[keep, at[other_present]] == 1
        share = (err[gross] ** 2).sum() / (err**2).sum()
        print(
            f"{name}: R² {r2(y, q):.3f}, median |error| {np.median(np.abs(err)):.4f}; errors over 0.1: "
            f"{100 * gross.mean():.1f} % of samples, {100 * share:.0f} % of the squared error, R² without them "
            f"{r2(y[~gross], q[~gross]):.3f}; slot 1 filled in {100 * two.mean():.0f} % of samples and "
            f"{100 * two[gross].mean():.0f} % of those errors; R² with slot 1 empty {r2(y[~two], q[~two]):.3f}, "
            f"filled {r2(y[two], q[two]):.3f}"
        )


def main() -> None:
    p = argparse.ArgumentParser(description=(__doc__ or "").splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    f = sub.add_parser("fit")
    f.add_argument("size", type=int)
    f.add_argument("samples", type=int)
    f.add_argument("epochs", type=int)
    f.add_argument("out")
    f.add_argument("--device", default="cpu")
    a = sub.add_parser("analyse")
    a.add_argument("out")
    a.add_argument("size", type=int)
    args = p.parse_args()
    if args.command == "fit":
        fit(args.size, args.samples, args.epochs, args.out, args.device)
    else:
        analyse(args.out, args.size)


if __name__ == "__main__":
    main()
