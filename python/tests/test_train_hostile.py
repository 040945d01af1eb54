"""The training recipe under hostile input and faults: every setting checked before anything is written, an
existing run refused unless --force, Ctrl-C saves the model atomically, and a NaN loss stops the run before the
optimiser step."""

from __future__ import annotations

import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

torch = pytest.importorskip("torch", reason="torch is not installed (scripts/test-python.sh installs it)")
from chopperscape.learn import networks, train  # noqa: E402
from chopperscape.learn.presets import NOVELTY  # noqa: E402
from chopperscape.learn.recipe import Recipe  # noqa: E402

#: A recipe that runs an update in a fraction of a second.
SMALL = ["--num-envs", "4", "--num-steps", "32", "--hidden", "8", "--num-minibatches", "2", "--update-epochs", "1"]


@pytest.fixture
def no_training(monkeypatch):
    """`train.train` replaced: a setting that reaches it was not refused."""
    calls = []
    monkeypatch.setattr(train, "train", lambda *a, **k: calls.append(a) or pathlib.Path("model.pt"))
    return calls


@pytest.mark.parametrize(
    "args,named",
    [
        (["--minutes", "nan"], "minutes"),
        (["--minutes", "-1"], "minutes"),
        (["--minutes", "inf"], "minutes"),
        (["--steps", "0"], "steps"),
        (["--num-envs", "0"], "num_envs"),
        (["--seed", "-1"], "seed"),
        (["--num-minibatches", "0"], "num_minibatches"),
        (["--num-minibatches", "100000"], "num_minibatches"),
        (["--torch-threads", "0"], "torch_threads"),
        (["--env-threads", "0"], "env_threads"),
        (["--gamma", "1.5"], "gamma"),
        (["--learning-rate", "nan"], "learning_rate"),
        (["--lr-floor", "1.5"], "lr_floor"),
        (["--lr-floor", "-0.1"], "lr_floor"),
        (["--ent-floor", "1.5"], "ent_floor"),
        (["--ent-floor", "nan"], "ent_floor"),
        (["--rnd-own-value"], "rnd_own_value`: it is the novelty bonus"),
        (["--rnd-proportion", "0.25"], "rnd_proportion`: it is the novelty bonus"),
        (["--rnd-coef", "0.5", "--rnd-proportion", "0"], "rnd_proportion"),
        (["--rnd-pool", "2"], "rnd_pool`: it is the novelty bonus"),
        (["--rnd-coef", "0.5", "--rnd-pool", "3"], "rnd_pool`: allowed 1, 2, 4"),
        (["--rnd-coef", "0.5", "--rnd-pool", "0"], "rnd_pool`: allowed 1, 2, 4"),
        (["--rnd-floor", "0.5"], "rnd_floor`: it is the novelty bonus"),
        (["--rnd-coef", "0.5", "--rnd-floor", "1.5"], "rnd_floor"),
        (["--rnd-coef", "0.5", "--rnd-floor", "nan"], "rnd_floor"),
        (["--rnd-hold", "0.5"], "rnd_hold`: it is the novelty bonus"),
        (["--preset", "pixels", "--rnd-hold", "0.5"], "rnd_hold`: it is where the novelty bonus's weight starts"),
        (["--rnd-coef", "0.5", "--rnd-floor", "0", "--rnd-hold", "1"], "rnd_hold`: allowed a finite number in [0, 1)"),
        (["--rnd-coef", "0.5", "--rnd-floor", "0", "--rnd-hold", "nan"], "rnd_hold"),
        (["--option", "obs_type=rgb"], "--obs-type"),
        (["--option", "num_threads=2"], "--env-threads"),
        (["--option", "lives=0"], "lives"),
        (["--mode", "v1"], "--mode"),
        (["--mode", "v0", "--preset", "fast"], "frame_skip=4 (the mode's: 1)"),
        (["--mode", "sticky-v0", "--option", "lives=2"], "lives=2 (the mode's: 1)"),
        (["--mode", "full-v0", "--option", "sticky_prob=0"], "sticky_prob=0.0 (the mode's: 0.25)"),
        (["--device", "banana"], "device"),
        (["--device", "tpu"], "device"),
        (["--device", "cuda:99"], "cuda:99"),
    ],
)
def test_bad_settings_are_refused_before_anything_is_written(args, named, tmp_path, no_training, capsys):
    out = tmp_path / "run"
    with pytest.raises(SystemExit) as e:
        train.main(["--out", str(out), *args])
    assert e.value.code == 2 and named in capsys.readouterr().err
    assert not no_training and not out.exists()


def test_the_train_function_checks_its_arguments_too(tmp_path):
    with pytest.raises(ValueError, match="num_envs"):
        train.train(Recipe(num_envs=0, total_steps=100), tmp_path / "a")
    with pytest.raises(ValueError, match="minutes"):
        train.train(Recipe(total_steps=100), tmp_path / "a", minutes=float("nan"))
    with pytest.raises(ValueError, match="total_steps"):
        train.train(Recipe(total_steps=0), tmp_path / "a")
    with pytest.raises(ValueError, match="network"):
        train.train(Recipe(network="resnet", total_steps=100), tmp_path / "a")
    with pytest.raises(ValueError, match="env option `num_threads`"):
        train.train(Recipe(env_options={"num_threads": 2}, total_steps=100), tmp_path / "a")
    assert not (tmp_path / "a").exists()


def test_an_out_that_is_a_file_or_holds_a_run_is_refused_unless_force(tmp_path, no_training, capsys):
    (tmp_path / "file").write_text("mine")
    with pytest.raises(SystemExit):
        train.main(["--out", str(tmp_path / "file"), "--steps", "100"])
    assert "is not a folder" in capsys.readouterr().err and (tmp_path / "file").read_text() == "mine"
    run = tmp_path / "run"
    run.mkdir()
    (run / "model.pt").write_bytes(b"the old model")
    (run / "progress.csv").write_text("the old curve")
    with pytest.raises(SystemExit):
        train.main(["--out", str(run), "--steps", "100"])
    err = capsys.readouterr().err
    assert "already holds a run" in err and "--force" in err
    assert (run / "model.pt").read_bytes() == b"the old model" and (run / "progress.csv").read_text() == "the old curve"
    assert not no_training
    assert train.main(["--out", str(run), "--steps", "100", "--force"]) == 0
    assert no_training


def test_force_starts_the_run_over(tmp_path):
    run = tmp_path / "run"
    run.mkdir()
    (run / "progress.csv").write_text("the old curve")
    assert train.main(["--out", str(run), "--steps", "256", "--force", *SMALL]) == 0
    assert (run / "progress.csv").read_text().startswith("env_steps,")
    assert torch.load(run / "model.pt", weights_only=True)["env_steps"] >= 256


def test_ctrl_c_saves_the_model_reached_so_far_and_leaves_no_temporary_file(tmp_path):
    run = tmp_path / "run"
    proc = subprocess.Popen(
        [sys.executable, "-m", "chopperscape.learn.train", "--out", str(run), "--minutes", "5", *SMALL],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    deadline = time.monotonic() + 120
    while time.monotonic() < deadline:
        csv = run / "progress.csv"
        if csv.exists() and len(csv.read_text().splitlines()) >= 3:
            break
        assert proc.poll() is None, proc.stderr.read()
        time.sleep(0.1)
    proc.send_signal(signal.SIGINT)
    _out, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "Traceback" not in err and "is saved in" in err, err
    model = torch.load(run / "model.pt", weights_only=True)
    assert model["env_steps"] > 0
    # Stopped by a signal, the run keeps what it reached and the state to go on from (`--resume`).
    assert sorted(os.listdir(run)) == ["model.pt", "progress.csv", "recipe.json", "resume.pt"]


def test_a_nan_loss_stops_the_run_before_the_optimiser_step(tmp_path, monkeypatch):
    made = []

    class Poisoned(networks.Agent):
        def __init__(self, *a):
            super().__init__(*a)
            made.append(self)

        def value(self, x):
            return super().value(x) * float("nan")

    monkeypatch.setattr(networks, "Agent", Poisoned)
    recipe = Recipe(num_envs=4, num_steps=32, hidden=8, num_minibatches=2, total_steps=10_000)
    with pytest.raises(FloatingPointError, match="loss became nan"):
        train.train(recipe, tmp_path / "run")
    (agent,) = made
    assert all(torch.isfinite(p).all() for p in agent.parameters()), "the optimiser stepped with a NaN loss"


def test_a_cuda_device_without_a_gpu_is_refused_with_the_reason(tmp_path, no_training, capsys):
    if torch.cuda.is_available():
        pytest.skip("this machine has a CUDA GPU")
    with pytest.raises(SystemExit) as e:
        train.main(["--out", str(tmp_path / "run"), "--preset", "pixels-large", "--device", "cuda"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and "torch sees no CUDA GPU" in err and "--device cpu" in err and not no_training


def test_the_large_pixel_preset_is_the_pixel_recipe_with_a_bigger_batch(tmp_path, no_training):
    assert train.main(["--out", str(tmp_path / "a"), "--preset", "pixels"]) == 0
    assert train.main(["--out", str(tmp_path / "b"), "--preset", "pixels-large", "--num-minibatches", "16"]) == 0
    small, large = no_training[0][0], no_training[1][0]
    assert (large.num_envs, large.num_minibatches, large.env_threads) == (256, 16, 2)
    # A GPU's schedule: the 28 M decisions it learns the game in (docs/learning.md), against the pixel preset's 12 M.
    assert (small.total_steps, large.total_steps) == (12_000_000, 28_000_000)
    # Since the twenty-fourth session the pixel preset explores with RND (presets.NOVELTY); the GPU preset keeps what
    # its figures were measured with, no bonus.
    batch = ("num_envs", "num_minibatches", "env_threads", "total_steps", *NOVELTY)
    assert (small.rnd_coef, large.rnd_coef, large.rnd_own_value, large.rnd_pool) == (0.5, 0.0, False, 1)
    same = {k: v for k, v in vars(small).items() if k not in batch}
    assert same == {k: v for k, v in vars(large).items() if k in same}
    assert large.env_options == {"obs_size": [42, 42], "frame_stack": 4, "frame_skip": 4}
