"""Issue 43's target, collected and summarised: every finished seed of RUNS (the folder `target43.sh` trains into) is
copied into `docs/curves/pixels-seeds/SET/` (SET `0-4`, the training seeds, or `100-104`, never tuned on) as
`seed-K.csv` (its training curve), `seed-K.recipe.json` and `seed-K.eval.json` (the held-out evaluation of its final
model); its line of `RUNS/target.csv` (decisions, wall and CPU seconds, how the episodes ended) goes into
`docs/curves/pixels-seeds/target.csv` with the machine it ran on, replacing that seed's earlier line; then each set is
summarised by the multi-seed runner (`python -m chopperscape.learn.seeds --summarise SET --preset pixels`: the IQM of
the seeds' held-out means with its 95 % bootstrap interval, the baselines at the preset's frame skip), written into
the set's folder as `summary.md`, `summary.json` and `curves.png`.

    python docs/curves/pixels-probes/collect_target.py RUNS [--machine TEXT] [--out FOLDER] [--title TEXT]

`--out` gathers a candidate recipe's seeds into a folder of their own (e.g. `docs/curves/pixels-candidates/NAME`,
the same layout: `SET/seed-K.*`, `target.csv`, each set's summary), so that the preset's figures in
`pixels-seeds/` stay the preset's until the candidate replaces it; its baselines are copied from `pixels-seeds/`
where that set has them (the same held-out seeds and rules), not evaluated again. `--title` names the recipe in the
summaries' plots.

Nothing is copied from a seed whose evaluation is missing (a run cut before its end); a seed outside both sets is
refused by name.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[3]
OUT = ROOT / "docs" / "curves" / "pixels-seeds"
SETS = {"0-4": range(5), "100-104": range(100, 105)}
FIELDS = ["seed", "decisions", "wall_s", "cpu_s", "mean_return", "bird", "fuel", "truncated", "machine"]


def this_machine() -> str:
    """`N-vCPU MODEL (family F model M, AVX-512)`: the hosts of these sessions all call themselves "AMD EPYC", so
    the CPU's family and model tell them apart (family 25: Zen 3 or 4; 26: Zen 5), and AVX-512 is named where it is.
    """
    info = Path("/proc/cpuinfo").read_text() if Path("/proc/cpuinfo").is_file() else ""
    fields: dict[str, str] = {}
    for line in info.splitlines():
        key, _, value = line.partition(":")
        fields.setdefault(key.strip(), value.strip())
    cpu = [f"family {fields['cpu family']} model {fields['model']}"] if "cpu family" in fields else []
    cpu += ["AVX-512"] if "avx512f" in fields.get("flags", "").split() else []
    return f"{os.cpu_count()}-vCPU {fields.get('model name', '?')}" + (f" ({', '.join(cpu)})" if cpu else "")


def set_of(seed: int) -> str:
    for name, seeds in SETS.items():
        if seed in seeds:
            return name
    raise ValueError(f"seed {seed} is in neither set of the target (allowed: 0-4 and 100-104)")


def main() -> int:
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("runs", type=Path, help="target43.sh's folder: target.csv and seed-K/")
    p.add_argument("--machine", default=None, help="what the seeds ran on (default: this machine's CPU)")
    p.add_argument("--out", type=Path, default=OUT, help=f"where the seeds go (default: {OUT.relative_to(ROOT)})")
    p.add_argument("--title", default="PPO, frames alone", help="the recipe's name in the summaries' plots")
    a = p.parse_args()
    machine = a.machine or this_machine()
    out: Path = a.out.resolve()
    with open(a.runs / "target.csv", newline="") as f:
        new = list(csv.DictReader(f))
    table = out / "target.csv"
    rows: dict[int, dict[str, str]] = {}
    if table.is_file():
        with open(table, newline="") as f:
            rows = {int(r["seed"]): r for r in csv.DictReader(f)}
    touched = set()
    for row in new:
        seed, decisions = int(row["seed"]), row["decisions"]
        run, folder = a.runs / f"seed-{seed}", out / set_of(seed)
        evaluation = run / f"eval-{decisions}.json"
        if not evaluation.is_file():
            print(f"seed {seed}: {evaluation} missing; not collected", file=sys.stderr)
            continue
        folder.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(run / "progress.csv", folder / f"seed-{seed}.csv")
        shutil.copyfile(run / "recipe.json", folder / f"seed-{seed}.recipe.json")
        # The evaluation as `evaluate` wrote it, with the training's wall time (as the multi-seed runner adds it).
        doc = json.loads(evaluation.read_text())
        (folder / f"seed-{seed}.eval.json").write_text(json.dumps({**doc, "train_wall_s": float(row["wall_s"])}))
        rows[seed] = {**row, "machine": machine}
        touched.add(folder.name)
    with open(table, "w", newline="") as f:
        w = csv.DictWriter(f, fieldnames=FIELDS, lineterminator="\n")
        w.writeheader()
        w.writerows(rows[s] for s in sorted(rows))
    for name in sorted(touched):
        for baseline in (OUT / name).glob("baseline-*.json"):  # the preset's, on the same seeds and rules
            if not (out / name / baseline.name).exists():
                shutil.copyfile(baseline, out / name / baseline.name)
        title = f"{a.title}, seeds {name}"
        cmd = [sys.executable, "-m", "chopperscape.learn.seeds", "--summarise", str(out / name), "--preset", "pixels"]
        # The summary states the seeds' schedule: their recipes' (a candidate's may differ from the preset's).
        steps = {json.loads(r.read_text())["total_steps"] for r in (out / name).glob("seed-*.recipe.json")}
        if len(steps) != 1:
            raise ValueError(f"{out / name}: seeds of different schedules ({sorted(steps)}) cannot share a summary")
        subprocess.run([*cmd, "--steps", str(steps.pop()), "--title", title], check=True)
        for log in (out / name).glob("baseline-*.log"):
            if log.stat().st_size == 0:  # the baselines' evaluations said nothing
                log.unlink()
    return 0


if __name__ == "__main__":
    sys.exit(main())
