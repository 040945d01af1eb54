"""Privileged information only as a training signal: `--aux-coef` (the game's features predicted from the CNN's trunk)
and `--teacher` (KL to a features model on the policy's own rollouts), each read from a twin features env; neither
leaves a trace in the saved model, and a teacher that does not fit is refused before anything is written."""

from __future__ import annotations

import contextlib
import csv
import json
import re

import pytest
from conftest import needs_torch, progress_rows


@needs_torch
def test_auxiliary_features_train_the_trunk_only_and_leave_no_trace_in_the_model(tmp_path, capsys):
    """`--aux-coef`: a twin features env in lockstep (its rewards checked every step), a loss on the CNN's trunk;
    the saved model is an ordinary pixel model (no extra head) that evaluate plays. Refused for the features MLP."""
    import torch

    from chopperscape.learn import modelfile, networks, train

    base = ["--preset", "pixels", "--steps", "600", "--num-envs", "4", "--num-steps", "32", "--seed", "5"]
    base += ["--option", "obs_size=42x42", "--option", "max_fuel=120"]
    assert train.main([*base, "--out", str(tmp_path / "aux"), "--aux-coef", "2"]) == 0
    assert train.main([*base, "--out", str(tmp_path / "plain")]) == 0
    capsys.readouterr()
    aux = torch.load(tmp_path / "aux" / "model.pt", weights_only=True)
    plain = torch.load(tmp_path / "plain" / "model.pt", weights_only=True)
    assert json.loads((tmp_path / "aux" / "recipe.json").read_text())["aux_coef"] == 2.0
    assert set(aux) == set(plain)  # no auxiliary head saved
    assert all(aux[part].keys() == plain[part].keys() for part in ("actor", "critic"))
    # The loss moved the trunk: the same run with a vanishing weight (the same twin and head, so the runs differ
    # only by the loss's weight; 1e-30 is lost in rounding) ends elsewhere.
    assert train.main([*base, "--out", str(tmp_path / "faint"), "--aux-coef", "1e-30"]) == 0
    faint = torch.load(tmp_path / "faint" / "model.pt", weights_only=True)
    first = next(k for k in aux["actor"] if k.startswith("0.") and k.endswith(".weight"))  # the first convolution
    assert not torch.equal(aux["actor"][first], faint["actor"][first])
    assert isinstance(modelfile.agent_from_checkpoint(aux), networks.CnnAgent)
    # The twin runs the same game: with equal seeds and actions, every reward and end matched (else it raises).
    rows = progress_rows(tmp_path / "aux" / "progress.csv")
    assert rows and int(rows[-1]["episodes"]) > 0
    with pytest.raises(SystemExit):
        train.main(["--steps", "100", "--out", str(tmp_path / "mlp"), "--aux-coef", "1"])
    assert "`aux_coef`: the auxiliary features loss is for CNN recipes" in capsys.readouterr().err
    with pytest.raises(SystemExit):
        train.main([*base, "--out", str(tmp_path / "neg"), "--aux-coef", "-1"])
    assert "invalid value -1.0 for option `aux_coef`" in capsys.readouterr().err
    assert not (tmp_path / "mlp").exists() and not (tmp_path / "neg").exists()


def _teacher_file(path, rules, favourite=3):
    """A features model as `train` writes it, whose policy plays `favourite` nearly always (a strong bias on its
    output layer), on the rules options `rules`."""
    import torch

    from chopperscape.learn import modelfile, networks, normalize
    from chopperscape.learn.recipe import Recipe

    torch.manual_seed(0)
    agent = networks.build_agent("mlp", (46,), hidden=16)
    with torch.no_grad():
        agent.actor[-1].bias[favourite] = 8.0
    recipe = Recipe(obs_type="features", env_options=dict(rules), hidden=16)
    modelfile.save(path, agent, normalize.ObsNormalizer((46,), True), recipe, (46,), 0)
    return path


def _column(path, name):
    """One column of a progress CSV, as written."""
    with open(path, newline="") as f:
        return [row[name] for row in csv.DictReader(f)]


@needs_torch
def test_a_teacher_pulls_the_pixel_policy_toward_it_and_changes_nothing_at_weight_zero(tmp_path, capsys):
    """`--teacher`: KL(teacher ‖ policy) on the policy's own rollouts, read from a twin features env. At weight 0 the
    run is the plain run bit for bit (the twin only watches); with weight the KL falls and the greedy policy plays
    the teacher's action; the saved model is a plain pixel model."""
    import torch

    from chopperscape.learn import modelfile, train

    rules = {"frame_skip": 2, "max_fuel": 150}
    teacher = _teacher_file(tmp_path / "teacher.pt", rules)
    # The teacher's route (`pixels-teacher`): at the frames-alone preset's lr 1e-3 this smoke's plain run also
    # settles on one action from random frames, which would hide the teacher's pull.
    base = ["--preset", "pixels-teacher", "--steps", "1500", "--num-envs", "4", "--num-steps", "32", "--seed", "2"]
    base += ["--option", "obs_size=42x42", "--option", "frame_skip=2", "--option", "max_fuel=150"]
    assert train.main([*base, "--out", str(tmp_path / "plain")]) == 0
    assert train.main([*base, "--out", str(tmp_path / "zero"), "--teacher", str(teacher), "--teacher-coef", "0"]) == 0
    assert train.main([*base, "--out", str(tmp_path / "taught"), "--teacher", str(teacher), "--teacher-coef", "5"]) == 0
    capsys.readouterr()
    plain, zero, taught = (
        torch.load(tmp_path / r / "model.pt", weights_only=True) for r in ("plain", "zero", "taught")
    )
    assert set(taught) == set(plain) and taught["actor"].keys() == plain["actor"].keys()
    assert all(torch.equal(zero["actor"][k], plain["actor"][k]) for k in plain["actor"])
    assert not torch.equal(taught["actor"]["1.weight"], plain["actor"]["1.weight"])
    kl = [float(v) for v in _column(tmp_path / "taught" / "progress.csv", "teacher_kl")]
    assert kl[-1] < kl[0] / 2, kl
    assert set(_column(tmp_path / "plain" / "progress.csv", "teacher_kl")) == {""}
    # The taught policy flies Up (the teacher's action) from frames it has never seen; the plain one does not.
    frames = torch.randint(0, 256, (64, 42, 42, 4), dtype=torch.uint8)
    for run, want in (("taught", True), ("plain", False)):
        agent = modelfile.load(tmp_path / run / "model.pt").agent
        with torch.no_grad():
            up = (agent.actor(frames).argmax(-1) == 3).float().mean().item()
        assert (up > 0.9) is want, (run, up)


@needs_torch
def test_a_teacher_is_refused_unless_it_fits_before_anything_is_written(tmp_path, capsys):
    from chopperscape.learn import train

    good = _teacher_file(tmp_path / "t.pt", {"frame_skip": 4})
    other_rules = _teacher_file(tmp_path / "fs2.pt", {"frame_skip": 2})
    same_by_default = _teacher_file(tmp_path / "fs4.pt", {"frame_skip": 4.0, "alien_prob": 0.0, "max_fuel": 1000})
    (tmp_path / "junk.pt").write_bytes(b"not a model")
    base = ["--preset", "pixels", "--steps", "300", "--num-envs", "2", "--num-steps", "32"]
    cases = [
        ([*base, "--teacher", str(tmp_path / "none.pt")], "no such file"),
        ([*base, "--teacher", str(tmp_path / "junk.pt")], "is not a chopperscape.learn.train model"),
        ([*base, "--teacher", str(other_rules)], r"learned other rules \(\{'frame_skip': 2.0\}\) than this run's"),
        (["--steps", "300", "--teacher", str(good)], "a features teacher guides CNN recipes"),
        (
            [*base, "--teacher", str(good), "--teacher-fade", "0"],
            r"`teacher_fade`: allowed a finite number in \(0, 1\]",
        ),
        ([*base, "--teacher", str(good), "--teacher-coef", "-1"], "`teacher_coef`"),
    ]
    for args, message in cases:
        out = tmp_path / "run"
        with pytest.raises(SystemExit) if "teacher_" in message or "guides" in message else contextlib.nullcontext():
            assert train.main([*args, "--out", str(out)]) == 2
        assert re.search(message, capsys.readouterr().err), message
        assert not out.exists()
    # A pixel teacher is refused by name.
    pixel_run = tmp_path / "pix"
    assert train.main([*base, "--option", "obs_size=42x42", "--out", str(pixel_run)]) == 0
    capsys.readouterr()
    assert train.main([*base, "--teacher", str(pixel_run / "model.pt"), "--out", str(tmp_path / "run")]) == 2
    assert "a teacher must be a features model" in capsys.readouterr().err
    # Rules spelled with their defaults are the same rules.
    assert train.main([*base, "--option", "obs_size=42x42", "--teacher", str(same_by_default), "--out",
                       str(tmp_path / "ok")]) == 0  # fmt: skip
