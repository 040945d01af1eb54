"""Evaluates a trained policy on held-out seeds and prints one JSON object.

    python -m chopperscape.learn.evaluate MODEL --episodes 100 --seed 1000000

`MODEL` is a file written by ``python -m chopperscape.learn.train`` (``model.pt``), a Stable-Baselines3 ``.zip`` (then
give the env options it was trained with: ``--option obs_type=features``; a ``vecnormalize.json`` beside it, from
``chopperscape.integrations.sb3_files.save_normalization``, normalises the observations as in training), or the
name of a built-in policy (``random``, ``heuristic``, ``noop``…, see ``chopperscape.policies``), so that baselines
come from the same seeds; a file named like a built-in policy is given as ``./NAME``.

Loading a model never runs code from it: a recipe model is read with ``torch.load(weights_only=True)`` (tensors
and plain data), and the pickled parts of an SB3 ``.zip`` are replaced by what the env gives. Pickles (SB3's
``vecnormalize.pkl``, an SB3 model whose settings cannot be rebuilt) are refused unless ``--trust-pickle``: give it
only for files whose author you trust.

Episode ``k`` is played on seed ``S + k`` (the seeds of a ``VectorEnv`` reset with ``seed=S``), each to its end or
to the 10,000-step truncation (``--option max_episode_steps=N``, or ``none``; a recipe model trained with
``--option max_episode_steps=N`` plays to its own ``N`` unless ``--option`` gives another; one trained with ``none``
to 10,000), with the greedy action
(``--stochastic`` samples instead, from a generator seeded with ``S``). The output:

    {"model": ..., "episodes": 100, "seed": 1000000, "mean_return": ..., "std_return": ..., "min_return": ...,
     "max_return": ..., "mean_steps": ..., "causes": {"bird": 0.62, "fuel": 0.08, "truncated": 0.30}, ...}

Memory does not grow with ``--episodes`` (at most 1,000,000): episodes are played ``CHUNK`` at a time and summarised
as they end, and the ``--per-episode`` rows wait in a temporary file until the line is written. ``causes`` gives
the share of episodes that ended each way (``--per-episode`` adds each episode's seed,
return, steps and cause: the episodes ``chopperscape demo --policy MODEL.onnx --json`` plays for the same
``--seed``, from the export of the same model).

``--video out.gif`` (or ``out.mp4``, through the ``ffmpeg`` program) also writes the first ``--video-episodes K``
episodes (default 1) one after the other, at 30 frames a second, as the command line's ``record`` draws them
(600 × 800, the text HUD). The episodes are played first and their actions replayed to draw them, so the video
shows exactly the episodes of the result line.
"""

from __future__ import annotations

import argparse
import itertools
import json
import sys
import tempfile
from pathlib import Path
from typing import Any

from .._cli import cannot, env_options, print_chunks, print_line, run_command
from .episodes import MAX_EPISODES, Summary, iter_episodes
from .players import BuiltinPlayer, load_policy

#: `--option` names evaluation does not take, and why.
REFUSED_OPTIONS = {
    "num_threads": "evaluation steps its own batch on one thread (results do not depend on threads)",
    "autoreset_mode": "evaluation plays each episode once to its end; it needs no autoreset mode",
    "copy": "evaluation reads each step's arrays itself; it takes no `copy`",
    "render_mode": "evaluation draws nothing itself; give --video FILE (.gif or .mp4) for a video",
}


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m chopperscape.learn.evaluate", description=__doc__.splitlines()[0])
    p.add_argument(
        "model",
        help="model.pt from chopperscape.learn.train, an SB3 .zip, or a built-in policy's name (a file "
        "named like one: ./NAME)",
    )
    p.add_argument("--episodes", type=int, default=100, help="episodes to play (default 100)")
    p.add_argument("--seed", type=int, default=1_000_000, help="first seed (default 1000000, held out from training)")
    p.add_argument("--stochastic", action="store_true", help="sample actions instead of taking the greedy one")
    p.add_argument(
        "--option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="env option, as the command line's flags take it (obs_size=84x84, hud=false, max_episode_steps=none)",
    )
    p.add_argument("--per-episode", action="store_true", help="also list every episode")
    p.add_argument(
        "--video",
        metavar="FILE",
        help="also write the first episodes as a video: .gif (Pillow) or .mp4 "
        "(needs the ffmpeg program); an existing file is replaced",
    )
    p.add_argument(
        "--video-episodes", type=int, default=1, metavar="K", help="episodes in the --video, from the first (default 1)"
    )
    p.add_argument(
        "--trust-pickle",
        action="store_true",
        help="allow pickled parts of an SB3 .zip and a vecnormalize.pkl beside it: pickles run code when "
        "loaded, so only for files whose author you trust",
    )
    a = p.parse_args(argv)
    if not 1 <= a.episodes <= MAX_EPISODES:
        p.error(f"--episodes {a.episodes}: allowed an integer in 1..={MAX_EPISODES}")
    if not 0 <= a.seed < 2**63:
        p.error(f"--seed {a.seed}: allowed 0 <= seed < 2**63")
    if not 1 <= a.video_episodes <= a.episodes:
        p.error(f"--video-episodes {a.video_episodes}: allowed 1..=--episodes ({a.episodes})")
    options = env_options(p, a.option, refused=REFUSED_OPTIONS)
    return run_command(lambda: evaluate(a, options))


def evaluate(a: argparse.Namespace, options: dict[str, Any]) -> int:
    """The evaluation `main` runs, from its checked flags `a` and env `options`: plays, prints the result line and
    returns 0 (or the status of a closed or failing standard output); raises what `run_command` maps to a
    status."""
    given = "max_episode_steps" in options
    limit = options.pop("max_episode_steps", 10_000)
    keep = a.video_episodes if a.video is not None else 0
    if a.video is not None:
        from . import video

        video.check_destination(Path(a.video))
    act, play_options = load_policy(a.model, a.stochastic, a.seed, options, trust_pickle=a.trust_pickle)
    # The model's own truncation (a recipe model trained with max_episode_steps=N) unless --option gives one;
    # a model trained without one (`none`) is still evaluated to 10,000 steps, so that evaluation ends.
    if given or play_options.get("max_episode_steps") is None:
        play_options["max_episode_steps"] = limit
    limit = play_options["max_episode_steps"]
    acc = Summary()
    kept: list[dict[str, Any]] = []
    rows = None
    try:
        # The per-episode rows wait in a temporary file, not in memory, until the result line is written.
        with cannot("hold the per-episode rows in a temporary file"):
            rows = tempfile.TemporaryFile("w+", encoding="utf-8") if a.per_episode else None
            for i, r in enumerate(iter_episodes(act, a.episodes, a.seed, play_options, keep_actions=keep)):
                acc.add(r)
                if i < keep:
                    kept.append(r)
                if rows is not None:
                    rows.write(("" if i == 0 else ", ") + json.dumps({k: v for k, v in r.items() if k != "actions"}))
        if a.video is not None:
            with cannot(f"write {a.video}"):
                video.write(Path(a.video), play_options, kept)
        out: dict[str, Any] = {"model": str(a.model), "seed": a.seed}
        if not isinstance(act, BuiltinPlayer):
            out["greedy"] = not a.stochastic
        if limit != 10_000:
            out["max_episode_steps"] = limit
        out.update(acc.result())
        tail = {"video": a.video} if a.video is not None else {}
        if rows is None:
            return print_line(json.dumps({**out, **tail}))
        rows.seek(0)
        head = json.dumps(out)[:-1] + ', "per_episode": ['
        end = "]" + (", " + json.dumps(tail)[1:] if tail else "}")
        return print_chunks(itertools.chain([head], iter(lambda: rows.read(1 << 16), ""), [end]))
    finally:
        if rows is not None:
            rows.close()


if __name__ == "__main__":
    sys.exit(main())
