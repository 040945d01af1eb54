"""`train --resume`: a run stopped at any update and resumed draws the uninterrupted run's curve row for row and
ends with the same model, plain PPO and guided alike; what cannot be resumed is refused by name. Also the
random-shift augmentation (`--augment shift`) and the pixel preset's smoke run without a teacher."""

from __future__ import annotations

import csv
import importlib.util
import json
import pickle
from pathlib import Path

import numpy as np
import pytest

pytestmark = pytest.mark.skipif(
    importlib.util.find_spec("torch") is None, reason="torch is not installed (scripts/test-python.sh installs it)"
)

#: The progress columns that do not depend on the wall clock.
SAME = (
    "env_steps", "episodes", "mean_return", "entropy", "approx_kl", "value_loss", "policy_loss",
    "aux_loss", "recon_loss", "rnd_loss", "novelty",
)  # fmt: skip


def _rows(path: Path) -> list[dict[str, str]]:
    with open(path, newline="") as f:
        return [{k: r[k] for k in SAME} for r in csv.DictReader(f)]


class _Clock:
    """A fake `time.monotonic` that advances one second a call: `--minutes` then stops a run after a number of
    clock reads that is the same every time, so the stop falls on a chosen update."""

    def __init__(self) -> None:
        self.now = 0.0

    def monotonic(self) -> float:
        self.now += 1.0
        return self.now

    def perf_counter(self) -> float:
        return self.now


def _stopped_then_resumed(recipe, out: Path, stop_after_s: float, monkeypatch) -> None:
    import chopperscape.learn.run as run
    import chopperscape.learn.state as state
    import chopperscape.learn.train as train

    with monkeypatch.context() as m:
        clock = _Clock()
        m.setattr(state.time, "monotonic", clock.monotonic)
        m.setattr(run, "CHECKPOINT_EVERY", 2)
        train.train(recipe, out, minutes=stop_after_s / 60)
    assert (out / "resume.pt").exists()
    train.train(recipe, out, resume=True)


@pytest.mark.parametrize("ent_floor", [1.0, 0.25])
def test_a_resumed_features_run_is_the_uninterrupted_run(tmp_path, monkeypatch, ent_floor):
    import torch

    from chopperscape.learn import train
    from chopperscape.learn.recipe import Recipe

    recipe = Recipe(
        num_envs=8,
        num_steps=32,
        hidden=16,
        update_epochs=2,
        num_minibatches=2,
        env_options={"max_fuel": 150},
        total_steps=8 * 32 * 7,
        ent_floor=ent_floor,
    )
    train.train(recipe, tmp_path / "whole")
    _stopped_then_resumed(recipe, tmp_path / "parts", 7, monkeypatch)
    whole, parts = _rows(tmp_path / "whole" / "progress.csv"), _rows(tmp_path / "parts" / "progress.csv")
    assert len(whole) >= 7 and parts == whole
    a = torch.load(tmp_path / "whole" / "model.pt", weights_only=True)
    b = torch.load(tmp_path / "parts" / "model.pt", weights_only=True)
    assert all(torch.equal(a["actor"][k], b["actor"][k]) for k in a["actor"])
    assert a["obs_rms"] == b["obs_rms"] and a["env_steps"] == b["env_steps"]


@pytest.mark.parametrize(
    ("aux_coef", "recon_coef", "rnd_coef", "novelty"),
    [
        (0.0, 0.0, 0.0, {}),
        (0.5, 0.0, 0.0, {}),
        (0.0, 2.0, 0.0, {}),
        (0.0, 0.0, 0.5, {}),
        (0.0, 0.0, 0.5, {"rnd_own_value": True}),
        (0.0, 0.0, 0.5, {"rnd_own_value": True, "rnd_proportion": 0.5}),
        (0.0, 0.0, 0.5, {"rnd_own_value": True, "rnd_pool": 2}),
        (0.0, 0.0, 0.5, {"rnd_own_value": True, "rnd_floor": 0.0}),
        (0.0, 0.0, 0.5, {"rnd_own_value": True, "rnd_floor": 0.0, "rnd_hold": 0.5}),
    ],
)
def test_a_resumed_pixel_run_is_the_uninterrupted_run(tmp_path, monkeypatch, aux_coef, recon_coef, rnd_coef, novelty):
    from chopperscape.learn import train
    from chopperscape.learn.recipe import Recipe

    side = 16 * novelty.get("rnd_pool", 1)  # the bonus's networks read at least 10×10 once pooled
    recipe = Recipe(
        obs_type="grayscale",
        env_options={"obs_size": [side, side], "frame_stack": 2, "max_fuel": 120},
        network="small",
        num_envs=4,
        num_steps=16,
        num_minibatches=2,
        aux_coef=aux_coef,
        recon_coef=recon_coef,
        rnd_coef=rnd_coef,
        **novelty,
        augment="shift",
        total_steps=4 * 16 * 5,
    )
    train.train(recipe, tmp_path / "whole")
    _stopped_then_resumed(recipe, tmp_path / "parts", 6, monkeypatch)
    whole, parts = _rows(tmp_path / "whole" / "progress.csv"), _rows(tmp_path / "parts" / "progress.csv")
    assert len(whole) >= 5 and parts == whole
    assert all(bool(r["aux_loss"]) == (aux_coef > 0) for r in whole)
    assert all(bool(r["recon_loss"]) == (recon_coef > 0) for r in whole)
    assert all(bool(r["rnd_loss"]) == (rnd_coef > 0) for r in whole)


def test_resume_refuses_what_it_cannot_continue(tmp_path, capsys):
    from chopperscape.learn import train

    run = tmp_path / "run"
    args = ["--out", str(run), "--num-envs", "4", "--num-steps", "16", "--hidden", "8", "--steps", "128"]
    assert train.main(args) == 0
    capsys.readouterr()
    # Flags that would change the recipe are named.
    with pytest.raises(SystemExit) as e:
        train.main(["--resume", str(run), "--learning-rate", "0.1", "--steps", "10"])
    assert e.value.code == 2
    err = capsys.readouterr().err
    assert "--learning-rate, --steps cannot be given with it" in err
    with pytest.raises(SystemExit) as e:
        train.main(["--resume", str(run), "--mode", "sticky-v0"])
    assert e.value.code == 2 and "--mode cannot be given with it" in capsys.readouterr().err
    # A folder without a resume state, a damaged one, and one that runs code are refused by name, changing nothing.
    empty = tmp_path / "empty"
    empty.mkdir()
    (empty / "recipe.json").write_text((run / "recipe.json").read_text())
    assert train.main(["--resume", str(empty)]) == 2
    assert "no resume.pt there" in capsys.readouterr().err
    before = (run / "progress.csv").read_bytes()
    (run / "resume.pt").write_bytes(b"not a checkpoint")
    assert train.main(["--resume", str(run)]) == 2
    assert "resume.pt" in capsys.readouterr().err
    (run / "resume.pt").write_bytes(pickle.dumps(Path("/")))
    assert train.main(["--resume", str(run)]) == 2
    assert "resume.pt" in capsys.readouterr().err
    assert (run / "progress.csv").read_bytes() == before
    # A recipe.json that is not one.
    (empty / "recipe.json").write_text(json.dumps({"learning_rate": 0.1, "gravity": 9.8}))
    with pytest.raises(SystemExit):
        train.main(["--resume", str(empty)])
    assert "unknown settings ['gravity']" in capsys.readouterr().err


def test_the_progress_csv_of_a_resumed_run_drops_the_rows_after_its_checkpoint(tmp_path):
    from chopperscape.learn import progress

    path = tmp_path / "progress.csv"
    with progress.Writer(path) as w:
        for steps in (100, 200, 300):
            w.row({"env_steps": steps, "wall_s": 1})
    with progress.Writer.resume(path, 200) as w:
        w.row({"env_steps": 300, "wall_s": 2})
    with open(path, newline="") as f:
        rows = list(csv.DictReader(f))
    assert [(r["env_steps"], r["wall_s"]) for r in rows] == [("100", "1"), ("200", "1"), ("300", "2")]
    (tmp_path / "other.csv").write_text("a,b\n1,2\n")
    with pytest.raises(ValueError, match=r"other\.csv: not a progress CSV this trainer wrote"):
        progress.Writer.resume(tmp_path / "other.csv", 0)


def test_random_shift_crops_the_edge_padded_frames():
    import torch

    from chopperscape.learn.augment import random_shift, shift_pad

    assert (shift_pad((84, 84, 4)), shift_pad((42, 42, 4)), shift_pad((16, 16))) == (4, 2, 1)
    x = torch.from_numpy(np.random.default_rng(0).integers(0, 256, (6, 12, 10, 3), dtype=np.uint8))
    gen = torch.Generator().manual_seed(1)
    y = random_shift(x, 2, gen)
    assert y.shape == x.shape and y.dtype == torch.uint8
    padded = np.pad(x.numpy(), ((0, 0), (2, 2), (2, 2), (0, 0)), mode="edge")
    offsets = torch.randint(0, 5, (2, 6), generator=torch.Generator().manual_seed(1))
    for i in range(6):
        dy, dx = int(offsets[0, i]), int(offsets[1, i])
        assert np.array_equal(y[i].numpy(), padded[i, dy : dy + 12, dx : dx + 10])
    assert len({tuple(offsets[:, i].tolist()) for i in range(6)}) > 1
    # 2-D frames (no stack axis) keep their shape.
    assert random_shift(x[..., 0], 1).shape == (6, 12, 10)
