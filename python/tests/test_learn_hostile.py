"""The learning tools (train, evaluate, export, seeds) under hostile input and faults, issue 32: every option train
takes round-trips through evaluate and export; crafted model files, summary files and flags end in one line naming
the input (exit 2), in bounded time and memory; a run folder never mixes two runs; a full disk or a read-only
folder is one line, and nothing is left behind."""

from __future__ import annotations

import errno
import json
import math
import os
import pathlib
import time
import tracemalloc

import pytest

torch = pytest.importorskip("torch", reason="torch is not installed (scripts/test-python.sh installs it)")
from chopperscape import _atomic, _core  # noqa: E402
from chopperscape.learn import evaluate as ev  # noqa: E402
from chopperscape.learn import export as ex  # noqa: E402
from chopperscape.learn import modelfile, networks, normalize, seeds, train  # noqa: E402
from chopperscape.learn import run as run_module  # noqa: E402
from chopperscape.learn.recipe import RESERVED_OPTIONS, Recipe  # noqa: E402

#: A recipe that runs an update in a fraction of a second.
SMALL = ["--num-envs", "4", "--num-steps", "32", "--hidden", "8", "--num-minibatches", "2", "--update-epochs", "1"]

#: A value other than the default for every option `train --option` takes, as the command line gives it.
OPTION_VALUES = {
    "obs_size": "42x42",
    "frame_stack": "2",
    "hud": "false",
    "hud_style": "gauge",
    "look": "agent",
    "lives": "2",
    "bird_fuel_collision": "destroy",
    "alien_prob": "0.1",
    "frame_skip": "2",
    "sticky_prob": "0.25",
    "bird_prob": "0.05",
    "fuel_prob": "0.05",
    "max_fuel": "300",
    "max_episode_steps": "30",
    "keep_dim": "true",
}
TRAIN_OPTIONS = [n for n in (*_core.OPTION_NAMES, "keep_dim") if n not in RESERVED_OPTIONS]


def one_line(err: str) -> str:
    assert "Traceback" not in err, err
    lines = [line for line in err.splitlines() if line.strip()]
    assert lines, "nothing said"
    return lines[-1]


def small_model(path: pathlib.Path, **recipe) -> pathlib.Path:
    """A features model file as the trainer writes it (hidden 8)."""
    r = Recipe(hidden=8, **recipe)
    modelfile.save(path, networks.Agent(46, 5, 8), normalize.ObsNormalizer((46,)), r, (46,), 0)
    return path


def test_the_option_table_covers_every_option_train_takes():
    assert sorted(OPTION_VALUES) == sorted(TRAIN_OPTIONS)


@pytest.mark.parametrize("name", TRAIN_OPTIONS)
def test_every_option_train_takes_round_trips_through_evaluate_and_export(name, tmp_path, capsys):
    run = tmp_path / "run"
    option = f"{name}={OPTION_VALUES[name]}"
    assert train.main(["--out", str(run), "--steps", "128", *SMALL, "--option", option]) == 0
    capsys.readouterr()
    assert ev.main([str(run / "model.pt"), "--episodes", "2", "--option", "max_episode_steps=20"]) == 0
    out = json.loads(capsys.readouterr().out)
    assert out["episodes"] == 2 and out["max_episode_steps"] == 20
    if name == "max_episode_steps":  # without --option, the model's own truncation
        assert ev.main([str(run / "model.pt"), "--episodes", "2"]) == 0
        out = json.loads(capsys.readouterr().out)
        assert out["max_episode_steps"] == 30 and out["mean_steps"] <= 30
        # A model trained without one is evaluated to the usual 10,000 steps: evaluation ends.
        payload = torch.load(run / "model.pt", weights_only=True)
        payload["recipe"]["env_options"]["max_episode_steps"] = None
        torch.save(payload, tmp_path / "none.pt")
        assert ev.main([str(tmp_path / "none.pt"), "--episodes", "1", "--option", "max_fuel=30"]) == 0
        assert "max_episode_steps" not in json.loads(capsys.readouterr().out)
    assert ex.main([str(run / "model.pt"), "--out", str(tmp_path / "m.onnx")]) == 0, capsys.readouterr().err
    result = json.loads(capsys.readouterr().out)
    assert result["checked"] is True
    import onnx

    meta = {p.key: p.value for p in onnx.load(str(tmp_path / "m.onnx")).metadata_props}
    assert (name in json.loads(meta["env_options"])) == (name != "keep_dim")


def test_env_options_the_recipe_sets_itself_or_strings_as_statistics_are_refused_by_name(tmp_path, capsys):
    bad = small_model(tmp_path / "threads.pt", env_options={"num_threads": 2})
    payload = torch.load(small_model(tmp_path / "x.pt"), weights_only=True)
    payload["obs_rms"] = {"mean": ["a"] * 46, "var": ["b"] * 46, "count": 1.0}
    torch.save(payload, tmp_path / "strings.pt")
    for path, named in ((bad, "num_threads"), (tmp_path / "strings.pt", "obs_rms")):
        assert ev.main([str(path), "--episodes", "1"]) == 2
        line = one_line(capsys.readouterr().err)
        assert named in line and path.name in line, line
        assert ex.main([str(path), "--out", str(tmp_path / "m.onnx")]) == 2
        line = one_line(capsys.readouterr().err)
        assert named in line and path.name in line, line
    assert not (tmp_path / "m.onnx").exists()


def test_a_weightless_model_claiming_a_huge_network_is_refused_before_it_is_built(tmp_path, capsys):
    payload = {
        "format": "chopperscape-ppo/1",
        "recipe": {"hidden": 1 << 16, "obs_type": "features", "env_options": {}},
        "obs_dim": 46,
        "num_actions": 5,
        "actor": {},
        "critic": {},
    }
    torch.save(payload, tmp_path / "huge.pt")
    start = time.monotonic()
    assert ev.main([str(tmp_path / "huge.pt"), "--episodes", "1"]) == 2
    line = one_line(capsys.readouterr().err)
    assert time.monotonic() - start < 10 and "`actor`" in line and "huge.pt" in line, line
    # Weights of other sizes than the recipe claims: refused by name too.
    payload = torch.load(small_model(tmp_path / "x.pt"), weights_only=True)
    payload["recipe"]["hidden"] = 4096
    torch.save(payload, tmp_path / "claims.pt")
    assert ev.main([str(tmp_path / "claims.pt"), "--episodes", "1"]) == 2
    assert "hidden 4096" in one_line(capsys.readouterr().err)


def test_a_teacher_that_cannot_guide_is_refused_before_anything_is_written(tmp_path, capsys):
    teacher = small_model(tmp_path / "teacher.pt", env_options={"autoreset_mode": "SameStep"})
    out = tmp_path / "run"
    args = ["--out", str(out), "--preset", "pixels", "--option", "obs_size=42x42", *SMALL, "--steps", "256"]
    assert train.main([*args, "--teacher", str(teacher)]) == 2
    line = one_line(capsys.readouterr().err)
    assert "autoreset_mode" in line and "teacher.pt" in line, line
    assert not out.exists()
    # A teacher whose weights do not fit its own options' observations.
    payload = torch.load(small_model(tmp_path / "x.pt", env_options={"frame_skip": 4}), weights_only=True)
    payload["recipe"]["env_options"]["frame_stack"] = 2
    torch.save(payload, tmp_path / "stacked.pt")
    assert train.main([*args, "--option", "frame_skip=4", "--teacher", str(tmp_path / "stacked.pt")]) == 2
    line = one_line(capsys.readouterr().err)
    assert "stacked.pt" in line, line
    assert not out.exists()
    # A folder or a device as the teacher: named as what it is.
    assert train.main([*args, "--teacher", str(tmp_path)]) == 2
    assert "is a folder" in one_line(capsys.readouterr().err)
    assert not out.exists()


def test_an_out_that_cannot_be_a_folder_is_exit_2(tmp_path, capsys):
    (tmp_path / "file").write_text("mine")
    out = tmp_path / "file" / "run"
    try:
        code = train.main(["--out", str(out), "--steps", "128", *SMALL])
    except SystemExit as e:
        code = e.code
    assert code == 2
    assert str(out) in one_line(capsys.readouterr().err)
    assert (tmp_path / "file").read_text() == "mine"


def fail_with_enospc(monkeypatch, after: int = 0):
    """The atomic writer's sync fails with a full disk (after `after` good writes)."""
    real = _atomic._fsync
    calls = {"n": 0}

    def fsync(path, directory=False):
        if not directory:
            calls["n"] += 1
            if calls["n"] > after:
                raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return real(path, directory)

    monkeypatch.setattr(_atomic, "_fsync", fsync)


def test_a_full_disk_while_training_is_one_line_and_leaves_no_temporary_file(tmp_path, monkeypatch, capsys):
    fail_with_enospc(monkeypatch, after=1)  # recipe.json is written; the model is not
    run = tmp_path / "run"
    assert train.main(["--out", str(run), "--steps", "128", *SMALL]) == 1
    line = one_line(capsys.readouterr().err)
    assert "model.pt" in line and "No space left" in line, line
    assert sorted(os.listdir(run)) == ["progress.csv", "recipe.json"]


def test_a_full_disk_at_the_start_leaves_nothing_behind(tmp_path, monkeypatch, capsys):
    fail_with_enospc(monkeypatch)
    run = tmp_path / "run"
    assert train.main(["--out", str(run), "--steps", "128", *SMALL]) == 1
    line = one_line(capsys.readouterr().err)
    assert "recipe.json" in line and "No space left" in line, line
    assert not run.exists()


def test_export_to_a_full_disk_or_under_a_file_is_one_line_and_writes_nothing(tmp_path, monkeypatch, capsys):
    src = small_model(tmp_path / "m.pt")
    (tmp_path / "file").write_text("mine")
    assert ex.main([str(src), "--out", str(tmp_path / "file" / "m.onnx"), "--no-check"]) == 2
    assert "is not a folder" in one_line(capsys.readouterr().err)
    assert ex.main([str(src), "--out", str(tmp_path), "--no-check"]) == 2
    assert "is a folder" in one_line(capsys.readouterr().err)
    # The model itself as --out, even with --force: refused, the model kept.
    before = src.read_bytes()
    assert ex.main([str(src), "--out", str(src), "--force", "--no-check"]) == 2
    assert "is the model file itself" in one_line(capsys.readouterr().err) and src.read_bytes() == before
    fail_with_enospc(monkeypatch)
    assert ex.main([str(src), "--out", str(tmp_path / "m.onnx"), "--no-check"]) == 1
    line = one_line(capsys.readouterr().err)
    assert "m.onnx" in line and "No space left" in line, line
    assert sorted(os.listdir(tmp_path)) == ["file", "m.pt"]


class Killed(BaseException):
    """The process dies here (SIGKILL: nothing after it runs)."""


def test_force_over_a_finished_run_never_leaves_a_folder_mixing_two_runs(tmp_path, monkeypatch, capsys):
    run = tmp_path / "run"
    assert train.main(["--out", str(run), "--steps", "128", *SMALL]) == 0
    old = {name: (run / name).read_bytes() for name in ("model.pt", "progress.csv", "recipe.json")}
    capsys.readouterr()

    def die(*a, **k):
        raise Killed

    monkeypatch.setattr(run_module, "save", die)  # killed before its first save
    with pytest.raises(Killed):
        train.main(["--out", str(run), "--steps", "128", "--seed", "7", *SMALL, "--force"])
    err = capsys.readouterr().err
    aside = run / "replaced-1"
    assert f"kept in {aside}" in err, err
    assert {name: (aside / name).read_bytes() for name in old} == old
    # What is left in the folder is the new run alone: its recipe and its curve, no model of the old one.
    assert sorted(p.name for p in run.iterdir() if p.is_file()) == ["progress.csv", "recipe.json"]
    assert json.loads((run / "recipe.json").read_text())["seed"] == 7
    assert (run / "progress.csv").read_text().startswith("env_steps,")


def test_evaluate_memory_does_not_grow_with_the_episodes(capsys):
    def peak(episodes: int) -> int:
        tracemalloc.start()
        try:
            assert ev.main(["noop", "--episodes", str(episodes), "--option", "max_episode_steps=2"]) == 0
            return tracemalloc.get_traced_memory()[1]
        finally:
            tracemalloc.stop()

    peak(128)
    small, large = peak(256), peak(4096)
    out = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert out["episodes"] == 4096 and out["mean_steps"] == 2
    assert large < small + 256 * 1024, (small, large)


def test_per_episode_rows_are_streamed_into_one_valid_line(capsys):
    assert ev.main(["noop", "--episodes", "300", "--option", "max_episode_steps=2", "--per-episode"]) == 0
    (line,) = capsys.readouterr().out.splitlines()
    out = json.loads(line)
    assert [r["seed"] for r in out["per_episode"]] == list(range(1_000_000, 1_000_300))
    assert out["episodes"] == 300 and out["causes"] == {"truncated": 1.0}


GOOD_EVAL = {
    "model": "m",
    "seed": 1_000_000,
    "episodes": 100,
    "mean_return": 5000.0,
    "std_return": 100.0,
    "min_return": 4000,
    "max_return": 6000,
    "mean_steps": 900.0,
    "causes": {"bird": 0.5, "fuel": 0.5},
}
GOOD_CSV = "env_steps,wall_s,episodes,mean_return,std_return,mean_length\n100,1,1,10,1,5\n200,2,2,20,1,5\n"


def _eval_with(**changes) -> bytes:
    doc = {**GOOD_EVAL, **changes}
    return json.dumps({k: v for k, v in doc.items() if v is not ...}).encode()


#: Crafted files for `seeds --summarise`: (file name, content or a callable making it, a word the error names).
CRAFTED = [
    ("seed-1.eval.json", _eval_with(mean_return=...), "mean_return"),
    ("seed-1.eval.json", _eval_with(min_return=...), "min_return"),
    ("seed-1.eval.json", _eval_with(mean_steps=...), "mean_steps"),
    ("seed-1.eval.json", _eval_with(mean_return="5000"), "mean_return"),
    ("seed-1.eval.json", _eval_with(causes=[1, 2]), "causes"),
    ("seed-1.eval.json", _eval_with(causes={"bird": "all"}), "causes"),
    ("seed-1.eval.json", _eval_with(episodes=True), "episodes"),
    ("seed-1.eval.json", _eval_with(mean_return=1e300), "mean_return"),
    ("seed-1.eval.json", _eval_with(std_return=10**400), "std_return"),
    ("seed-1.eval.json", _eval_with().replace(b"5000.0", b"NaN"), "NaN"),
    ("seed-1.eval.json", _eval_with().replace(b"5000.0", b"Infinity"), "Infinity"),
    ("seed-1.eval.json", _eval_with().replace(b"5000.0", b"-Infinity"), "Infinity"),
    ("seed-1.eval.json", _eval_with().replace(b"5000.0", b"1e400"), "1e400"),
    ("seed-1.eval.json", b"", "not an evaluation JSON"),
    ("seed-1.eval.json", b"[1, 2]", "not an evaluation JSON"),
    ("seed-1.eval.json", b"\xff\xfe{}", "UTF-8"),
    ("seed-1.eval.json", b"[" * 100_000, "not an evaluation JSON"),
    ("seed-1.eval.json", "dir", "folder"),
    ("seed-1.eval.json", "/dev/zero", "device"),
    ("seed-1.csv", "dir", "folder"),
    ("seed-1.csv", "/dev/zero", "device"),
    ("seed-1.csv", b"", "no rows"),
    ("seed-1.csv", b"env_steps,wall_s\n1,2\n", "missing columns"),
    ("seed-1.csv", GOOD_CSV.replace("10,1,5", "ten,1,5").encode(), "'ten'"),
    ("seed-1.csv", GOOD_CSV.replace("10,1,5", "nan,1,5").encode(), "'nan'"),
    ("seed-1.csv", GOOD_CSV.replace("100,1", "inf,1").encode(), "'inf'"),
    ("seed-1.csv", GOOD_CSV.replace("200,2", "50,2").encode(), "increase"),
    ("seed-1.csv", b"\xff" + GOOD_CSV.encode(), "UTF-8"),
    ("seed-1.csv", b"env_steps,mean_return\n1,\x00\n", "seed-1.csv"),
    ("baseline-heuristic.json", _eval_with(std_return=-1.0), "std_return"),
    ("baseline-random.json", b"NaN", "NaN"),
]


@pytest.mark.parametrize("name,content,named", CRAFTED, ids=[f"{i}-{c[0]}" for i, c in enumerate(CRAFTED)])
def test_summarise_refuses_each_crafted_file_by_name_and_writes_nothing(name, content, named, tmp_path, capsys):
    (tmp_path / "seed-0.eval.json").write_bytes(_eval_with())
    (tmp_path / "seed-0.csv").write_text(GOOD_CSV)
    (tmp_path / "seed-1.eval.json").write_bytes(_eval_with())
    (tmp_path / "seed-1.csv").write_text(GOOD_CSV)
    target = tmp_path / name
    target.unlink(missing_ok=True)
    if content == "dir":
        target.mkdir()
    elif content == "/dev/zero":
        target.symlink_to("/dev/zero")
    else:
        target.write_bytes(content)
    before = sorted(os.listdir(tmp_path))
    start = time.monotonic()
    assert seeds.main(["--summarise", str(tmp_path), "--steps", "200"]) == 2
    assert time.monotonic() - start < 30
    captured = capsys.readouterr()
    line = one_line(captured.err)
    assert name in line and named in line, line
    assert captured.out == "" and sorted(os.listdir(tmp_path)) == before


def test_summarise_writes_valid_json_from_good_files(tmp_path, capsys):
    for k in (0, 1):
        (tmp_path / f"seed-{k}.eval.json").write_bytes(_eval_with(mean_return=5000.0 + k))
        (tmp_path / f"seed-{k}.csv").write_text(GOOD_CSV)
    for name, mean in (("random", 10.0), ("heuristic", 3000.0)):
        doc = {**GOOD_EVAL, "mean_return": mean, "runner": {"episodes": 100, "seed": 1_000_000, "option": []}}
        (tmp_path / f"baseline-{name}.json").write_text(json.dumps(doc))
    assert seeds.main(["--summarise", str(tmp_path), "--steps", "200"]) == 0
    summary = json.loads(
        (tmp_path / "summary.json").read_text(),
        parse_constant=lambda c: pytest.fail(f"{c} in summary.json"),
    )
    assert summary["seeds"] == [0, 1] and math.isfinite(summary["iqm"])
    assert "IQM" in capsys.readouterr().out
    assert not [p for p in os.listdir(tmp_path) if p.endswith(".part")]


def test_a_pickle_refusal_names_the_file_and_the_global_without_terminal_codes(tmp_path, monkeypatch, capsys):
    import pickle

    def refuse(*a, **k):
        raise pickle.UnpicklingError(
            "\x1b[1mWeights only load failed.\x1b[0m In PyTorch 2.6, we changed the default value of the "
            "`weights_only` argument.\n\n\x1b[1mTrying to load unsupported GLOBAL posix.system whose module posix is "
            "blocked.\x1b[0m\n\nCheck the documentation of torch.load to learn more"
        )

    src = small_model(tmp_path / "evil.pt")
    monkeypatch.setattr(torch, "load", refuse)
    assert ev.main([str(src), "--episodes", "1"]) == 2
    line = one_line(capsys.readouterr().err)
    assert "\x1b" not in line and "evil.pt" in line and "GLOBAL posix.system" in line and "run code" in line, line


@pytest.mark.parametrize("what,named", [("/dev/zero", "is a device"), ("dir", "is a folder")])
def test_a_device_or_a_folder_as_a_model_says_what_it_is(what, named, tmp_path, capsys):
    path = pathlib.Path(what) if what != "dir" else tmp_path
    assert ev.main([str(path), "--episodes", "1"]) == 2
    line = one_line(capsys.readouterr().err)
    assert named in line and str(path) in line, line
    assert ex.main([str(path), "--out", str(tmp_path / "m.onnx")]) == 2
    line = one_line(capsys.readouterr().err)
    assert named in line and str(path) in line, line


# --- Every flag of the four commands: huge, negative, NaN, missing files, folders in place of files ----------


@pytest.mark.parametrize(
    "args,named",
    [
        (["--hidden", "65536"], "hidden"),  # 2 x 16 GiB of weights: minutes before any error
        (["--update-epochs", "100000000"], "update_epochs"),  # an update that never ends, signals deferred
        (["--steps", str(10**13)], "total_steps"),
        (["--num-steps", "100000000"], "num_steps"),  # 155 GiB of rollout buffers
        (["--option", "obs_size=4096x4096", "--obs-type", "rgb_float", "--network", "nature"], "parameters"),
        (["--preset", "pixels", "--teacher", "/dev/zero"], "is a device"),
        (["--preset", "pixels", "--teacher", "."], "is a folder"),
        (["--preset", "pixels", "--teacher", "recipe.json"], "not a zip archive"),
    ],
)
def test_train_flags_out_of_bounds_are_one_line_exit_2_before_anything_is_written(
    args, named, tmp_path, monkeypatch, capsys
):
    monkeypatch.chdir(tmp_path)
    pathlib.Path("recipe.json").write_text("{}")
    out = tmp_path / "run"
    start = time.monotonic()
    try:
        code = train.main(["--out", str(out), *SMALL, *args])
    except SystemExit as e:
        code = e.code
    assert code == 2 and time.monotonic() - start < 30
    assert named in one_line(capsys.readouterr().err)
    assert not out.exists()


@pytest.mark.parametrize(
    "args,named",
    [
        (["--seeds", "0", "--out", "OUT", "--jobs", "0"], "--jobs"),
        (["--seeds", "0", "--out", "OUT", "--eval-episodes", str(10**14)], "--eval-episodes"),
        (["--seeds", "0", "--out", "OUT", "--eval-seed", str(2**63)], "--eval-seed"),
        (["--seeds", "0", "--out", "OUT", "--steps", str(10**20)], "--steps"),
        (["--seeds", str(2**64), "--out", "OUT"], "--seeds"),
        (["--seeds", "0", "--out", "FILE"], "not a folder"),
        # Training flags: checked as train checks them before any seed trains (they failed in each child, exit 1).
        (["--seeds", "0", "--out", "OUT", "--hidden", "0"], "hidden"),
        (["--seeds", "0", "--out", "OUT", "--steps", "100", "--preset", "pixels", "--teacher", "/dev/zero"], "device"),
    ],
)
def test_seeds_flags_out_of_bounds_are_refused_before_any_training(args, named, tmp_path, capsys):
    (tmp_path / "FILE").write_text("mine")
    args = [str(tmp_path / x) if x in ("OUT", "FILE") else x for x in args]
    with pytest.raises(SystemExit) as e:
        seeds.main(args)
    assert e.value.code == 2 and named in one_line(capsys.readouterr().err)
    assert sorted(os.listdir(tmp_path)) == ["FILE"]


def test_evaluate_refuses_more_episodes_than_it_can_play(capsys):
    with pytest.raises(SystemExit) as e:
        ev.main(["noop", "--episodes", str(10**23)])
    assert e.value.code == 2 and "--episodes" in one_line(capsys.readouterr().err)
