"""Datasets under hostile input and faults: signals to the module and to `chopperscape dataset`, stale temporary
folders, full disks, bad ids and places, bad action logs (read by the command line's own reader), and the
command line's options parsed per type. Each is a clear error or a clean stop; nothing is left behind."""

from __future__ import annotations

import json
import os
import pathlib
import signal
import subprocess
import sys
import time

import pytest

pytest.importorskip("minari", reason="minari is not installed (pip install 'minari[hdf5]' pillow)")
pytest.importorskip("h5py", reason="h5py is not installed (pip install 'minari[hdf5]')")
import minari
from test_policies import cli

from chopperscape import _cli, policies
from chopperscape.integrations import datasets
from chopperscape.integrations.datasets import cli as datasets_cli

#: A collection that takes minutes: stopped by the tests long before it ends.
LONG = [
    "--policy",
    "heuristic",
    "--episodes",
    "100000",
    "--option",
    "obs_type=grayscale",
    "--option",
    "obs_size=84x84",
    "--no-progress",
]


@pytest.fixture(autouse=True)
def datasets_path(tmp_path, monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "minari"))
    return tmp_path / "minari"


def hidden(folder: pathlib.Path) -> list[str]:
    return sorted(p.name for p in folder.glob(".*")) if folder.exists() else []


def wait_for_temp(folder: pathlib.Path, proc: subprocess.Popen, timeout: float = 120.0) -> pathlib.Path:
    """The temporary folder of a collection once its data file exists (the collection is under way)."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        for p in folder.glob(".*.part"):
            if (p / "data" / "main_data.hdf5").exists():
                time.sleep(0.3)
                return p
        if proc.poll() is not None:
            raise AssertionError(f"the collection ended early: {proc.returncode}\n{proc.stderr.read()}")
        time.sleep(0.05)
    proc.kill()
    raise AssertionError("no collection under way")


def module(*args: str, **kw) -> subprocess.Popen:
    return subprocess.Popen(
        [sys.executable, "-m", "chopperscape.integrations.datasets", *args],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
        **kw,
    )


# --- signals and leftovers ----------------------------------------------------------------------------------


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGTERM, signal.SIGHUP], ids=["INT", "TERM", "HUP"])
def test_a_signal_stops_the_collection_and_removes_its_folder(sig, datasets_path):
    proc = module("--out", "cs/sig-v0", *LONG)
    wait_for_temp(datasets_path / "cs", proc)
    proc.send_signal(sig)
    _out, err = proc.communicate(timeout=60)
    assert proc.returncode == 128 + sig, err
    assert "removed the unfinished dataset 'cs/sig-v0'" in err and "Traceback" not in err, err
    assert hidden(datasets_path / "cs") == [] and not (datasets_path / "cs" / "sig-v0").exists()


def test_ctrl_c_is_never_swallowed(datasets_path):
    # h5py opens and closes its file at every flushed chunk: a Ctrl-C raised inside its finalizers was once
    # printed as "Exception ignored" and the collection went on.
    for delay in (0.0, 0.13, 0.29, 0.41, 0.57):
        proc = module("--out", "cs/ctrl-c-v0", *LONG, "--chunk-steps", "1")
        wait_for_temp(datasets_path / "cs", proc)
        time.sleep(delay)
        proc.send_signal(signal.SIGINT)
        try:
            _, err = proc.communicate(timeout=60)
        except subprocess.TimeoutExpired:
            proc.kill()
            raise AssertionError(f"a Ctrl-C after {delay} s was swallowed: the collection went on") from None
        assert proc.returncode == 130 and "Exception ignored" not in err, err
        assert hidden(datasets_path / "cs") == []


def children(pid: int) -> list[int]:
    """The processes whose parent is `pid` (from /proc)."""
    kids = []
    for stat in pathlib.Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[1]) == pid:
            kids.append(int(stat.parent.name))
    return kids


def gone(pid: int, timeout: float = 60.0) -> bool:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        try:
            os.kill(pid, 0)
        except ProcessLookupError:
            return True
        try:
            if pathlib.Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0] == "Z":
                return True
        except OSError:
            return True
        time.sleep(0.05)
    return False


@pytest.mark.parametrize(
    "sig", [signal.SIGTERM, signal.SIGHUP, signal.SIGINT, signal.SIGKILL], ids=["TERM", "HUP", "INT", "KILL"]
)
def test_the_cli_dataset_command_stops_its_python_child(sig, datasets_path):
    exe = cli()
    if exe is None or not pathlib.Path("/proc/self/task").exists():
        pytest.skip("cargo (or /proc) is not available")
    env = {**os.environ, "CHOPPERSCAPE_PYTHON": sys.executable}
    proc = subprocess.Popen(
        [
            str(exe),
            "dataset",
            "--out",
            "cs/cli-sig-v0",
            "--episodes",
            "100000",
            "--obs-type",
            "grayscale",
            "--obs-size",
            "84x84",
        ],
        env=env,
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
        text=True,
    )
    wait_for_temp(datasets_path / "cs", proc)
    kids = children(proc.pid)
    assert kids, "the command runs the Python package as a child"
    proc.send_signal(sig)
    _, err = proc.communicate(timeout=90)
    assert proc.returncode == (-signal.SIGKILL if sig == signal.SIGKILL else 128 + sig), err
    assert all(gone(k) for k in kids), "the Python child went on after the command stopped"
    assert hidden(datasets_path / "cs") == [], "the child's unfinished dataset was left"


def test_folders_left_by_killed_runs_are_removed_by_the_next_and_nothing_else(datasets_path, capsys):
    cs = datasets_path / "cs"
    dead = subprocess.run([sys.executable, "-c", "import os; print(os.getpid())"], capture_output=True, text=True)
    dead_pid = int(dead.stdout)
    stale = cs / f".old-v0.{dead_pid}.abcd_123.part"
    (stale / "data").mkdir(parents=True)
    (stale / "data" / "main_data.hdf5").write_bytes(b"\0" * 1000)
    live = cs / f".other-v0.{os.getppid()}.abcd_123.part"  # a process that runs: never touched
    live.mkdir()
    mine = cs / ".notes.txt"  # not our pattern: never touched
    mine.write_text("keep")
    datasets.collect("cs/next-v0", "noop", 1, 0, max_fuel=20)
    assert hidden(cs) == sorted([live.name, mine.name])
    assert f"removed {stale}" in capsys.readouterr().err


@pytest.fixture
def played(monkeypatch):
    """The steps the policies play (none, when a collection is refused before it starts)."""
    steps = []
    act = policies.Policy.act
    monkeypatch.setattr(policies.Policy, "act", lambda self, env: steps.append(1) or act(self, env))
    return steps


def test_a_second_writer_of_one_id_is_refused_before_it_collects(datasets_path, played):
    cs = datasets_path / "cs"
    busy = cs / f".busy-v0.{os.getppid()}.abcd_123.part"  # as if a running process were writing cs/busy-v0
    (busy / "data").mkdir(parents=True)
    with pytest.raises(ValueError, match=r"another process \(pid \d+\) is writing a dataset 'busy-v0'"):
        datasets.collect("cs/busy-v0", "heuristic", 20, max_episode_steps=100)
    assert played == [], "refused only after collecting"
    assert hidden(cs) == [busy.name] and not (cs / "busy-v0").exists()


FULL = """
import resource, sys
resource.setrlimit(resource.RLIMIT_FSIZE, (20 << 20, 20 << 20))
from chopperscape.integrations.datasets import cli
sys.exit(cli.main(sys.argv[1:]))
"""


def test_a_full_disk_is_a_one_line_error_naming_the_file_and_removes_the_dataset(datasets_path):
    done = subprocess.run(
        [
            sys.executable,
            "-c",
            FULL,
            "--out",
            "cs/full-v0",
            "--policy",
            "noop",
            "--episodes",
            "50",
            "--option",
            "obs_type=grayscale",
            "--option",
            "obs_size=84x84",
            "--no-progress",
            "--chunk-steps",
            "100",
        ],
        capture_output=True,
        text=True,
        timeout=300,
    )
    assert done.returncode == 1, (done.returncode, done.stderr)
    lines = done.stderr.strip().splitlines()
    assert len(lines) == 1 and "cannot write the dataset 'cs/full-v0'" in lines[0] and ".hdf5" in lines[0], lines
    assert hidden(datasets_path / "cs") == [] and not (datasets_path / "cs" / "full-v0").exists()


# --- ids and places -----------------------------------------------------------------------------------------


def test_ids_and_places_are_checked_before_anything_is_played(datasets_path, tmp_path, monkeypatch, played):
    for bad, message in [
        ("cs/no-version", "Malformed dataset ID"),
        ("no version", "Malformed dataset ID"),
        ("cs/" + "x" * 300 + "-v0", "too long"),
        (42, "Malformed dataset ID"),
    ]:
        with pytest.raises(ValueError, match=message):
            datasets.collect(bad, "noop", 1)
    (datasets_path / "cs").mkdir(parents=True)
    (datasets_path / "cs" / "link-v0").symlink_to(tmp_path / "nowhere")
    with pytest.raises(ValueError, match="symbolic link"):
        datasets.collect("cs/link-v0", "heuristic", 20, max_episode_steps=100)
    assert played == [], "refused only after collecting"
    (tmp_path / "a-file").write_text("")
    for value, message in [
        ("", "set but empty"),
        (str(tmp_path / "a-file"), "not a folder"),
        (str(tmp_path / "a-file" / "below"), "cannot be made"),
    ]:
        monkeypatch.setenv("MINARI_DATASETS_PATH", value)
        with pytest.raises(ValueError, match=message):
            datasets.collect("cs/place-v0", "noop", 1)
    if os.geteuid() != 0:  # root writes anywhere
        locked = tmp_path / "locked"
        locked.mkdir(mode=0o500)
        monkeypatch.setenv("MINARI_DATASETS_PATH", str(locked))
        with pytest.raises(ValueError, match="not writable"):
            datasets.collect("cs/place-v0", "noop", 1)


# --- defaults and the command line --------------------------------------------------------------------------


def test_the_module_defaults_to_features_as_the_command_line(datasets_path):
    assert datasets_cli.main(["--out", "cs/default-v0", "--no-progress", "--option", "max_episode_steps=20"]) == 0
    ds = minari.load_dataset("cs/default-v0")
    assert ds.observation_space.shape == (46,) and ds.total_steps == 20


@pytest.mark.parametrize("flags", [["--policy", "random"], ["--episodes", "3"], ["--seed", "4"]])
def test_policy_flags_with_from_logs_are_refused(tmp_path, flags, capsys):
    log = tmp_path / "a.json"
    log.write_text("{}")
    with pytest.raises(SystemExit) as e:
        datasets_cli.main(["--out", "cs/logs-v0", "--from-logs", str(log), *flags])
    assert e.value.code == 2 and "cannot be given with --from-logs" in capsys.readouterr().err


def test_hud_false_and_other_typed_options_from_the_command_line(datasets_path):
    args = [
        "--out",
        "cs/hud-v0",
        "--episodes",
        "1",
        "--no-progress",
        "--option",
        "obs_type=grayscale",
        "--option",
        "obs_size=24x32",
        "--option",
        "hud=false",
        "--option",
        "max_episode_steps=5",
        "--option",
        "lives=2",
    ]
    assert datasets_cli.main(args) == 0
    kwargs = minari.load_dataset("cs/hud-v0").spec.env_spec.kwargs
    assert kwargs["hud"] is False and tuple(kwargs["obs_size"]) == (24, 32) and kwargs["lives"] == 2
    exe = cli()
    if exe is not None:
        env = {**os.environ, "CHOPPERSCAPE_PYTHON": sys.executable}
        done = subprocess.run(
            [
                str(exe),
                "dataset",
                "--out",
                "cs/no-hud-v0",
                "--no-hud",
                "--obs-type",
                "rgb",
                "--obs-size",
                "16x16",
                "--max-episode-steps",
                "3",
            ],
            env=env,
            capture_output=True,
            text=True,
        )
        assert done.returncode == 0, done.stderr
        assert minari.load_dataset("cs/no-hud-v0").spec.env_spec.kwargs["hud"] is False


@pytest.mark.parametrize(
    "name,text,value",
    [
        ("hud", "false", False),
        ("hud", "true", True),
        ("obs_size", "84x84", (84, 84)),
        ("obs_size", "[84, 84]", (84, 84)),
        ("lives", "3", 3),
        ("alien_prob", "0.25", 0.25),
        ("obs_type", "features", "features"),
        ("obs_type", '"features"', "features"),
        ("max_episode_steps", "none", None),
        ("max_episode_steps", "7", 7),
        ("keep_dim", "true", True),
        ("bird_fuel_collision", "destroy", "destroy"),
    ],
)
def test_command_line_values_are_parsed_per_option_type(name, text, value):
    assert _cli.option_value(name, text) == value and type(_cli.option_value(name, text)) is type(value)


@pytest.mark.parametrize(
    "name,text",
    [
        ("hud", "False"),
        ("hud", "0"),
        ("lives", "0"),
        ("lives", "1.5"),
        ("obs_size", "84"),
        ("alien_prob", "nan"),
        ("nope", "1"),
        ("keep_dim", "1"),
    ],
)
def test_command_line_values_out_of_range_name_the_option(name, text):
    with pytest.raises(ValueError, match=name):
        _cli.option_value(name, text)


def test_a_closed_standard_output_ends_quietly(datasets_path):
    with module("--out", "cs/closed-v0", "--no-progress", "--option", "max_episode_steps=5") as proc:
        proc.stdout.close()
        err = proc.stderr.read()
    assert proc.returncode == 141 and "Traceback" not in err, err
    assert minari.load_dataset("cs/closed-v0").total_steps == 5


# --- no time limit ------------------------------------------------------------------------------------------

#: An episode of 12,000 steps: no birds, fuel for 12,000 steps, Do Nothing.
ENDLESS = {"bird_prob": 0.0, "fuel_prob": 0.0, "max_fuel": 12_000}


def test_max_episode_steps_none_is_no_time_limit_everywhere(tmp_path, datasets_path):
    ep = next(policies.episodes("noop", 1, 0, max_episode_steps=None, **ENDLESS))
    assert (ep["steps"], ep["cause"]) == (12_000, "fuel")
    ds = datasets.collect("cs/endless-v0", "noop", 1, 0, max_episode_steps=None, **ENDLESS)
    assert ds.total_steps == 12_000 and ds.storage.metadata["max_episode_steps"] is None
    assert minari.load_dataset("cs/endless-v0").spec.env_spec.max_episode_steps is None
    assert (
        datasets_cli.main(
            [
                "--out",
                "cs/endless-cli-v0",
                "--policy",
                "noop",
                "--no-progress",
                "--option",
                "max_episode_steps=none",
                *[f"--option={k}={v}" for k, v in ENDLESS.items()],
            ]
        )
        == 0
    )
    assert minari.load_dataset("cs/endless-cli-v0").total_steps == 12_000
    # A log with no time limit, as `chopperscape play --max-episode-steps none` writes it, replays into a dataset.
    rules = {"max_episode_steps": "none", "bird_prob": "0", "fuel_prob": "0", "max_fuel": "12000"}
    doc = {
        "format": "chopperscape-actions",
        "version": 1,
        "env": "ChopperScape-v0",
        "seed": 0,
        "options": rules,
        "policy": "human",
        "steps": 12_000,
        "return": 12_000,
        "cause": "fuel",
        "actions": "4" * 12_000,
    }
    (tmp_path / "endless.json").write_text(json.dumps(doc))
    ds = datasets.from_action_logs("cs/endless-log-v0", [tmp_path / "endless.json"])
    assert ds.total_steps == 12_000 and ds.spec.env_spec.max_episode_steps is None


# --- action logs --------------------------------------------------------------------------------------------

GOOD = {
    "format": "chopperscape-actions",
    "version": 1,
    "env": "ChopperScape-v0",
    "seed": 3,
    "options": {},
    "policy": "human",
    "steps": 3,
    "return": 3,
    "cause": None,
    "actions": "443",
}


def log_text(**changes) -> str:
    doc = {**GOOD, **changes}
    return json.dumps({k: v for k, v in doc.items() if v is not KeyError})


CRAFTED = {
    "missing seed": log_text(seed=KeyError),
    "seed 1e999": log_text().replace('"seed": 3', '"seed": 1e999'),
    "seed 2**70": log_text(seed=2**70),
    "seed 1.7": log_text(seed=1.7),
    "seed true": log_text(seed=True),
    "options not an object": log_text(options=[1, 2]),
    "a list as an option value": log_text(options={"lives": [2]}),
    "deeply nested": log_text(options={"lives": "1"}).replace(
        '"options": {"lives": "1"}', '"options": ' + "[" * 10_000 + "]" * 10_000
    ),
    "steps off": log_text(steps=4),
}


@pytest.mark.parametrize("case", sorted(CRAFTED))
def test_bad_action_logs_are_refused_by_the_replay_reader_with_a_message(case, tmp_path):
    path = tmp_path / "log.json"
    path.write_text(CRAFTED[case])
    with pytest.raises(ValueError, match=r"log\.json"):
        datasets.read_action_log(path)
    with pytest.raises(ValueError, match=r"log\.json"):
        datasets.from_action_logs("cs/crafted-v0", [path])
    exe = cli()
    if exe is not None:  # `chopperscape replay` refuses the same file
        assert subprocess.run([str(exe), "replay", str(path)], capture_output=True).returncode == 1


def test_a_byte_order_mark_is_read_as_replay_reads_it_and_size_is_capped(tmp_path):
    path = tmp_path / "bom.json"
    path.write_bytes(b"\xef\xbb\xbf" + log_text().encode())
    log = datasets.read_action_log(path)
    assert log["seed"] == 3 and list(log["actions"]) == [4, 4, 3]
    started = time.monotonic()
    with pytest.raises(ValueError, match="larger than 64 MiB"):
        datasets.read_action_log("/dev/zero")
    assert time.monotonic() - started < 30
    exe = cli()
    if exe is not None:
        assert subprocess.run([str(exe), "replay", str(path)], capture_output=True).returncode == 0
