"""Trained policies everywhere (issue 19): the ONNX export (`python -m chopperscape.learn.export`), the command line
playing it (`chopperscape demo --policy MODEL.onnx`) the same episodes as
`python -m chopperscape.learn.evaluate MODEL.pt`,
and videos from `evaluate --video`."""

from __future__ import annotations

import hashlib
import importlib.util
import json
import pathlib
import pickle
import shutil
import subprocess

import numpy as np
import pytest
from test_policies import ROOT, cli

needs_torch = pytest.mark.skipif(
    importlib.util.find_spec("torch") is None or importlib.util.find_spec("onnx") is None,
    reason="torch and onnx are not installed (scripts/test-python.sh installs them)",
)
MODEL = ROOT / "models" / "ppo-features.pt"
EXPORT = ROOT / "models" / "ppo-features.onnx"
PIXEL_MODEL = ROOT / "models" / "ppo-pixels.pt"
PIXEL_EXPORT = ROOT / "models" / "ppo-pixels.onnx"
TEACHER_PIXEL_MODEL = ROOT / "models" / "ppo-pixels-teacher.pt"
TEACHER_PIXEL_EXPORT = ROOT / "models" / "ppo-pixels-teacher.onnx"


def export(*args) -> int:
    from chopperscape.learn import export as ex

    return ex.main([str(a) for a in args])


def evaluate(*args) -> int:
    from chopperscape.learn import evaluate as ev

    return ev.main([str(a) for a in args])


def make_pixel_model(path: pathlib.Path) -> None:
    """The 84×84 pixel recipe's CNN (`pixels-teacher`), untrained (torch seed 0), reading plain frames as 0.1.0's
    models do: what `crates/policy/tests/data/pixels-untrained.onnx` is the export of."""
    import torch

    from chopperscape.learn import modelfile, networks, normalize
    from chopperscape.learn.recipe import PRESETS, Recipe

    torch.manual_seed(0)
    shape = (84, 84, 4)
    recipe = Recipe(**PRESETS["pixels-teacher"], invert_frames=False)
    modelfile.save(
        path, networks.build_agent("small", shape, 5), normalize.ObsNormalizer(shape, False), recipe, shape, 0
    )


def metadata(path: pathlib.Path) -> dict[str, str]:
    import onnx

    return {p.key: p.value for p in onnx.load(str(path)).metadata_props}


@needs_torch
@pytest.mark.parametrize(
    "model, exported, obs_type, shape, options, pixels_version",
    [
        (MODEL, EXPORT, "features", [46], {}, "3"),
        (
            PIXEL_MODEL,
            PIXEL_EXPORT,
            "grayscale",
            [42, 42, 4],
            {"frame_skip": 4, "frame_stack": 4, "obs_size": [42, 42]},
            "3",
        ),
        (
            TEACHER_PIXEL_MODEL,
            TEACHER_PIXEL_EXPORT,
            "grayscale",
            [84, 84, 4],
            {"frame_skip": 4, "frame_stack": 4, "obs_size": [84, 84]},
            "2",
        ),
    ],
    ids=["features", "pixels", "pixels-teacher"],
)
def test_the_committed_export_is_of_the_committed_model(model, exported, obs_type, shape, options, pixels_version):
    meta = metadata(exported)
    assert meta["format"] == "chopperscape-policy/1"
    assert meta["source_sha256"] == hashlib.sha256(model.read_bytes()).hexdigest()
    assert (meta["obs_type"], json.loads(meta["obs_shape"]), json.loads(meta["env_options"])) == (
        obs_type,
        shape,
        options,
    )
    # The teacher-free pixel policy learned layout 3 (the agent view at 42×42), the teacher-guided one layout 2 (the
    # art), which the loaders show them; a features policy's pixels_version
    # only says which layout was current when it was exported (`python -m chopperscape.learn.export MODEL --force`).
    assert (meta["features_version"], meta["pixels_version"]) == ("2", pixels_version)


@needs_torch
def test_export_maps_raw_observations_to_torchs_logits(tmp_path, capsys):
    out = tmp_path / "policy.onnx"
    assert export(MODEL, "--out", out) == 0
    result = json.loads(capsys.readouterr().out)
    if importlib.util.find_spec("onnxruntime") is None:
        assert result["checked"] is False and "onnxruntime" in result["why"]
        pytest.skip("onnxruntime is not installed: the logits check is skipped")
    assert result["checked"] and result["observations"] == 1000 and result["max_abs_diff"] <= 1e-5
    # The committed export (0.1.0) has every key but the training seeds, which the model file records.
    meta = metadata(out)
    from chopperscape.learn.modelfile import load

    recipe = load(MODEL).recipe
    assert json.loads(meta.pop("train_seeds")) == [[recipe["seed"], recipe["num_envs"]]]
    assert meta == metadata(EXPORT)


@needs_torch
def test_a_pixel_model_exports_with_uint8_frames(tmp_path, capsys):
    import onnx

    make_pixel_model(tmp_path / "model.pt")
    out = tmp_path / "pixels.onnx"
    assert export(tmp_path / "model.pt", "--out", out) == 0
    result = json.loads(capsys.readouterr().out)
    assert result["obs_shape"] == [84, 84, 4]
    assert result.get("checked") is not True or result["max_abs_diff"] <= 1e-5
    meta = metadata(out)
    assert meta["obs_type"] == "grayscale"
    assert json.loads(meta["env_options"]) == {"frame_skip": 4, "frame_stack": 4, "obs_size": [84, 84]}
    graph_input = onnx.load(str(out)).graph.input[0].type.tensor_type
    assert graph_input.elem_type == onnx.TensorProto.UINT8
    assert [d.dim_value or d.dim_param for d in graph_input.shape.dim] == ["batch", 84, 84, 4]


@needs_torch
def test_bad_models_and_outputs_are_one_line_errors(tmp_path, capsys):
    marker = tmp_path / "ran"

    class Payload:
        def __reduce__(self):
            return (pathlib.Path.touch, (marker,))

    hostile = tmp_path / "hostile.pt"
    hostile.write_bytes(pickle.dumps({"format": "chopperscape-ppo/1", "x": Payload()}))
    text = tmp_path / "notes.pt"
    text.write_text("not a model")
    cases = [
        (tmp_path / "missing.pt", "does not exist"),
        (text, "is not a chopperscape.learn.train model"),
        (hostile, "is not a chopperscape.learn.train model"),
    ]
    for model, message in cases:
        assert export(model, "--out", tmp_path / "x.onnx") == 2
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    assert not marker.exists()
    assert not (tmp_path / "x.onnx").exists()
    (tmp_path / "taken.onnx").write_text("")
    assert export(MODEL, "--out", tmp_path / "taken.onnx") == 2
    assert "pass --force" in capsys.readouterr().err
    assert export(MODEL, "--out", tmp_path / "nowhere" / "x.onnx") == 2
    assert "does not exist" in capsys.readouterr().err


#: (model, its export, warned, evaluate --option, CLI flags) of the comparisons: the trained rules truncated early,
#: and birds five times as often as in training, so that every episode ends by a bird at a different step; the
#: pixel policy (42×42×4 agent-view frames drawn in Rust, its CNN run by the Rust loader) on its own rules.
CASES = [
    (MODEL, EXPORT, [], ["max_episode_steps=400"], ["--max-episode-steps", "400"]),
    (
        MODEL,
        EXPORT,
        ["bird_prob"],
        ["bird_prob=0.05", "max_episode_steps=2000"],
        ["--bird-prob", "0.05", "--max-episode-steps", "2000"],
    ),
    (PIXEL_MODEL, PIXEL_EXPORT, [], ["max_episode_steps=2000"], ["--max-episode-steps", "2000"]),
]


def assert_demo_plays(
    exe: pathlib.Path, exported: pathlib.Path, episodes: int, seed: int, flags: list[str], expected: list[dict]
) -> subprocess.CompletedProcess:
    """Runs `chopperscape demo --policy EXPORTED --json` and asserts that it plays the episodes `evaluate
    --per-episode` reported (`expected`: seed, return, steps and cause of each); returns the finished run."""
    cmd = [str(exe), "demo", "--policy", str(exported), "--episodes", str(episodes), "--seed", str(seed), "--json"]
    run = subprocess.run([*cmd, *flags], check=True, capture_output=True, text=True)
    got = [json.loads(line) for line in run.stdout.splitlines()]
    keys = ("seed", "return", "steps", "cause")
    assert [{k: e[k] for k in keys} for e in got] == [{k: e[k] for k in keys} for e in expected]
    return run


@needs_torch
@pytest.mark.parametrize(
    "model,exported,warned,options,flags", CASES, ids=["trained-rules", "more-birds", "pixels-trained-rules"]
)
def test_cli_demo_plays_the_export_as_evaluate_plays_the_model(model, exported, warned, options, flags, capsys):
    exe = cli()
    if exe is None:
        pytest.skip("cargo is not installed: the comparison with `chopperscape demo --json` is skipped")
    seed, episodes = 11, 6
    args = [model, "--episodes", episodes, "--seed", seed, "--per-episode"]
    assert evaluate(*args, *[x for o in options for x in ("--option", o)]) == 0
    expected = json.loads(capsys.readouterr().out)["per_episode"]
    run = assert_demo_plays(exe, exported, episodes, seed, flags, expected)
    for name in warned:
        assert f"was trained with {name} " in run.stderr, run.stderr
    if not warned:
        assert "warning" not in run.stderr, run.stderr


@needs_torch
@pytest.mark.parametrize("network", ["small-coord-deep-stem", "small-coord-deep-stem-norm"])
def test_cli_demo_plays_the_grey_band_network_as_evaluate_plays_it(network, tmp_path, capsys):
    """The "-stem" network's export (its grey bands a grouped Conv with fixed weights) runs in the Rust policy crate
    and plays the episodes torch plays: an untrained network (torch seed 0) whose policy head is scaled up, so that
    its greedy actions are not near-ties. So does "-norm"'s, whose graph holds ONNX's LayerNormalization."""
    import torch

    from chopperscape.learn import modelfile, networks, normalize
    from chopperscape.learn.recipe import PRESETS, Recipe

    exe = cli()
    if exe is None:
        pytest.skip("cargo is not installed: the comparison with `chopperscape demo --json` is skipped")
    torch.manual_seed(0)
    shape = (42, 42, 4)
    agent = networks.build_agent(network, shape, 5, invert_frames=True)
    with torch.no_grad():
        agent.actor[1].weight.mul_(300.0)  # type: ignore[index]
    recipe = Recipe(**{**PRESETS["pixels"], "network": network})
    model, onnx = tmp_path / "stem.pt", tmp_path / "stem.onnx"
    modelfile.save(model, agent, normalize.ObsNormalizer(shape, False), recipe, shape, 0)
    assert export(model, "--out", onnx) == 0
    capsys.readouterr()
    assert evaluate(model, "--episodes", 4, "--seed", 11, "--per-episode") == 0
    expected = json.loads(capsys.readouterr().out)["per_episode"]
    assert_demo_plays(exe, onnx, 4, 11, [], expected)
    assert len({e["steps"] for e in expected}) > 1  # the policy acts: not one fixed action's episodes


def test_cli_refuses_a_policy_file_it_cannot_run(tmp_path):
    exe = cli()
    if exe is None:
        pytest.skip("cargo is not installed")
    bad = tmp_path / "bad.onnx"
    bad.write_bytes(EXPORT.read_bytes()[:500])
    for path, message in [(bad, "not a ChopperScape policy"), (tmp_path / "none.onnx", "cannot read")]:
        run = subprocess.run(
            [str(exe), "record", "--policy", str(path), "--out", str(tmp_path / "a.gif")],
            capture_output=True,
            text=True,
        )
        assert run.returncode == 2 and message in run.stderr and "panicked" not in run.stderr, run.stderr
        assert not (tmp_path / "a.gif").exists()


def _gif_frames(path: pathlib.Path) -> list[np.ndarray]:
    from PIL import Image, ImageSequence

    with Image.open(path) as im:
        return [np.asarray(frame.convert("RGB")) for frame in ImageSequence.Iterator(im)]


@needs_torch
def test_evaluate_video_gif_shows_exactly_the_played_episodes(tmp_path, capsys):
    from chopperscape.env import ChopperScapeEnv

    out = tmp_path / "agent.gif"
    assert (
        evaluate(
            MODEL,
            "--episodes",
            3,
            "--seed",
            2,
            "--option",
            "bird_prob=0.2",
            "--per-episode",
            "--video",
            out,
            "--video-episodes",
            2,
        )
        == 0
    )
    result = json.loads(capsys.readouterr().out)
    first_two = result["per_episode"][:2]
    assert "actions" not in first_two[0] and result["video"] == str(out)
    frames = _gif_frames(out)
    assert len(frames) == sum(e["steps"] + 1 for e in first_two)
    # The frames are the env's own, after reset and after every step of each episode in turn.
    env = ChopperScapeEnv(render_mode="rgb_array", obs_type="features", bird_prob=0.2)
    env.reset(seed=2)
    assert np.array_equal(frames[0], env.render())
    assert np.array_equal(frames[first_two[0]["steps"] + 1], (env.reset(seed=3), env.render())[1])
    assert not list(tmp_path.glob(".*.part"))


def test_evaluate_video_mp4_and_its_errors(tmp_path, capsys, monkeypatch):
    assert evaluate("heuristic", "--episodes", 2, "--video", tmp_path / "a.avi") == 2
    assert "give a .gif or .mp4" in capsys.readouterr().err
    with pytest.raises(SystemExit) as exit_:
        evaluate("heuristic", "--episodes", 1, "--video", tmp_path / "a.gif", "--video-episodes", 2)
    assert exit_.value.code == 2 and "--video-episodes 2" in capsys.readouterr().err
    out = tmp_path / "a.mp4"
    if shutil.which("ffmpeg") is not None:
        assert evaluate("heuristic", "--episodes", 1, "--option", "max_episode_steps=60", "--video", out) == 0
        capsys.readouterr()
        probe = subprocess.run(["ffmpeg", "-i", str(out), "-f", "null", "-"], capture_output=True, text=True)
        assert "frame=   61" in probe.stderr or "frame=61" in probe.stderr.replace(" ", ""), probe.stderr[-300:]
        out.unlink()
    monkeypatch.setenv("PATH", str(tmp_path))
    assert evaluate("heuristic", "--episodes", 1, "--video", out) == 2
    err = capsys.readouterr().err
    assert "needs the ffmpeg program" in err and "Traceback" not in err
    assert not out.exists()
