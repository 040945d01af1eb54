"""Hardening, round four (issue 45): the benchmark's files, policy specs and outputs, resume and concurrent runs.
Each case was reproduced on the code before it; each is now a refusal in one line naming what was wrong (exit 2,
1 for a failed write) that changes nothing on disk, or the right number."""

from __future__ import annotations

import io
import json
import os
import signal
import subprocess
import sys
import time
import zipfile
from pathlib import Path

import pytest
from conftest import needs_sb3, needs_torch

from chopperscape.bench import evaluate, report, results
from chopperscape.bench.__main__ import main as bench

ROOT = Path(__file__).resolve().parents[2]
RESULTS = ROOT / "docs" / "bench" / "results"
MODELS = ROOT / "models"
#: A recipe that trains an update in a fraction of a second.
SMALL = ["--num-envs", "4", "--num-steps", "16", "--hidden", "8", "--num-minibatches", "2", "--update-epochs", "1"]


def _doc(name: str = "v0.random.seed0.json") -> dict:
    return json.loads((RESULTS / name).read_text())


def _write(path: Path, doc: dict, resummarise: bool = True) -> str:
    """`doc` written to `path`, its summary made consistent with its episodes (what a forger would do)."""
    if resummarise:
        doc["summary"] = results.summary(doc["episodes"], doc["mode"]["name"])
    path.write_text(json.dumps(doc))
    return str(path)


def _one_line(capsys, *names: str) -> str:
    err = capsys.readouterr().err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert "Traceback" not in err
    for name in names:
        assert name in lines[0], (name, lines[0])
    return lines[0]


# --- 1. a run counts once -----------------------------------------------------------------------------------------


def test_a_run_given_twice_copied_or_for_another_policy_seed_of_a_deterministic_policy_counts_once(tmp_path, capsys):
    one = RESULTS / "v0.heuristic.json"
    copy = tmp_path / "copy.json"
    copy.write_bytes(one.read_bytes())
    other_seed = _doc("v0.heuristic.json")
    other_seed["policy"]["policy_seed"] = 1  # what `evaluate heuristic --policy-seed 1` writes: the same episodes
    seed1 = _write(tmp_path / "seed1.json", other_seed, resummarise=False)
    link = tmp_path / "link.json"
    link.symlink_to(one)
    for second, says in [(one, "given twice"), (link, "given twice"), (copy, "same run"), (seed1, "same run")]:
        assert bench(["report", str(one), str(second), "--resamples", "100"]) == 2
        line = _one_line(capsys, str(second))
        assert says in line, line
    # Two different runs of one row are two runs.
    two = [str(RESULTS / "v0.random.seed0.json"), str(RESULTS / "v0.random.seed1.json")]
    assert bench(["report", *two, "--partial"]) == 0  # two of a stochastic policy's ten: partial
    assert "v0 (2 of 10 runs: partial)" in capsys.readouterr().out


# --- 2. impossible results ----------------------------------------------------------------------------------------


@pytest.mark.parametrize(
    "damage, says",
    [
        (lambda eps: [{**e, "return": 10**9} for e in eps], "`episodes[0].return` 1000000000 is out of -10.."),
        (lambda eps: [{**e, "return": -11} for e in eps], "`episodes[0].return` -11 is out of"),
        (lambda eps: [{**eps[0], "steps": 5, "return": 5, "cause": "truncated"}, *eps[1:]], "truncated at step 5"),
    ],
)
def test_results_the_protocol_cannot_give_are_refused(tmp_path, capsys, damage, says):
    doc = _doc()
    doc["episodes"] = damage(doc["episodes"])
    bad = _write(tmp_path / "bad.json", doc)
    assert bench(["report", bad, "--resamples", "100"]) == 2
    line = _one_line(capsys, bad, says)
    assert capsys.readouterr().out == "", line
    # The committed files all hold (truncation at the limit included).
    assert all(results.load(p) for p in sorted(RESULTS.glob("*.json")))


# --- 3 and 14. the observation a model learned: `look` ------------------------------------------------------------


@needs_torch
def test_an_onnx_pixel_model_plays_the_look_its_pt_plays_and_the_results_say_which():
    pytest.importorskip("onnxruntime")
    pt = evaluate.load(str(MODELS / "ppo-pixels-teacher.pt"), "v0")
    onnx = evaluate.load(str(MODELS / "ppo-pixels-teacher.onnx"), "v0")
    seen = {k: (list(v) if isinstance(v, tuple) else v) for k, v in pt.options.items() if k in evaluate.OBS_OPTIONS}
    assert pt.options["look"] == "art"  # pixel layout 2: the art at every size
    assert {k: (list(v) if isinstance(v, tuple) else v) for k, v in onnx.options.items() if k in seen} == seen
    assert evaluate._observation(onnx.options)["look"] == pt.options["look"]
    # A results file of frames always says which look it saw (the default too); features need none.
    assert evaluate._observation({"obs_type": "grayscale"})["look"] == "auto"
    assert "look" not in evaluate._observation({"obs_type": "features"})


def test_look_is_an_observation_option_of_the_bench(capsys):
    loaded = evaluate.load("noop", "v0", {"look": "art"})
    assert loaded.options["look"] == "art"
    assert bench(["evaluate", "noop", "--mode", "v0", "--option", "look=banana"]) == 2
    _one_line(capsys, "look")
    assert bench(["evaluate", "noop", "--mode", "v0", "--option", "frame_skip=2"]) == 2
    _one_line(capsys, "frame_skip")


# --- 4. the seed runner never trains on its held-out seeds --------------------------------------------------------


@pytest.mark.parametrize(
    "args", [["--seeds", "1000000"], ["--seeds", "0-1", "--eval-seed", "0"], ["--seeds", "999999", "--num-envs", "4"]]
)
def test_the_seed_runner_refuses_training_seeds_that_overlap_its_held_out_seeds(tmp_path, capsys, monkeypatch, args):
    from chopperscape.learn import seeds

    monkeypatch.setattr(seeds, "run_seeds", lambda *a: pytest.fail("the seeds were trained"))
    out = tmp_path / "seeds"
    with pytest.raises(SystemExit) as done:
        seeds.main([*args, "--out", str(out)])
    assert done.value.code == 2
    err = capsys.readouterr().err
    assert "overlap the held-out evaluation seeds" in err, err
    assert not out.exists()
    seeds.check_held_out([0, 9], 64, 1_000_000, 100)  # the defaults: apart


# --- 5. an --out that is the input or not a regular file ----------------------------------------------------------


def test_evaluate_never_replaces_its_input_a_device_or_a_pipe(tmp_path, capsys):
    pytest.importorskip("onnxruntime")
    model = tmp_path / "P.onnx"
    model.write_bytes((MODELS / "ppo-features.onnx").read_bytes())
    before = model.read_bytes()
    alias = tmp_path / "alias.onnx"
    alias.symlink_to(model)
    for out in (model, alias):
        assert bench(["evaluate", str(model), "--mode", "v0", "--out", str(out)]) == 2
        _one_line(capsys, str(out), "is the input")
    assert model.read_bytes() == before and alias.is_symlink()
    fifo = tmp_path / "fifo"
    os.mkfifo(fifo)
    for out, says in [(Path(os.devnull), "a device"), (fifo, "a pipe"), (tmp_path, "a folder")]:
        assert bench(["evaluate", "noop", "--mode", "v0", "--out", str(out)]) == 2
        _one_line(capsys, str(out), says)
    assert Path(os.devnull).is_char_device() and fifo.is_fifo()
    assert sorted(p.name for p in tmp_path.iterdir()) == ["P.onnx", "alias.onnx", "fifo"]


# --- 6. pictures are written whole or not at all ------------------------------------------------------------------


def test_a_full_disk_leaves_the_old_plots(tmp_path, capsys, monkeypatch):
    pytest.importorskip("matplotlib")
    from matplotlib.figure import Figure

    files = [str(RESULTS / f"v0.random.seed{k}.json") for k in range(3)]
    plots = tmp_path / "plots"
    assert bench(["report", *files, "--plots", str(plots), "--resamples", "100", "--partial"]) == 0
    capsys.readouterr()
    old = (plots / "intervals.png").read_bytes()
    real = Figure.savefig

    def full_disk(self, fname, **kw):
        with open(fname, "wb") as f:
            f.write(b"\x89PNG half")
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(Figure, "savefig", full_disk)
    assert bench(["report", *files, "--plots", str(plots), "--resamples", "100", "--partial"]) == 1
    _one_line(capsys, str(plots / "intervals.png"), "No space left on device")
    assert (plots / "intervals.png").read_bytes() == old
    assert sorted(p.name for p in plots.iterdir()) == ["intervals.png", "profile.png"]
    monkeypatch.setattr(Figure, "savefig", real)


# --- 7, 8, 9. run folders: one writer, a checkpoint bound to its run, no stale temporary files ---------------------


def test_a_run_folder_is_locked_while_a_process_holds_it(tmp_path):
    from chopperscape.learn.rundir import RunLock

    run = tmp_path / "new" / "run"
    with RunLock(run):
        assert run.is_dir()
        with pytest.raises(ValueError) as err:
            RunLock(run).__enter__()
        assert str(run) in str(err.value) and "in use" in str(err.value)
        assert f"process {os.getpid()}" in str(err.value)  # /proc/locks names the holder
    assert not (tmp_path / "new").exists()  # made for the run, empty, removed: a refused run leaves nothing
    run.mkdir(parents=True)
    with RunLock(run):
        pass
    with RunLock(run):  # released at the end of the block
        pass
    assert run.is_dir()


def _train(*args: str) -> int:
    from chopperscape.learn import train

    return train.main([*args])


def _listing(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted(folder.iterdir()) if p.is_file()}


@needs_torch
def test_resume_or_force_in_a_folder_another_process_trains_is_refused(tmp_path, capsys):
    run = tmp_path / "run"
    assert _train("--out", str(run), "--steps", "128", *SMALL) == 0
    capsys.readouterr()
    before = _listing(run)
    holder = subprocess.Popen(
        [
            sys.executable,
            "-c",
            "import sys, time; from chopperscape.learn.rundir import RunLock; lock = RunLock(sys.argv[1]).__enter__();"
            " print('locked', flush=True); time.sleep(120)",
            str(run),
        ],
        stdout=subprocess.PIPE,
        text=True,
    )
    try:
        assert holder.stdout is not None and holder.stdout.readline().strip() == "locked"
        for args in (["--resume", str(run)], ["--out", str(run), "--force", "--steps", "128", *SMALL]):
            assert _train(*args) == 2
            line = _one_line(capsys, str(run), "in use", f"process {holder.pid}")
            assert line.startswith("error: run folder"), line
        assert _listing(run) == before and not (run / "replaced-1").exists()
    finally:
        holder.kill()
        holder.wait()
        if holder.stdout is not None:
            holder.stdout.close()
    assert _train("--resume", str(run)) == 0  # the holder is gone: the lock went with it


@needs_torch
def test_a_checkpoint_resumes_only_the_run_that_saved_it(tmp_path, capsys):
    import shutil

    from chopperscape.learn.recipe import read_recipe
    from chopperscape.learn.rundir import RECIPE_KEY, recipe_hash

    a, b = tmp_path / "a", tmp_path / "b"
    assert _train("--out", str(a), "--steps", "64", "--seed", "1", *SMALL) == 0
    assert _train("--out", str(b), "--steps", "64", "--seed", "2", "--learning-rate", "0.001", *SMALL) == 0
    capsys.readouterr()
    import torch

    state = torch.load(a / "resume.pt", weights_only=True)
    assert state[RECIPE_KEY] == recipe_hash(read_recipe(a / "recipe.json"))
    shutil.copy(b / "resume.pt", a / "resume.pt")
    before = _listing(a)
    assert _train("--resume", str(a)) == 2
    _one_line(capsys, str(a), "belongs to another run")
    assert _listing(a) == before


@needs_torch
def test_a_run_removes_the_temporary_files_a_killed_run_left(tmp_path, capsys):
    run = tmp_path / "run"
    run.mkdir()
    stale = [run / ".model.pt.999999.part", run / ".resume.pt.4242.part"]
    for p in stale:
        p.write_bytes(b"\0" * 4096)
    other = run / ".notes.txt.999999.part"  # not the run's: left alone
    other.write_text("x")
    assert _train("--out", str(run), "--steps", "64", *SMALL) == 0
    assert not any(p.exists() for p in stale) and other.exists()
    (run / ".resume.pt.31337.part").write_bytes(b"\0" * 4096)  # SIGKILL during a checkpoint write
    assert _train("--resume", str(run)) == 0
    assert not (run / ".resume.pt.31337.part").exists()
    capsys.readouterr()


# --- 10 and 12. sizes, depths and files that are not files --------------------------------------------------------


def test_results_files_that_overflow_nest_or_are_not_regular_files_are_refused_by_name(tmp_path, capsys):
    cases = []
    for power in (400, 200):
        doc = _doc()
        doc["episodes"][0]["return"] = 10**power
        path = tmp_path / f"e{power}.json"
        path.write_text(json.dumps(doc))  # the summary cannot follow: the check must refuse first, by name
        cases.append((str(path), "return"))
    bomb = tmp_path / "bomb.json"
    bomb.write_text("[" * 100_000 + "]" * 100_000)
    cases.append((str(bomb), "nested too deeply"))
    zero = tmp_path / "zero.json"
    zero.symlink_to("/dev/zero")
    cases.append((str(zero), "a device"))
    big = tmp_path / "big.json"
    big.write_text(" " * (results.MAX_RESULTS_BYTES + 1))
    cases.append((str(big), "more than the 1,048,576"))
    for path, says in cases:
        assert bench(["report", path, "--resamples", "100"]) == 2
        _one_line(capsys, path, says)
    with pytest.raises(SystemExit) as done:
        bench(["report", str(RESULTS / "v0.heuristic.json"), "--resamples", str(10**12)])
    assert done.value.code == 2
    assert "--resamples 1000000000000: allowed an integer in 100..=1000000" in capsys.readouterr().err


def test_a_results_fifo_is_refused_at_once(tmp_path):
    fifo = tmp_path / "r.json"
    os.mkfifo(fifo)
    cmd = [sys.executable, "-m", "chopperscape.bench", "report", str(fifo)]
    done = subprocess.run(cmd, capture_output=True, text=True, timeout=120)
    assert done.returncode == 2, done.stderr
    assert str(fifo) in done.stderr and "a pipe or a socket" in done.stderr
    assert len(done.stderr.strip().splitlines()) == 1


@needs_sb3
def test_a_normalisation_file_nested_too_deeply_is_refused_by_name(tmp_path):
    from chopperscape.integrations import sb3_files

    (tmp_path / "vecnormalize.json").write_text("{" + '"a":{' * 50_000 + "}" * 50_001)
    with pytest.raises(ValueError, match=r"vecnormalize\.json is not a usable normalisation file: it is nested"):
        sb3_files.load_normalization(tmp_path)


@needs_sb3
def test_sb3_archives_are_checked_before_they_are_inflated(tmp_path, capsys):
    from stable_baselines3 import PPO

    from chopperscape.integrations.sb3 import ChopperScapeVecEnv

    venv = ChopperScapeVecEnv(2, seed=0, obs_type="features")
    PPO("MlpPolicy", venv, n_steps=16, batch_size=32, n_epochs=1, seed=0, device="cpu").save(tmp_path / "ok.zip")
    members = {}
    with zipfile.ZipFile(tmp_path / "ok.zip") as z:
        for name in z.namelist():
            members[name] = z.read(name)

    def rezip(name: str, **replace: bytes) -> str:
        with zipfile.ZipFile(tmp_path / name, "w", zipfile.ZIP_DEFLATED) as z:
            for member, data in {**members, **replace}.items():
                z.writestr(member, data)
        return str(tmp_path / name)

    # `data` inflating past its limit: refused from the archive's directory.
    bomb = rezip("bomb.zip", data=b" " * (20 << 20))
    assert os.path.getsize(bomb) < 1 << 20
    args = ["--mode", "v0", "--option", "obs_type=features"]
    assert bench(["evaluate", bomb, *args]) == 2
    _one_line(capsys, bomb, "inflate to")

    # Weights that pickle os.system: nothing runs, and the refusal is one line.
    class Evil:
        def __reduce__(self):
            return (os.system, ("echo pwned > " + str(tmp_path / "pwned"),))

    import torch

    buf = io.BytesIO()
    torch.save({"evil": Evil()}, buf)
    evil = rezip("evil.zip", **{"policy.pth": buf.getvalue()})
    assert bench(["evaluate", evil, *args]) == 2
    _one_line(capsys, evil)
    assert not (tmp_path / "pwned").exists()


# --- 11. policies that are not what they say ----------------------------------------------------------------------


def test_callables_that_do_not_import_or_return_no_actions_are_refused_in_one_line(tmp_path, capsys, monkeypatch):
    (tmp_path / "hostile_policies.py").write_text(
        "def none(obs):\n    return None\n\n"
        "def mapping(obs):\n    return {'a': 1}\n\n"
        "def short(obs):\n    return [0]\n\n"
        "def boom(obs):\n    raise ZeroDivisionError('no')\n"
    )
    monkeypatch.syspath_prepend(str(tmp_path))
    for spec, says in [
        ("builtins:len", "returned int"),
        ("..:x", "cannot import it"),
        (":x", "cannot import it"),
        ("hostile_policies:none", "returned NoneType"),
        ("hostile_policies:mapping", "returned dict"),
        ("hostile_policies:short", "one action per observation"),
        ("hostile_policies:boom", "ZeroDivisionError"),
    ]:
        assert bench(["evaluate", spec, "--mode", "v0"]) == 2, spec
        _one_line(capsys, repr(spec), says)


def _onnx_with(tmp_path: Path, name: str, *, meta: dict | None = None, graph=None) -> str:
    onnx = pytest.importorskip("onnx")
    model = onnx.load(str(MODELS / "ppo-features.onnx"))
    props = {p.key: p.value for p in model.metadata_props}
    if graph is not None:
        model = graph
    props.update(meta or {})
    del model.metadata_props[:]
    for key, value in props.items():
        model.metadata_props.add(key=key, value=value)
    onnx.save(model, str(tmp_path / name))
    return str(tmp_path / name)


def test_onnx_files_with_bad_metadata_no_input_or_the_wrong_width_are_refused(tmp_path, capsys):
    onnx = pytest.importorskip("onnx")
    pytest.importorskip("onnxruntime")
    from onnx import TensorProto, helper

    def tiny(width: int | None) -> object:
        starts, ends, axes = (
            helper.make_tensor(n, TensorProto.INT64, [1], [v]) for n, v in (("s", 0), ("e", 5), ("a", 1))
        )
        if width is None:  # no input at all: constant logits
            logits = helper.make_tensor("c", TensorProto.FLOAT, [1, 5], [0.0] * 5)
            nodes = [helper.make_node("Constant", [], ["logits"], value=logits)]
            inputs = []
        else:
            nodes = [helper.make_node("Slice", ["obs", "s", "e", "a"], ["logits"])]
            inputs = [helper.make_tensor_value_info("obs", TensorProto.FLOAT, ["batch", width])]
        out = helper.make_tensor_value_info("logits", TensorProto.FLOAT, ["batch", 5])
        graph = helper.make_graph(
            nodes, "tiny", inputs, [out], initializer=[] if width is None else [starts, ends, axes]
        )
        return helper.make_model(graph, opset_imports=[helper.make_opsetid("", 17)], ir_version=8)

    cases = [
        (_onnx_with(tmp_path, "list.onnx", meta={"env_options": "[1, 2]"}), "env_options metadata must be a JSON"),
        (_onnx_with(tmp_path, "str.onnx", meta={"env_options": '"frame_skip"'}), "env_options metadata must be"),
        (_onnx_with(tmp_path, "none.onnx", graph=tiny(None)), "has 0 inputs"),
        (_onnx_with(tmp_path, "narrow.onnx", graph=tiny(40)), "takes observations of shape (40,)"),
    ]
    assert onnx is not None
    for path, says in cases:
        assert bench(["evaluate", path, "--mode", "v0"]) == 2, path
        _one_line(capsys, path, says)
    # The features policy on frames: its input does not take them.
    good = str(MODELS / "ppo-features.onnx")
    assert bench(["evaluate", good, "--mode", "v0", "--option", "obs_type=grayscale"]) == 2
    _one_line(capsys, good, "takes observations of shape (46,)")


def _as_from_a_shell() -> None:
    """A child's SIGINT as a shell starts it: handled by default and not blocked. A child inherits an ignored or
    blocked SIGINT from its parent; in the whole suite's pytest process something earlier leaves it so (the test
    passed alone and lost its signal in the suite), which is pytest's state, not what a user's Ctrl-C meets."""
    signal.signal(signal.SIGINT, signal.SIG_DFL)
    signal.pthread_sigmask(signal.SIG_UNBLOCK, [signal.SIGINT])


def test_ctrl_c_during_evaluate_is_one_line_and_status_130(tmp_path):
    marker = tmp_path / "started"
    (tmp_path / "slow_policy.py").write_text(
        "import pathlib, time\nimport numpy as np\n\n"
        "def act(obs):\n"
        f"    pathlib.Path({str(marker)!r}).touch()\n"
        "    time.sleep(1.0)\n"  # long enough that a busy machine cannot finish the episodes before the signal
        "    return np.zeros(len(obs), dtype=np.int64)\n"
    )
    env = {**os.environ, "PYTHONPATH": os.pathsep.join([str(tmp_path), os.environ.get("PYTHONPATH", "")])}
    proc = subprocess.Popen(
        [sys.executable, "-m", "chopperscape.bench", "evaluate", "slow_policy:act", "--mode", "v0"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        env=env,
        preexec_fn=_as_from_a_shell,
    )
    deadline = time.monotonic() + 120
    while not marker.exists():
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.05)
    proc.send_signal(signal.SIGINT)
    out, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, (err, out[-300:])
    assert err.strip() == "interrupted" and out == "", err


# --- 11 and 13. labels: escaped in the table, drawn literally in the plots ----------------------------------------


def _named(tmp_path: Path, name: str, label: str, *, source: str | None = None) -> list[str]:
    paths = []
    for k in range(2):
        doc = _doc(f"v0.random.seed{k}.json")
        if source is None:
            doc["policy"]["name"] = label
        else:
            doc["policy"].pop("name", None)
            doc["policy"]["source"] = label
        paths.append(_write(tmp_path / f"{name}{k}.json", doc))
    return paths


def test_labels_cannot_forge_rows_or_reach_the_page_as_html(tmp_path, capsys):
    forged = "x | 9 (9) | 9 | 1.0 | 1.0 | 1.0 | 0.0 |\n| forged"
    files = _named(tmp_path, "s", forged, source="yes") + _named(tmp_path, "n", "<img src=x onerror=alert(1)>")
    assert bench(["report", *files, "--resamples", "100", "--partial"]) == 0
    table = capsys.readouterr().out.splitlines()
    assert len(table) == 4  # the header, its rule, two rows
    assert all(line.replace("\\|", "").count("|") == 8 for line in table), table
    assert not any("<img" in line for line in table)
    assert any("&lt;img src=x onerror=alert(1)&gt;" in line for line in table)
    assert report.cell("a\\|b") == "a\\\\\\|b"  # a backslash cannot unescape the bar


def test_plots_draw_every_label_literally_and_in_the_legend(tmp_path, capsys):
    pytest.importorskip("matplotlib")
    files = _named(tmp_path, "m", r"PPO $\b$ run") + _named(tmp_path, "u", "_hidden")
    plots = tmp_path / "plots"
    args = ["report", *files, "--plots", str(plots), "--format", "svg", "--resamples", "100", "--partial"]
    assert bench(args) == 0, capsys.readouterr().err
    assert "PPO $\\\\b$ run @ v0" in capsys.readouterr().out  # the table escapes the backslash
    profile = (plots / "profile.svg").read_text()
    assert "_hidden @ v0" in profile and "PPO $\\b$ run @ v0" in profile.replace("\\$", "$")


# --- 15. bench row: seeds are numbers and ranges; a failed seed leaves no claim ----------------------------------


def _row(*args: str) -> subprocess.CompletedProcess[str]:
    return subprocess.run(
        [sys.executable, "-m", "chopperscape.bench", "row", *args], capture_output=True, text=True, timeout=300
    )


def test_bench_row_reads_seeds_as_numbers_and_ranges_never_as_file_patterns(tmp_path):
    common = ("fast", "--mode", "sticky-v0", "--runs", str(tmp_path / "runs"), "--results", str(tmp_path))
    for bad in ("*", "Cargo.*", "1;2", "-3", "5-3", "0-100000000"):
        done = _row(*common, "--seeds", bad, "--dry-run")
        assert (done.returncode, done.stdout) == (2, ""), (bad, done)
        assert len(done.stderr.strip().splitlines()) == 1 and "--seeds" in done.stderr, done.stderr
    done = _row(*common, "--seeds", "2-4,3,0", "--dry-run")
    assert done.returncode == 0, done.stderr
    seeds = [line.split("--seed ")[1].split()[0] for line in done.stdout.splitlines() if "--seed " in line]
    assert seeds == ["0", "2", "3", "4"]
    assert not (tmp_path / "runs").exists()  # a dry run makes nothing


def test_bench_row_leaves_no_claim_when_a_seed_fails(tmp_path):
    runs = tmp_path / "runs"
    args = ("fast", "--mode", "sticky-v0", "--runs", str(runs), "--results", str(tmp_path), "--seeds", "1")
    done = _row(*args, "--python", "false")
    assert done.returncode != 0 and "failed" in done.stderr, done
    # The seed's claim went with the process: the next run takes the seed again instead of skipping it.
    again = _row(*args, "--python", "false")
    assert "being trained by another process" not in again.stdout and again.returncode != 0, again
