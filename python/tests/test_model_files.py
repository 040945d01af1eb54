"""Model files are shared files: loading one never runs code from it (recipe models are read with
`weights_only=True`, SB3's pickled parts are replaced, pickles need `--trust-pickle`), and `evaluate` refuses what
it cannot play with a clear error, never a traceback."""

from __future__ import annotations

import base64
import importlib.util
import json
import pathlib
import pickle
import zipfile

import pytest
from conftest import SHORT, needs_sb3, needs_torch

ROOT = pathlib.Path(__file__).resolve().parents[2]


class Payload:
    """Unpickling this writes the marker file: proof that loading ran code from the file."""

    def __init__(self, marker: pathlib.Path):
        self.marker = str(marker)

    def __reduce__(self):
        return (exec, (f"open({self.marker!r}, 'w').write('ran')",))


def evaluate(*args: str) -> int:
    from chopperscape.learn import evaluate as ev

    return ev.main([str(a) for a in args])


@needs_torch
def test_a_crafted_model_pt_runs_no_code_in_either_pickle_form(tmp_path, capsys):
    import torch

    marker = tmp_path / "ran"
    plain = tmp_path / "plain.pt"
    plain.write_bytes(pickle.dumps({"format": "chopperscape-ppo/1", "x": Payload(marker)}))
    zipped = tmp_path / "zipped.pt"
    torch.save({"format": "chopperscape-ppo/1", "recipe": {}, "x": Payload(marker)}, zipped)
    for path in (plain, zipped):
        assert evaluate(path, "--episodes", "1") == 2
        err = capsys.readouterr().err
        assert "is not a chopperscape.learn.train model" in err and path.name in err, err
        assert not marker.exists(), f"loading {path.name} ran code from it"


@needs_torch
def test_recipe_models_load_with_weights_only(tmp_path, capsys):
    import torch

    from chopperscape.learn import modelfile, networks, normalize
    from chopperscape.learn.recipe import Recipe

    # The committed policy and a freshly saved one are tensors and plain data.
    committed = torch.load(ROOT / "models" / "ppo-features.pt", map_location="cpu", weights_only=True)
    assert committed["format"] == "chopperscape-ppo/1"
    recipe = Recipe(hidden=8, env_options={"obs_size": (84, 84), "max_fuel": 300})
    agent = networks.Agent(46, 5, 8)
    norm = normalize.ObsNormalizer((46,))
    norm.rms.update(torch.rand(10, 46).numpy())
    modelfile.save(tmp_path / "model.pt", agent, norm, recipe, (46,), 123)
    back = torch.load(tmp_path / "model.pt", map_location="cpu", weights_only=True)
    assert back["recipe"]["env_options"] == {"obs_size": [84, 84], "max_fuel": 300} and back["env_steps"] == 123
    assert not list(tmp_path.glob(".*part"))
    assert evaluate(ROOT / "models" / "ppo-features.pt", "--episodes", "2", "--option", "max_episode_steps=30") == 0
    out = json.loads(capsys.readouterr().out)
    assert out["mean_steps"] == 30 and out["causes"] == {"truncated": 1.0} and out["max_episode_steps"] == 30


@needs_torch
@pytest.mark.parametrize("name", sorted(p.name for p in (ROOT / "models").glob("*.pt")))
def test_every_committed_model_loads_as_data_and_plays_under_its_own_options(name, capsys):
    """Each `models/*.pt` (the features policy, the frame-skip-4 teacher, the pixel policy) is tensors and plain
    data, and `evaluate` plays it with the options it was trained with (frame skip, frame size and stack)."""
    from chopperscape.learn import modelfile

    loaded = modelfile.load(ROOT / "models" / name)
    assert evaluate(ROOT / "models" / name, "--episodes", "2", "--option", "max_episode_steps=40") == 0
    out = json.loads(capsys.readouterr().out)
    assert out["episodes"] == 2 and out["mean_return"] > 0
    if loaded.recipe["obs_type"] != "features":  # a pixel policy: inverted frames, the teacher only in its recipe
        assert loaded.recipe["invert_frames"] is True and loaded.agent.actor[0][0].invert is True
        # no auxiliary head and no teacher weights: the keys of any model this trainer writes
        assert set(torch_payload(ROOT / "models" / name)) == set(torch_payload(ROOT / "models" / "ppo-features-fs4.pt"))


def torch_payload(path):
    import torch

    return torch.load(path, map_location="cpu", weights_only=True)


@needs_torch
def test_a_model_whose_input_does_not_fit_the_options_is_a_clear_error(tmp_path, capsys):
    from chopperscape.learn import modelfile, networks, normalize
    from chopperscape.learn.recipe import Recipe

    modelfile.save(
        tmp_path / "model.pt", networks.Agent(46, 5, 8), normalize.ObsNormalizer((46,)), Recipe(hidden=8), (46,), 0
    )
    assert evaluate(tmp_path / "model.pt", "--episodes", "1", "--option", "frame_stack=2") == 2
    err = capsys.readouterr().err
    assert "takes observations of shape (46,)" in err and "(92,)" in err and "Traceback" not in err, err
    # A payload with the right format but damaged fields names the field.
    import torch

    torch.save(
        {
            "format": "chopperscape-ppo/1",
            "recipe": {"hidden": 8, "obs_type": "features", "env_options": {}},
            "obs_dim": 46,
            "num_actions": 5,
            "actor": {"w": torch.zeros(2)},
            "critic": {},
        },
        tmp_path / "bad.pt",
    )
    assert evaluate(tmp_path / "bad.pt", "--episodes", "1") == 2
    assert "`actor`" in capsys.readouterr().err


def test_evaluate_options_that_collide_with_its_own_are_clear_errors(capsys):
    for option, named in [
        ("num_threads=2", "num_threads"),
        ("autoreset_mode=SameStep", "autoreset_mode"),
        ("copy=false", "copy"),
        ("no_such_option=1", "unknown option"),
    ]:
        with pytest.raises(SystemExit) as e:
            evaluate("random", "--episodes", "1", "--option", option)
        assert e.value.code == 2
        err = capsys.readouterr().err
        assert named in err and "Traceback" not in err, (option, err)
    # max_episode_steps is the truncation of evaluation's episodes, as everywhere else.
    assert evaluate("noop", "--episodes", "2", "--option", "max_episode_steps=25", "--option", "hud=false") == 0
    out = json.loads(capsys.readouterr().out)
    assert out["mean_steps"] == 25 and out["causes"] == {"truncated": 1.0}


def test_a_file_named_like_a_builtin_policy_is_not_a_model_unless_given_as_a_path(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "random").write_bytes(b"whatever is here")
    assert evaluate("random", "--episodes", "2", "--seed", "4", "--option", f"max_fuel={SHORT['max_fuel']}") == 0
    assert json.loads(capsys.readouterr().out)["episodes"] == 2
    assert evaluate("./random", "--episodes", "1") == 2
    err = capsys.readouterr().err
    # Read as a model: refused as one (or, without torch, because reading models needs it), never a traceback.
    assert "'random'" in err and "Traceback" not in err, err
    if importlib.util.find_spec("torch") is None:
        assert "needs torch" in err and "chopperscape[train]" in err


# --- Stable-Baselines3 --------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def sb3_model(tmp_path_factory):
    """A tiny SB3 PPO trained through the adapter, saved with its VecNormalize as pickle and as data."""
    if importlib.util.find_spec("stable_baselines3") is None:
        pytest.skip("stable-baselines3 is not installed")
    from stable_baselines3 import PPO
    from stable_baselines3.common.vec_env import VecNormalize

    from chopperscape.integrations.sb3 import ChopperScapeVecEnv
    from chopperscape.integrations.sb3_files import save_normalization

    folder = tmp_path_factory.mktemp("sb3")
    env = VecNormalize(ChopperScapeVecEnv(2, seed=0, obs_type="features", max_fuel=100), gamma=0.999)
    model = PPO(
        "MlpPolicy", env, n_steps=32, batch_size=32, n_epochs=1, device="cpu", policy_kwargs={"net_arch": [16]}
    ).learn(64)
    model.save(folder / "model.zip")
    env.save(str(folder / "vecnormalize.pkl"))
    save_normalization(env, folder / "vecnormalize.json")
    return folder


def copy_model(src: pathlib.Path, dst: pathlib.Path, *, pkl: bool = False, data: bool = False) -> pathlib.Path:
    dst.mkdir()
    (dst / "model.zip").write_bytes((src / "model.zip").read_bytes())
    if pkl:
        (dst / "vecnormalize.pkl").write_bytes((src / "vecnormalize.pkl").read_bytes())
    if data:
        (dst / "vecnormalize.json").write_text((src / "vecnormalize.json").read_text())
    return dst / "model.zip"


@needs_sb3
def test_sb3_models_load_without_unpickling_and_pickles_need_trust(sb3_model, tmp_path, capsys):
    args = ["--episodes", "2", "--option", "obs_type=features", "--option", "max_fuel=100"]
    # Normalisation statistics as data: no flag needed.
    assert evaluate(copy_model(sb3_model, tmp_path / "data", data=True), *args) == 0
    with_data = json.loads(capsys.readouterr().out)
    # Only SB3's pickle: refused, saying how to go on.
    pkl_only = copy_model(sb3_model, tmp_path / "pkl", pkl=True)
    assert evaluate(pkl_only, *args) == 2
    err = capsys.readouterr().err
    assert "vecnormalize.pkl is a pickle" in err and "--trust-pickle" in err and "save_normalization" in err, err
    assert evaluate(pkl_only, *args, "--trust-pickle") == 0
    trusted = json.loads(capsys.readouterr().out)
    # Both read the same statistics: the same episodes.
    assert (with_data["mean_return"], with_data["mean_steps"]) == (trusted["mean_return"], trusted["mean_steps"])


@needs_sb3
def test_a_crafted_sb3_zip_or_vecnormalize_runs_no_code(sb3_model, tmp_path, capsys):
    marker = tmp_path / "ran"
    evil = base64.b64encode(pickle.dumps(Payload(marker))).decode()
    args = ["--episodes", "1", "--option", "obs_type=features", "--option", "max_fuel=100"]

    def crafted(name: str, edit) -> pathlib.Path:
        path = copy_model(sb3_model, tmp_path / name)
        with zipfile.ZipFile(path) as z:
            files = {n: z.read(n) for n in z.namelist()}
        data = json.loads(files["data"])
        edit(data)
        files["data"] = json.dumps(data).encode()
        with zipfile.ZipFile(path, "w") as z:
            for n, b in files.items():
                z.writestr(n, b)
        return path

    # A pickled entry SB3 would unpickle on load: replaced (training state) or refused (what builds the policy).
    extra = crafted("extra", lambda d: d.update(ep_info_buffer={":type:": "x", ":serialized:": evil}))
    assert evaluate(extra, *args) == 0
    capsys.readouterr()
    policy = crafted("policy", lambda d: d.update(policy_class={":type:": "x", ":serialized:": evil}))
    assert evaluate(policy, *args) == 2
    assert "--trust-pickle" in capsys.readouterr().err
    kwargs = crafted(
        "kwargs",
        lambda d: d.update(
            policy_kwargs={":type:": "<class 'dict'>", ":serialized:": evil, "activation_fn": "<class 'os.system'>"}
        ),
    )
    assert evaluate(kwargs, *args) == 2
    assert "policy_kwargs['activation_fn']" in capsys.readouterr().err
    # A crafted vecnormalize.pkl beside a good model.
    good = copy_model(sb3_model, tmp_path / "evil-norm")
    (good.parent / "vecnormalize.pkl").write_bytes(pickle.dumps(Payload(marker)))
    assert evaluate(good, *args) == 2
    assert not marker.exists(), "loading an SB3 file ran code from it"


@needs_sb3
def test_an_sb3_model_for_other_observations_is_a_clear_error(sb3_model, tmp_path, capsys):
    path = copy_model(sb3_model, tmp_path / "m", data=True)
    assert evaluate(path, "--episodes", "1", "--option", "obs_type=features", "--option", "frame_stack=2") == 2
    err = capsys.readouterr().err
    assert "(46,)" in err and "(92,)" in err and "Traceback" not in err, err


@needs_sb3
def test_an_sb3_dqn_from_the_example_is_read_without_unpickling(tmp_path, capsys):
    """`python/examples/sb3_dqn.py` saves a DQN that `evaluate` and the bench read as data: its pickled training
    settings (the exploration schedule, the training frequency) are replaced, a crafted one runs no code, no replay
    buffer is allocated, and it plays as SB3's own unpickling load plays it. A DQN cannot sample: refused."""
    import subprocess
    import sys

    from chopperscape.bench import evaluate as bench

    out = tmp_path / "dqn"
    script = ROOT / "python" / "examples" / "sb3_dqn.py"
    done = subprocess.run(
        [sys.executable, str(script), "--mode", "sticky-v0", "--steps", "300", "--out", str(out)],
        capture_output=True,
        text=True,
        timeout=600,
    )
    assert done.returncode == 0, done.stderr
    args = ["--episodes", "2", "--option", "obs_type=features", "--option", "frame_skip=4"]
    assert evaluate(out / "model.zip", *args) == 0
    safe = json.loads(capsys.readouterr().out)
    assert evaluate(out / "model.zip", *args, "--trust-pickle") == 0
    trusted = json.loads(capsys.readouterr().out)
    assert (safe["mean_return"], safe["mean_steps"]) == (trusted["mean_return"], trusted["mean_steps"])
    assert evaluate(out / "model.zip", *args, "--stochastic") == 2
    assert "is a DQN: its policy is greedy" in capsys.readouterr().err
    doc = bench.run(str(out / "model.zip"), "sticky-v0", {"obs_type": "features"}, train_seeds=(0, 1))
    assert doc["policy"]["kind"] == "sb3" and doc["policy"]["recipe"] == {"algorithm": "DQN"}
    # A crafted pickle where DQN keeps its training frequency: replaced, never unpickled.
    marker = tmp_path / "ran"
    with zipfile.ZipFile(out / "model.zip") as z:
        files = {n: z.read(n) for n in z.namelist()}
    data = json.loads(files["data"])
    evil = base64.b64encode(pickle.dumps(Payload(marker))).decode()
    data["train_freq"] = {":type:": "x", ":serialized:": evil}
    files["data"] = json.dumps(data).encode()
    crafted = tmp_path / "crafted" / "model.zip"
    crafted.parent.mkdir()
    with zipfile.ZipFile(crafted, "w") as z:
        for n, b in files.items():
            z.writestr(n, b)
    assert evaluate(crafted, *args) == 0
    assert not marker.exists(), "loading an SB3 DQN ran code from it"
