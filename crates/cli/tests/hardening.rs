//! The command line under faults and hostile input: two outputs on one file, signals during a recording,
//! stale temporary files, a closed or full standard output, endless episodes, oversized or odd action logs,
//! unmeasurable durations, negative numbers, a failing ffmpeg, a full disk.

use std::io::{BufRead, BufReader, Read};
use std::path::Path;
use std::process::{Command as StdCommand, Stdio};
use std::time::{Duration, Instant};

use predicates::prelude::*;

mod common;
use common::{bin, cs};

fn names(dir: &Path) -> Vec<String> {
    let mut v: Vec<String> =
        std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    v.sort();
    v
}

/// The options of an episode that never ends by itself.
const ENDLESS: &[&str] = &["--policy", "noop", "--bird-prob", "0", "--fuel-prob", "1"];

/// A process id that no process has now (a child that has been waited for).
fn dead_pid() -> u32 {
    let mut child = StdCommand::new("true").spawn().unwrap();
    let pid = child.id();
    child.wait().unwrap();
    pid
}

#[test]
fn two_outputs_on_one_file_are_refused_before_anything_is_played() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    cs().current_dir(d)
        .args(["record", "--policy", "noop", "--out", "same.png", "--save-actions", "same.png", "--force"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--out same.png and --save-actions same.png are the same file"));
    cs().current_dir(d)
        .args(["record", "--policy", "noop", "--out", "fr.gif", "--frames", "fr.gif"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("--out").and(predicate::str::contains("--frames")));
    #[cfg(unix)]
    {
        std::fs::create_dir(d.join("real")).unwrap();
        std::os::unix::fs::symlink(d.join("real"), d.join("alias")).unwrap();
        cs().current_dir(d)
            .args(["record", "--policy", "noop", "--out", "real/a.gif", "--frames", "alias/a.gif"])
            .assert()
            .code(2);
        cs().current_dir(d)
            .args(["record", "--policy", "noop", "--frames", "real", "--out", "alias/run.gif"])
            .assert()
            .code(2)
            .stderr(predicate::str::contains("inside the --frames folder"));
    }
    assert!(names(d).iter().all(|n| n == "real" || n == "alias"), "{:?}", names(d));
}

#[cfg(unix)]
#[test]
fn replay_never_writes_over_the_log_it_reads() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("ep.json");
    cs().args(["record", "--policy", "noop", "--max-episode-steps", "5", "--save-actions"])
        .arg(&log)
        .assert()
        .success();
    let before = std::fs::read(&log).unwrap();
    std::os::unix::fs::symlink(&log, dir.path().join("ep.gif")).unwrap();
    cs().arg("replay")
        .arg(&log)
        .arg("--out")
        .arg(dir.path().join("ep.gif"))
        .arg("--force")
        .assert()
        .code(2)
        .stderr(predicate::str::contains("the action log").and(predicate::str::contains("--out")));
    assert_eq!(std::fs::read(&log).unwrap(), before);
}

#[cfg(unix)]
#[test]
fn a_dangling_symbolic_link_as_out_is_refused_before_recording() {
    let dir = tempfile::tempdir().unwrap();
    let link = dir.path().join("run.gif");
    std::os::unix::fs::symlink(dir.path().join("gone/run.gif"), &link).unwrap();
    let start = Instant::now();
    cs().args(["record", "--max-episode-steps", "3000"])
        .args(ENDLESS)
        .arg("--out")
        .arg(&link)
        .assert()
        .failure()
        .stderr(predicate::str::contains("symbolic link").and(predicate::str::contains("does not exist")));
    assert!(start.elapsed() < Duration::from_secs(20), "refused only after {:?}", start.elapsed());
    assert_eq!(names(dir.path()), ["run.gif"]);
}

/// Starts a long recording in `dir`, waits until its temporary outputs exist, sends `signal`, and returns the
/// exit code.
#[cfg(unix)]
fn interrupt_recording(dir: &Path, signal: libc::c_int, out: &str) -> Option<i32> {
    let mut child = StdCommand::new(bin())
        .current_dir(dir)
        .args([
            "record",
            "--max-episode-steps",
            "20000",
            "--frames",
            "frames",
            "--save-actions",
            "a.json",
            "--out",
            out,
        ])
        .args(ENDLESS)
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let deadline = Instant::now() + Duration::from_secs(60);
    while names(dir).iter().filter(|n| n.ends_with(".part")).count() < 2 && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    std::thread::sleep(Duration::from_millis(300));
    assert!(names(dir).iter().any(|n| n.ends_with(".part")), "the recording never started: {:?}", names(dir));
    let pid = libc::pid_t::try_from(child.id()).unwrap();
    // SAFETY: kill takes plain integers; the pid is our own child, not yet waited for.
    assert_eq!(unsafe { libc::kill(pid, signal) }, 0);
    let deadline = Instant::now() + Duration::from_secs(30);
    while child.try_wait().unwrap().is_none() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let status = child.wait().unwrap();
    let mut err = String::new();
    child.stderr.take().unwrap().read_to_string(&mut err).unwrap();
    assert!(!err.contains("panicked"), "{err}");
    status.code()
}

#[cfg(unix)]
#[test]
fn a_signal_during_a_recording_removes_its_unfinished_files() {
    for (signal, code) in [(libc::SIGTERM, 143), (libc::SIGINT, 130), (libc::SIGHUP, 129)] {
        let dir = tempfile::tempdir().unwrap();
        assert_eq!(interrupt_recording(dir.path(), signal, "run.gif"), Some(code), "signal {signal}");
        assert_eq!(names(dir.path()), Vec::<String>::new(), "signal {signal} left files behind");
    }
}

#[cfg(unix)]
#[test]
fn a_signal_during_an_mp4_recording_stops_ffmpeg_and_removes_its_file() {
    if !StdCommand::new("ffmpeg").arg("-version").output().is_ok_and(|o| o.status.success()) {
        eprintln!("ffmpeg is not installed: skipped");
        return;
    }
    let dir = tempfile::tempdir().unwrap();
    assert_eq!(interrupt_recording(dir.path(), libc::SIGTERM, "run.mp4"), Some(143));
    std::thread::sleep(Duration::from_millis(500));
    assert_eq!(names(dir.path()), Vec::<String>::new());
}

#[test]
fn stale_temporary_files_of_a_killed_run_are_removed_and_nothing_else() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let dead = dead_pid();
    let live = std::process::id();
    std::fs::write(d.join(format!(".run.gif.{dead}.Ab3xYz.part")), "half").unwrap();
    std::fs::create_dir(d.join(format!(".frames.{dead}.Qw7rTy.part"))).unwrap();
    std::fs::write(d.join(format!(".frames.{dead}.Qw7rTy.part/frame_00000.png")), "half").unwrap();
    std::fs::write(d.join(format!(".run.gif.{live}.Ab3xYz.part")), "still being written").unwrap();
    std::fs::write(d.join(".notes.part"), "not ours").unwrap();
    cs().current_dir(d)
        .args(["record", "--policy", "noop", "--max-episode-steps", "3", "--save-actions", "a.json"])
        .assert()
        .success()
        .stderr(predicate::str::contains("left by an interrupted run"));
    assert_eq!(names(d), [".notes.part".to_string(), format!(".run.gif.{live}.Ab3xYz.part"), "a.json".to_string()]);
}

#[test]
fn a_frames_swap_cut_in_half_is_put_back_by_the_next_run() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let dead = dead_pid();
    // What a run killed between the two renames of `--frames frames --force` leaves: the old folder aside,
    // the new one unfinished, `frames` itself missing.
    let aside = d.join(format!(".frames.{dead}.Qw7rTy.old"));
    std::fs::create_dir(&aside).unwrap();
    std::fs::write(aside.join("frame_00000.png"), "old frame").unwrap();
    std::fs::create_dir(d.join(format!(".frames.{dead}.Qw7rTy.part"))).unwrap();
    cs().current_dir(d)
        .args(["record", "--policy", "noop", "--max-episode-steps", "3", "--save-actions", "a.json"])
        .assert()
        .success()
        .stderr(predicate::str::contains("put back"));
    assert_eq!(names(d), ["a.json", "frames"]);
    assert_eq!(std::fs::read_to_string(d.join("frames/frame_00000.png")).unwrap(), "old frame");
    // And a swap that completed its renames but not the removal: the new folder stays, the old one goes.
    std::fs::create_dir(&aside).unwrap();
    std::fs::write(aside.join("frame_00000.png"), "older frame").unwrap();
    cs().current_dir(d)
        .args(["record", "--policy", "noop", "--max-episode-steps", "3", "--save-actions", "b.json"])
        .assert()
        .success();
    assert_eq!(names(d), ["a.json", "b.json", "frames"]);
    assert_eq!(std::fs::read_to_string(d.join("frames/frame_00000.png")).unwrap(), "old frame");
}

#[test]
fn demo_json_prints_each_episode_as_it_ends() {
    let mut child = StdCommand::new(bin())
        .args(["demo", "--json", "--policy", "noop", "--episodes", "1000000"])
        .stdout(Stdio::piped())
        .stderr(Stdio::null())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    let (tx, rx) = std::sync::mpsc::channel();
    std::thread::spawn(move || {
        let mut line = String::new();
        let _ = BufReader::new(stdout).read_line(&mut line);
        let _ = tx.send(line);
    });
    let first = rx.recv_timeout(Duration::from_secs(30));
    child.kill().unwrap();
    child.wait().unwrap();
    let first = first.expect("no episode line within 30 s");
    let v: serde_json::Value = serde_json::from_str(&first).unwrap();
    assert_eq!(v["episode"], 0);
}

#[test]
fn a_closed_standard_output_ends_quietly() {
    let mut child = StdCommand::new(bin())
        .args(["demo", "--json", "--policy", "noop", "--episodes", "1000000"])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let stdout = child.stdout.take().unwrap();
    // Read one line and close the pipe, as `| head -1` does.
    let reader = std::thread::spawn(move || {
        let mut line = String::new();
        let _ = BufReader::new(stdout).read_line(&mut line);
    });
    let deadline = Instant::now() + Duration::from_secs(60);
    while child.try_wait().unwrap().is_none() && Instant::now() < deadline {
        std::thread::sleep(Duration::from_millis(20));
    }
    let _ = child.kill();
    let status = child.wait().unwrap();
    reader.join().unwrap();
    let mut err = String::new();
    child.stderr.take().unwrap().read_to_string(&mut err).unwrap();
    assert_eq!(status.code(), Some(141), "{err}");
    assert_eq!(err, "");
}

#[test]
fn a_full_standard_output_is_a_one_line_error() {
    if !Path::new("/dev/full").exists() {
        return;
    }
    for args in [
        &["demo", "--json", "--policy", "noop"][..],
        &["bench", "--seconds", "0.01", "--runs", "1", "--scenario", "features"],
    ] {
        let out =
            StdCommand::new(bin()).args(args).stdout(std::fs::File::create("/dev/full").unwrap()).output().unwrap();
        let err = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(1), "{args:?}: {err}");
        assert_eq!(err.lines().count(), 1, "{args:?}: {err}");
        assert!(err.contains("cannot write to standard output"), "{args:?}: {err}");
    }
    let out = StdCommand::new(bin())
        .args(["demo", "--help"])
        .stdout(std::fs::File::create("/dev/full").unwrap())
        .output()
        .unwrap();
    assert_ne!(out.status.code(), Some(101), "{}", String::from_utf8_lossy(&out.stderr));
}

#[test]
fn an_episode_that_cannot_end_is_stopped_at_the_step_cap() {
    let dir = tempfile::tempdir().unwrap();
    cs().current_dir(dir.path())
        .env("CHOPPERSCAPE_STEP_CAP", "5000")
        .args(["record", "--max-episode-steps", "none", "--save-actions", "a.json"])
        .args(ENDLESS)
        .assert()
        .code(1)
        .stderr(
            predicate::str::contains("did not end within 5000 steps")
                .and(predicate::str::contains("--max-episode-steps N")),
        );
    assert_eq!(names(dir.path()), Vec::<String>::new());
}

#[cfg(unix)]
#[test]
fn replay_of_an_endless_file_stops_at_the_size_limit() {
    // Under a 2 GB address-space limit: reading /dev/zero whole would fail there, not eat the machine.
    let out = StdCommand::new("sh")
        .arg("-c")
        .arg("ulimit -v 2000000 && exec \"$0\" replay /dev/zero")
        .arg(bin())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{err}");
    assert!(err.contains("/dev/zero is larger than 64 MiB"), "{err}");
}

#[test]
fn bench_refuses_durations_it_cannot_measure() {
    for bad in ["1e-300", "0.001", "NaN", "inf", "-1", "601"] {
        cs().args(["bench", "--seconds", bad])
            .assert()
            .code(2)
            .stderr(predicate::str::contains("[0.01, 600]").and(predicate::str::contains(bad)));
    }
}

#[test]
fn negative_numbers_are_named_as_invalid_values() {
    for (args, needle) in [
        (&["demo", "--lives", "-1"][..], "1..=1000"),
        (&["demo", "--aliens", "-0.5"], "[0, 1]"),
        (&["demo", "--seed", "-1"], "0..=18446744073709551615"),
        (&["demo", "--episodes", "-2"], "1..="),
        (&["bench", "--runs", "-1"], "1..="),
        (&["web", "--port", "-1"], "0..=65535"),
    ] {
        let out = cs().args(args).assert().code(2).get_output().stderr.clone();
        let err = String::from_utf8_lossy(&out);
        assert!(err.contains("invalid value") && err.contains(needle), "{args:?}: {err}");
        assert!(!err.contains("unexpected argument"), "{args:?}: {err}");
    }
}

fn log_with_actions(actions: &str) -> String {
    format!(
        r#"{{"format": "chopperscape-actions", "version": 1, "env": "ChopperScape-v0", "seed": 0,
        "options": {{}}, "steps": 3, "return": 3, "cause": null, "actions": {actions}}}"#
    )
}

#[test]
fn action_logs_say_what_is_wrong_and_a_byte_order_mark_is_fine() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("ep.json");
    for (actions, needle) in [
        (r#"{"a": 1}"#, "`actions` as a string of the digits 0..=4 or an array of the integers 0..=4"),
        ("[3, 3, 7]", "action 2 is 7"),
        (r#"[3, "x", 4]"#, "action 1 as an integer 0..=4"),
        (r#""339""#, "action 2 is '9'"),
    ] {
        std::fs::write(&log, log_with_actions(actions)).unwrap();
        let out = cs().arg("replay").arg(&log).assert().code(1).get_output().stderr.clone();
        let err = String::from_utf8_lossy(&out);
        assert!(err.contains(needle) && !err.contains("untagged"), "{actions}: {err}");
    }
    std::fs::write(&log, log_with_actions("[3, 3, 4]").replace("\"seed\": 0", "\"seed\": -4")).unwrap();
    cs().arg("replay").arg(&log).assert().code(1).stderr(predicate::str::contains("`seed` is -4"));

    let recorded = dir.path().join("rec.json");
    cs().args(["record", "--policy", "heuristic", "--max-episode-steps", "20", "--save-actions"])
        .arg(&recorded)
        .assert()
        .success();
    let mut with_bom = b"\xEF\xBB\xBF".to_vec();
    with_bom.extend(std::fs::read(&recorded).unwrap());
    std::fs::write(&log, with_bom).unwrap();
    cs().arg("replay").arg(&log).assert().success().stdout(predicate::str::contains("reproduces"));
}

#[cfg(unix)]
#[test]
fn ffmpegs_own_words_are_kept_when_it_stops() {
    use std::os::unix::fs::PermissionsExt;
    let dir = tempfile::tempdir().unwrap();
    let fake = dir.path().join("ffmpeg");
    std::fs::write(&fake, "#!/bin/sh\necho \"Unknown encoder 'libx264'\" >&2\nexit 1\n").unwrap();
    std::fs::set_permissions(&fake, std::fs::Permissions::from_mode(0o755)).unwrap();
    let path = format!("{}:{}", dir.path().display(), std::env::var("PATH").unwrap_or_default());
    cs().current_dir(dir.path())
        .env("PATH", path)
        .args(["record", "--policy", "noop", "--max-episode-steps", "30", "--out", "run.mp4"])
        .assert()
        .code(1)
        .stderr(
            predicate::str::contains("run.mp4")
                .and(predicate::str::contains("ffmpeg stopped reading frames"))
                .and(predicate::str::contains("Unknown encoder 'libx264'")),
        );
    assert_eq!(names(dir.path()), ["ffmpeg"]);
}

#[cfg(unix)]
#[test]
fn a_full_disk_names_the_file_it_could_not_write() {
    // A file-size limit stands in for a full disk: writes past it fail (with SIGXFSZ ignored, as EFBIG).
    for out in ["big.gif", "big.png"] {
        let dir = tempfile::tempdir().unwrap();
        let run = StdCommand::new("sh")
            .current_dir(dir.path())
            .arg("-c")
            .arg(format!("trap '' XFSZ; ulimit -f 64 && exec \"$0\" record --policy heuristic --max-episode-steps 200 --out {out}"))
            .arg(bin())
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&run.stderr);
        assert_eq!(run.status.code(), Some(1), "{err}");
        assert!(err.contains(&format!("cannot write {out}")), "{err}");
        assert_eq!(names(dir.path()), Vec::<String>::new(), "{err}");
    }
}

#[test]
fn dataset_refuses_policy_flags_with_action_logs_before_running_python() {
    let dir = tempfile::tempdir().unwrap();
    let log = dir.path().join("a.json");
    std::fs::write(&log, "{}").unwrap();
    for flags in [["--policy", "random"], ["--episodes", "3"], ["--seed", "4"]] {
        cs().args(["dataset", "--out", "cs/x-v0", "--from-logs"])
            .arg(&log)
            .args(flags)
            .env("CHOPPERSCAPE_PYTHON", "/nonexistent/python")
            .assert()
            .code(2)
            .stderr(predicate::str::contains("cannot be used with"));
    }
}
