"""The leaderboard's trained rows, declared once (:data:`ROWS`): each row's trainer, settings, budget, modes and seed
scheme, and the command that trains a row's seeds and evaluates them under the protocol.

    python -m chopperscape.bench row NAME --mode MODE --seeds 0-9 --runs DIR [--results DIR] [--steps N] [--dry-run]

For each training seed S (`--seeds`: numbers and ranges, `0-9`, `0,3,5`, `0-4,7`), one at a time:

- a seed whose results file `RESULTS/MODE.NAME.seedS.json` exists is skipped (a stopped row continues where it
  stopped);
- the seed is claimed by an advisory lock on `RUNS/seed-S.lock` (`fcntl.flock`, released when its process ends,
  however it ends): a seed another process holds is skipped, so several `bench row` on one row share its seeds, one
  process a core;
- the row's trainer trains it into `RUNS/seed-S/` (its output in `RUNS/seed-S.log`), resuming from the run's
  checkpoint where the trainer keeps one (`chopperscape.learn.train`'s `resume.pt`), and skipped when
  `RUNS/seed-S/training.json` says this row, mode, seed and budget were trained already;
- the training record (:mod:`.record`: the exact command, the project's commit, the trainer's full settings, the
  training seeds as the trainer used them) is written to `RUNS/seed-S/training.json`;
- `python -m chopperscape.bench evaluate MODEL --mode MODE --name ROW'S NAME --training ... --out RESULTS/...`
  evaluates the model by the protocol; the results file carries the training record.

`--dry-run` prints each command (shell-quoted, one a line) instead. `--steps` changes a row's budget, and its name
with it ("3 M decisions"). Exit status 0; 2 with one line naming a bad argument; 1 when a training or an evaluation
fails (its log named); 130 and such when interrupted.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import re
import shlex
import subprocess
import sys
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, TextIO

from .. import _atomic
from .._cli import print_line
from . import record

#: The modes a trained row is trained and evaluated on (frame skip 4).
TRAINED_MODES = ("sticky-v0", "full-v0")
#: The largest training seed `--seeds` takes, and the most seeds in one command.
MAX_SEED, MAX_SEEDS = 999_999, 1000
#: RLlib's seed stride (`chopperscape.integrations.rllib.SEED_STRIDE`; that module imports Ray).
RLLIB_SEED_STRIDE = 2**20


def _fast() -> Any:
    from ..learn.recipe import PRESETS, Recipe

    return Recipe(**{k: v for k, v in PRESETS["fast"].items() if k != "total_steps"})


def _learn(preset: str | None, flags: tuple[str, ...] = ()) -> Callable[[], dict[str, Any]]:
    """The recipe trainer's settings: a preset (None: the recipe's defaults) and flags after it."""
    return lambda: {"preset": preset, "flags": list(flags)}


#: The pixel preset until the ninth session (issue 28's p3: the plain small CNN, 2 epochs of 4 minibatches at lr 1e-3,
#: the value loss at 0.5, no novelty bonus) as flags over today's `--preset pixels`: the leaderboard's first pixel
#: rows were trained with it, under the key `pixels` and the name that row `pixels-p3` keeps.
PIXELS_P3_FLAGS = (
    "--network", "small", "--update-epochs", "2", "--num-minibatches", "4", "--learning-rate", "1e-3",
    "--vf-coef", "0.5", "--rnd-coef", "0", "--no-rnd-own-value", "--rnd-pool", "1",
)  # fmt: skip


#: How `--preset pixels` is trained at its stated budget (12 M decisions since the thirty-first session; issue 43's
#: target protocol, `docs/curves/pixels-probes/target43.sh`): compiled, on two threads, one seed at a time (about 40
#: minutes a seed on a 2-vCPU Zen 5 EPYC, 100 on a Zen 3 one). They change the speed, not the recipe's learning.
PIXELS_SPEED_FLAGS = ("--torch-compile", "--torch-threads", "2")


def _sb3_ppo() -> dict[str, Any]:
    from ..integrations.sb3_train import recipe_settings

    return recipe_settings(_fast())


def _rllib_ppo() -> dict[str, Any]:
    """The fast preset in RLlib's terms, one runner of its 128 games (`rllib.flags.recipe_settings`, tested equal)."""
    r = _fast()
    batch = r.num_envs * r.num_steps
    return {
        "env-runners": 1,
        "envs-per-runner": r.num_envs,
        "train-batch-size": batch,
        "minibatch-size": batch // r.num_minibatches,
        "epochs": r.update_epochs,
        "lr": r.learning_rate,
        "gamma": r.gamma,
        "lambda": r.gae_lambda,
        "entropy": r.ent_coef,
        "clip": r.clip_coef,
        "kl-coeff": 0.0,
        "hidden": f"{r.hidden},{r.hidden}",
        "init": "orthogonal",
        "obs-filter": "synced",
        "env-config": {"obs_type": "features", **dict(r.env_options)},
    }


@dataclass(frozen=True)
class Row:
    """A trained row: `title` with `{budget}` is its leaderboard name; `trainer` one of `learn`, `sb3-ppo`,
    `sb3-dqn`, `rllib-ppo`; `settings()` what the row gives its trainer (a preset's name, the SB3 trainer's settings
    over its defaults, the RLlib trainer's flags); `steps` its budget in decisions; `seeds` its seed scheme."""

    key: str
    title: str
    trainer: str
    settings: Callable[[], dict[str, Any]]
    steps: int
    model: str
    seeds: str
    modes: tuple[str, ...] = TRAINED_MODES

    def name(self, steps: int | None = None) -> str:
        return self.title.format(budget=budget(self.steps if steps is None else steps))


_RECIPE_SEEDS = "training seed S: games S … S + num_envs − 1 (one reset each; autoresets continue their generators)"
#: The trained rows, by the key their results files carry (`MODE.KEY.seedS.json`).
ROWS: dict[str, Row] = {
    r.key: r
    for r in (
        Row("fast", "fast preset: PPO on features, {budget} decisions", "learn", _learn("fast"), 3_000_000,
            "model.pt", _RECIPE_SEEDS),
        Row("features", "features recipe: PPO on features, {budget} decisions", "learn", _learn(None), 3_000_000,
            "model.pt", _RECIPE_SEEDS),
        Row("sb3-ppo", "SB3 PPO, the fast preset's settings, {budget} decisions", "sb3-ppo", _sb3_ppo, 3_000_000,
            "model.zip", "training seed S: games S … S + 127 (SB3 seeds env i with S + i)"),
        Row("sb3-dqn", "SB3 DQN, stock, {budget} decisions", "sb3-dqn", dict, 500_000, "model.zip",
            "training seed S: game S (one env)"),
        Row("rllib-ppo", "RLlib PPO, the fast preset's settings, {budget} decisions", "rllib-ppo", _rllib_ppo,
            3_000_000, "model.onnx", "training seed S: runner 1's games (S + 1) · 2**20 + i, i = 0 … 127"),
        Row("pixels", "pixel preset with RND: PPO on 42x42 frames alone, {budget} decisions", "learn",
            _learn("pixels", PIXELS_SPEED_FLAGS), 12_000_000, "model.pt", _RECIPE_SEEDS),
        Row("pixels-p3", "pixel preset: PPO on 42x42 frames alone, {budget} decisions", "learn",
            _learn("pixels", PIXELS_P3_FLAGS), 1_000_000, "model.pt", _RECIPE_SEEDS),
    )
}  # fmt: skip


def budget(steps: int) -> str:
    """A budget as a row's name says it: 3000000 is "3 M", 250000 "250 k", 2048 "2,048"."""
    if steps % 1_000_000 == 0:
        return f"{steps // 1_000_000} M"
    return f"{steps // 1000} k" if steps % 1000 == 0 else f"{steps:,}"


def parse_seeds(text: str) -> list[int]:
    """Training seeds given as numbers and ranges, `0-9`, `0,3,5`, `0-4,7` (sorted, each once); `ValueError` saying
    what is allowed for anything else (a shell glob, a negative or reversed range, too many seeds)."""
    allowed = f"allowed numbers and ranges such as 0-9 or 0,3,5 (seeds 0 to {MAX_SEED}, at most {MAX_SEEDS})"
    if not re.fullmatch(r"\d{1,7}(-\d{1,7})?(,\d{1,7}(-\d{1,7})?)*", text):
        raise ValueError(f"--seeds {text!r}: {allowed}")
    seeds: set[int] = set()
    for part in text.split(","):
        lo, _, hi = part.partition("-")
        first, last = int(lo), int(hi or lo)
        if first > last or last > MAX_SEED or len(seeds) + last - first + 1 > MAX_SEEDS:
            raise ValueError(f"--seeds {text!r}: {part!r} is out of bounds; {allowed}")
        seeds.update(range(first, last + 1))
    return sorted(seeds)


def add_parser(sub: Any) -> None:
    r = sub.add_parser("row", help="train a trained row's seeds and evaluate them (chopperscape.bench.rows)")
    r.add_argument("row", metavar="NAME", help=f"the row: {', '.join(ROWS)}")
    r.add_argument("--mode", required=True, help=f"the mode to train and evaluate on: {', '.join(TRAINED_MODES)}")
    r.add_argument("--seeds", default="0-9", help="training seeds: 0-9 (default), 0,3,5, 0-4,7")
    r.add_argument("--runs", required=True, metavar="DIR", help="folder of the runs (RUNS/seed-S/) and their locks")
    r.add_argument("--results", metavar="DIR", help="folder of the results files (default: docs/bench/results)")
    r.add_argument("--steps", help="the budget in decisions (default the row's; the row's name says it)")
    r.add_argument("--python", default=sys.executable, help="the interpreter of the trainers and the evaluation")
    r.add_argument(
        "--rllib-python",
        help="the interpreter of the RLlib trainer (default: .venv-rllib/bin/python of the checkout, or of the "
        "current folder)",
    )
    r.add_argument("--dry-run", action="store_true", help="print each command (shell-quoted) instead of running it")


def _checkout() -> Path:
    return Path(__file__).resolve().parents[3]


def _rllib_python(fallback: str) -> str:
    """The RLlib trainer's interpreter: `.venv-rllib` of the checkout this package is in, or of the current folder
    (an installed package's checkout is unknown), else `fallback`."""
    for root in (_checkout(), Path.cwd()):
        candidate = root / ".venv-rllib" / "bin" / "python"
        if candidate.is_file():
            return str(candidate)
    return fallback


def train_command(row: Row, mode: str, seed: int, steps: int, out: Path, py: str, rllib_py: str) -> list[str]:
    """The command that trains seed `seed` of `row` on `mode` for `steps` decisions into `out`."""
    s = row.settings()
    if row.trainer == "learn":
        if (out / "resume.pt").is_file():
            return [py, "-m", "chopperscape.learn.train", "--resume", str(out)]
        preset = ([] if s["preset"] is None else ["--preset", s["preset"]]) + s["flags"]
        args = ["--mode", mode, "--steps", str(steps), "--seed", str(seed), "--out", str(out), "--force"]
        return [py, "-m", "chopperscape.learn.train", *preset, *args]
    if row.trainer in ("sb3-ppo", "sb3-dqn"):
        algo = row.trainer.removeprefix("sb3-")
        args = ["--out", str(out), "--seed", str(seed), "--mode", mode, "--steps", str(steps)]
        return [py, "-m", "chopperscape.integrations.sb3_train", algo, *args, "--settings", json.dumps(s)]
    flags = [f"--{k}={json.dumps({**v, 'mode': mode}) if k == 'env-config' else v}" for k, v in s.items()]
    files = [f"--csv={out / 'progress.csv'}", f"--summary={out / 'summary.json'}", f"--export={out / row.model}"]
    return [rllib_py, "-m", "chopperscape.integrations.rllib.ppo", *flags, f"--steps={steps}", f"--seed={seed}", *files]


def _last_env_steps(path: Path) -> int | None:
    try:
        with open(path, newline="", encoding="utf-8") as f:
            rows = list(csv.DictReader(f))
        return int(rows[-1]["env_steps"]) if rows else None
    except (OSError, ValueError, KeyError):
        return None


def training_record(row: Row, mode: str, seed: int, steps: int, out: Path, command: list[str]) -> dict[str, Any]:
    """The training record of a finished training (:mod:`.record`), read from what its trainer wrote in `out`."""
    if row.trainer == "learn":
        settings = json.loads((out / "recipe.json").read_text())
        seeds = [[settings["seed"], settings["num_envs"]]]
        env_steps = _last_env_steps(out / "progress.csv")
    else:
        made = json.loads((out / ("summary.json" if row.trainer == "rllib-ppo" else "trainer.json")).read_text())
        settings, seeds, env_steps = made["settings"], made["train_seeds"], made["env_steps"]
    return record.check_training(
        {
            "format": record.TRAINING,
            "row": row.key,
            "trainer": "chopperscape.learn.train" if row.trainer == "learn" else row.trainer,
            "mode": mode,
            "seed": seed,
            "command": command,
            "commit": record.project_commit()[0],
            "settings": settings,
            "steps": steps,
            "env_steps": env_steps,
            "train_seeds": seeds,
        },
        mode,
    )


def _trained(path: Path, row: Row, mode: str, seed: int, steps: int) -> bool:
    try:
        t = record.read_training(path)
    except ValueError:
        return False
    return (t["row"], t["mode"], t["seed"], t["steps"]) == (row.key, mode, seed, steps)


def _lock(path: Path) -> TextIO | None:
    """The advisory lock on `path` held by this process (released when the file closes or the process ends), or
    None when another process holds it."""
    import fcntl

    f = open(path, "a+")
    try:
        fcntl.flock(f, fcntl.LOCK_EX | fcntl.LOCK_NB)
    except BlockingIOError:
        f.close()
        return None
    f.seek(0)
    f.truncate()
    f.write(f"{os.getpid()}\n")
    f.flush()
    return f


def _run(command: list[str], log: Path | None) -> int:
    if log is None:
        return subprocess.run(command).returncode
    with open(log, "w") as f:
        return subprocess.run(command, stdout=f, stderr=subprocess.STDOUT).returncode


def _fail(what: str, code: int, log: Path | None) -> int:
    where = f"; its output: {log}" if log is not None else ""
    print(f"error: {what} failed (exit status {code}){where}", file=sys.stderr)
    return code if code > 128 else 1


def main(a: argparse.Namespace) -> int:
    """`bench row` (the module's docs)."""
    if a.row not in ROWS:
        raise ValueError(f"unknown row {a.row!r}: allowed {', '.join(ROWS)}")
    row = ROWS[a.row]
    if a.mode not in row.modes:
        raise ValueError(f"--mode {a.mode!r} is not a mode of row {row.key}: allowed {', '.join(row.modes)}")
    seeds = parse_seeds(a.seeds)
    steps = row.steps
    if a.steps is not None:
        if not re.fullmatch(r"[1-9]\d{0,12}", a.steps):
            raise ValueError(f"--steps {a.steps!r}: allowed a whole number of decisions from 1, e.g. 3000000")
        steps = int(a.steps)
    results_dir = Path(a.results) if a.results else _checkout() / "docs" / "bench" / "results"
    if a.results is None and not results_dir.is_dir():
        raise ValueError("--results: give the folder of the results files (this package is not in a checkout)")
    if not a.dry_run:
        try:
            results_dir.mkdir(parents=True, exist_ok=True)
        except OSError as e:
            raise ValueError(f"--results {str(results_dir)!r}: cannot make the folder ({e.strerror})") from None
    rllib_py = a.rllib_python or _rllib_python(a.python)
    name, runs = row.name(steps), Path(a.runs)
    for seed in seeds:
        out, results = runs / f"seed-{seed}", results_dir / f"{a.mode}.{row.key}.seed{seed}.json"
        if results.exists():
            print_line(f"{results} exists: seed {seed} skipped")
            continue
        lock = None
        if not a.dry_run:
            runs.mkdir(parents=True, exist_ok=True)
            lock = _lock(runs / f"seed-{seed}.lock")
            if lock is None:
                print_line(
                    f"seed {seed} is being trained by another process (its lock {runs}/seed-{seed}.lock): skipped"
                )
                continue
            if results.exists():  # finished by another process meanwhile
                lock.close()
                continue
        try:
            done = _trained(out / "training.json", row, a.mode, seed, steps) and (out / row.model).is_file()
            train = train_command(row, a.mode, seed, steps, out, a.python, rllib_py)
            evaluate = [a.python, "-m", "chopperscape.bench", "evaluate", str(out / row.model), "--mode", a.mode]
            evaluate += ["--name", name, "--training", str(out / "training.json"), "--out", str(results)]
            if row.trainer.startswith("sb3-"):  # an SB3 .zip does not say what it observed
                evaluate += ["--option", "obs_type=features"]
            if a.dry_run:
                if not done:
                    print_line(shlex.join(train))
                print_line(shlex.join(evaluate))
                continue
            if not done:
                log = runs / f"seed-{seed}.log"
                out.mkdir(parents=True, exist_ok=True)  # the RLlib trainer writes into it and does not make it
                code = _run(train, log)
                if code != 0:
                    return _fail(f"seed {seed}: training", code, log)
                made = training_record(row, a.mode, seed, steps, out, train)
                _atomic.write_text(out / "training.json", json.dumps(made, indent=2, sort_keys=True) + "\n")
            code = _run(evaluate, None)
            if code != 0:
                return _fail(f"seed {seed}: evaluation", code, None)
        finally:
            if lock is not None:
                lock.close()
    return 0
