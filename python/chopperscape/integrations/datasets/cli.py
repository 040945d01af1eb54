"""`python -m chopperscape.integrations.datasets`: what `chopperscape dataset` runs (see `--help`)."""

from __future__ import annotations

import argparse

from ... import _cli, policies
from . import DEFAULT_OBS_TYPE, collect, from_action_logs


def main(argv: list[str] | None = None) -> int:
    """`python -m chopperscape.integrations.datasets`: what `chopperscape dataset` runs (see `--help`)."""
    parser = argparse.ArgumentParser(
        prog="python -m chopperscape.integrations.datasets",
        description="Write a Minari dataset of ChopperScape-v0 episodes (under MINARI_DATASETS_PATH). "
        f"Observations are {DEFAULT_OBS_TYPE} unless --option obs_type=... says otherwise.",
    )
    parser.add_argument("--out", required=True, help='the dataset id, e.g. "chopperscape/heuristic-v0"')
    parser.add_argument("--policy", choices=policies.NAMES, help="the built-in policy (default heuristic)")
    parser.add_argument("--episodes", type=int, help="episodes to play (default 1)")
    parser.add_argument("--seed", type=int, help="seed of the first episode (default 0)")
    parser.add_argument("--from-logs", nargs="+", metavar="LOG", help="replay these action logs instead of a policy")
    parser.add_argument(
        "--option",
        action="append",
        default=[],
        metavar="NAME=VALUE",
        help="an env option, as the command line's flags take it (obs_size=84x84, hud=false, max_episode_steps=none)",
    )
    parser.add_argument("--chunk-steps", type=int, default=1000)
    parser.add_argument("--no-progress", action="store_true")
    args = parser.parse_args(argv)
    options = _cli.env_options(parser, args.option)
    if args.from_logs:
        given = [f"--{n}" for n in ("policy", "episodes", "seed") if getattr(args, n) is not None]
        if given:
            parser.error(
                f"{', '.join(given)} cannot be given with --from-logs: the logs hold their own seeds and actions"
            )
    limit = options.pop("max_episode_steps", 10_000)
    progress = False if args.no_progress else None

    def command() -> int:
        if args.from_logs:
            if "max_episode_steps" in [o.partition("=")[0].strip() for o in args.option]:
                raise ValueError(
                    "--option max_episode_steps cannot be given with --from-logs: the logs hold their own rules"
                )
            ds = from_action_logs(args.out, args.from_logs, chunk_steps=args.chunk_steps, progress=progress, **options)
        else:
            ds = collect(
                args.out,
                args.policy or "heuristic",
                1 if args.episodes is None else args.episodes,
                0 if args.seed is None else args.seed,
                max_episode_steps=limit,
                chunk_steps=args.chunk_steps,
                progress=progress,
                **options,
            )
        return _cli.print_line(
            f"wrote {ds.total_episodes} episodes ({ds.total_steps} steps) to {ds.storage.data_path.parent}"
        )

    return _cli.run_command(command)
