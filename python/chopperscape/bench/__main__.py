"""`python -m chopperscape.bench {modes,evaluate,report,row}` (see `chopperscape.bench`)."""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .._cli import parse_options, print_line, run_command
from ..modes import MODES
from ..options import ENV_OPTIONS
from . import evaluate, protocol, record, report, results
from . import rows as trained_rows


def main(argv: list[str] | None = None) -> int:
    p = argparse.ArgumentParser(prog="python -m chopperscape.bench", description=__doc__.splitlines()[0])
    sub = p.add_subparsers(dest="command", required=True)
    sub.add_parser("modes", help="the difficulty modes and the protocol, as JSON")
    e = sub.add_parser("evaluate", help="evaluate a policy on one mode under the protocol")
    e.add_argument("policy", help="a built-in policy, a .pt, .onnx or SB3 .zip file, or pkg.mod:func")
    e.add_argument("--mode", required=True, choices=[m["name"] for m in MODES])
    e.add_argument("--policy-seed", type=int, default=0, help="the run: seeds a stochastic policy (default 0)")
    e.add_argument(
        "--stochastic",
        action="store_true",
        help="sample a trained policy's actions (not greedy); a callable's if it can",
    )
    e.add_argument(
        "--policy-arg",
        action="append",
        default=[],
        metavar="KEY=VALUE",
        help="an argument of a callable policy factory pkg.mod:func (recorded), e.g. weights=model.pt",
    )
    e.add_argument("--option", action="append", default=[], metavar="NAME=VALUE", help="observation option")
    e.add_argument("--trust-pickle", action="store_true", help="allow pickled parts of an SB3 .zip (runs code)")
    e.add_argument(
        "--train-seeds",
        metavar="FIRST:COUNT",
        help="the reset seeds the policy was trained on, where its file does not say (checked, recorded)",
    )
    e.add_argument(
        "--name",
        help="the leaderboard row this run belongs to (the runs of one recipe's training seeds share it); "
        "default: the policy's source",
    )
    e.add_argument(
        "--training",
        metavar="FILE",
        help="a trained row's training record (RUN/training.json, written by `bench row`): recorded, its seeds checked",
    )
    e.add_argument("--out", metavar="FILE", help="write the results file here (atomically); default: print it")
    r = sub.add_parser("report", help="aggregates with 95 %% intervals over results files, and their plots")
    r.add_argument("results", nargs="+", metavar="RESULTS")
    r.add_argument("--plots", metavar="DIR", help="write intervals.FMT and profile.FMT here")
    r.add_argument("--format", choices=("png", "svg"), default="png")
    r.add_argument("--pool-modes", action="store_true", help="one row per policy over its modes (tasks)")
    r.add_argument("--json", action="store_true", help="print the rows as JSON instead of a Markdown table")
    r.add_argument(
        "--partial",
        action="store_true",
        help="show a row with fewer or more runs than the protocol's, marked partial (default: refused)",
    )
    r.add_argument("--resamples", type=int, default=report.RESAMPLES, help=argparse.SUPPRESS)
    trained_rows.add_parser(sub)
    given = sys.argv[1:] if argv is None else list(argv)
    a = p.parse_args(given)

    def command() -> int:
        if a.command == "modes":
            return print_line(json.dumps({"modes": MODES, "protocol": protocol.PROTOCOL}, indent=2))
        if a.command == "evaluate":
            options = parse_options(a.option, ENV_OPTIONS)
            seeds = None
            if a.train_seeds is not None:
                first, sep, count = a.train_seeds.partition(":")
                try:
                    seeds = (int(first), int(count) if sep else 1)
                except ValueError:
                    p.error(f"--train-seeds {a.train_seeds!r}: expected FIRST:COUNT, e.g. 0:64")
            policy_args: dict[str, str] = {}
            for item in a.policy_arg:
                key, sep, value = item.partition("=")
                if not sep or key in policy_args:
                    p.error(f"--policy-arg {item!r}: expected KEY=VALUE, each KEY once, e.g. weights=model.pt")
                policy_args[key] = value
            if a.out is not None:
                results.check_out(a.out, a.policy)
            training = None if a.training is None else record.read_training(a.training)
            command = ["python", "-m", "chopperscape.bench", *given]
            doc = evaluate.run(
                a.policy,
                a.mode,
                options,
                a.stochastic,
                a.policy_seed,
                a.trust_pickle,
                seeds,
                a.name,
                training,
                command,
                policy_args,
            )
            text = results.dumps(doc)
            if a.out is None:
                return print_line(text.rstrip("\n"))
            report.check_joins(doc, a.out)
            results.write_atomic(a.out, text)
            s = doc["summary"]
            return print_line(f"{a.out}: {a.mode}, mean return {s['mean_return']}, score {s['score']}")
        if a.command == "row":
            return trained_rows.main(a)
        if not 100 <= a.resamples <= report.MAX_RESAMPLES:
            p.error(f"--resamples {a.resamples}: allowed an integer in 100..={report.MAX_RESAMPLES}")
        docs = report.load_all(a.results)
        report.check_settings(docs, a.results)
        rows = report.report(docs, a.resamples, a.pool_modes, a.partial)
        if a.plots:
            report.plot(docs, rows, Path(a.plots), a.format, a.pool_modes)
        return print_line(json.dumps(rows, indent=2) if a.json else report.markdown(rows).rstrip("\n"))

    return run_command(command)


if __name__ == "__main__":
    sys.exit(main())
