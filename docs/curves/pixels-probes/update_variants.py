"""The pixel update's minibatch step (forward, backward, Adam) under the CPU variants issue 43 lists, timed back to
back with no loop around it: the network's memory format (contiguous or channels-last), `torch.compile`, the
minibatch size and the torch threads. A benchmark, not a test; run it with the machine quiet.

    .venv/bin/python docs/curves/pixels-probes/update_variants.py [--network small-coord] [--threads 1,2]

Prints µs per sample of one minibatch step for each variant (the median of `--repeats` timings of 8 steps).
"""

from __future__ import annotations

import argparse
import statistics
import time

import torch

from chopperscape.learn.networks import build_agent


def step_time(network: str, batch: int, threads: int, channels_last: bool, compiled: bool, repeats: int) -> float:
    torch.set_num_threads(threads)
    torch.manual_seed(0)
    agent = build_agent(network, (42, 42, 4), invert_frames=True)
    if channels_last:
        agent = agent.to(memory_format=torch.channels_last)
    opt = torch.optim.Adam(agent.parameters(), lr=1e-3, eps=1e-5)
    frames = torch.randint(0, 256, (batch, 42, 42, 4), dtype=torch.uint8)
    actions = torch.randint(0, 5, (batch,))
    adv = torch.randn(batch)

    def loss_of(x: torch.Tensor) -> torch.Tensor:
        logits, value, _ = agent.heads(x)
        logp = torch.log_softmax(logits, -1).gather(1, actions[:, None]).squeeze(1)
        return -(logp * adv).mean() + 0.5 * (value - adv).pow(2).mean()

    fn = torch.compile(loss_of) if compiled else loss_of

    def one() -> None:
        opt.zero_grad(set_to_none=True)
        fn(frames).backward()
        torch.nn.utils.clip_grad_norm_(agent.parameters(), 0.5)
        opt.step()

    for _ in range(3):
        one()
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        for _ in range(8):
            one()
        times.append((time.perf_counter() - t0) / (8 * batch))
    return statistics.median(times) * 1e6


def main() -> None:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--network", default="small-coord")
    p.add_argument("--threads", default="1,2")
    p.add_argument("--batches", default="1024,2048")
    p.add_argument("--repeats", type=int, default=5)
    p.add_argument("--no-compile", action="store_true", help="skip torch.compile (it needs a C++ compiler)")
    a = p.parse_args()
    print(f"# torch {torch.__version__}, network {a.network}, µs per sample of one minibatch step (fwd+bwd+Adam)")
    print("| threads | minibatch | contiguous | channels-last | compiled |")
    print("|---:|---:|---:|---:|---:|")
    for threads in (int(t) for t in a.threads.split(",")):
        for batch in (int(b) for b in a.batches.split(",")):
            row = [step_time(a.network, batch, threads, cl, False, a.repeats) for cl in (False, True)]
            comp = "–" if a.no_compile else f"{step_time(a.network, batch, threads, False, True, a.repeats):.1f}"
            print(f"| {threads} | {batch} | {row[0]:.1f} | {row[1]:.1f} | {comp} |", flush=True)


if __name__ == "__main__":
    main()
