//! `--policy FILE.onnx`: a trained policy (from `python -m chopperscape.learn.export`) in `demo` and `record`.
//! (`python/tests/test_export.py` checks its episodes against `python -m chopperscape.learn.evaluate` on the `.pt`.)

use std::path::Path;

use assert_cmd::Command;
use predicates::prelude::*;
use serde_json::Value;

const FEATURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/ppo-features.onnx");
const PIXELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../policy/tests/data/pixels-untrained.onnx");

fn cs() -> Command {
    Command::cargo_bin("chopperscape").unwrap()
}

#[test]
fn record_policy_writes_the_gif_and_an_action_log_that_replays() {
    let dir = tempfile::tempdir().unwrap();
    let (gif, log) = (dir.path().join("agent.gif"), dir.path().join("agent.json"));
    cs().args(["record", "--policy", FEATURES, "--seed", "3", "--max-episode-steps", "120", "--bird-prob", "0.05"])
        .arg("--out")
        .arg(&gif)
        .arg("--save-actions")
        .arg(&log)
        .assert()
        .success()
        .stderr(predicate::str::contains("was trained with bird_prob 0.01; it plays with bird_prob 0.05"));
    assert!(gif.metadata().unwrap().len() > 1000);
    let saved: Value = serde_json::from_str(&std::fs::read_to_string(&log).unwrap()).unwrap();
    assert_eq!(saved["policy"].as_str().unwrap(), FEATURES);
    let replayed = cs().arg("replay").arg(&log).arg("--json").assert().success().get_output().stdout.clone();
    let replayed: Value = serde_json::from_slice(&replayed).unwrap();
    assert_eq!(replayed["return"], saved["return"]);
}

#[test]
fn demo_plays_a_pixel_policy_under_its_trained_options() {
    let out = cs()
        .args(["demo", "--policy", PIXELS, "--json", "--episodes", "2", "--max-episode-steps", "5"])
        .assert()
        .success()
        .stderr(predicate::str::contains("warning").not())
        .get_output()
        .stdout
        .clone();
    let lines: Vec<Value> = String::from_utf8(out).unwrap().lines().map(|l| serde_json::from_str(l).unwrap()).collect();
    // frame_skip 4 from the policy's metadata: 5 agent steps of 4 ticks, +1 each.
    assert_eq!(lines.len(), 2);
    assert_eq!((lines[0]["steps"].as_u64(), lines[0]["return"].as_i64()), (Some(5), Some(20)));
}

#[test]
fn a_damaged_or_missing_policy_file_is_refused_before_anything_is_written() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.onnx");
    std::fs::write(&bad, &std::fs::read(FEATURES).unwrap()[..300]).unwrap();
    let gif = dir.path().join("a.gif");
    for (path, message) in [(bad.as_path(), "not a ChopperScape policy"), (Path::new("none/x.onnx"), "cannot read")] {
        cs().args(["record", "--policy"])
            .arg(path)
            .arg("--out")
            .arg(&gif)
            .assert()
            .code(2)
            .stderr(predicate::str::contains(message).and(predicate::str::contains("panicked").not()));
        assert!(!gif.exists());
    }
    cs().args(["demo", "--policy", "nonsense", "--json"])
        .assert()
        .code(2)
        .stderr(predicate::str::contains("an exported policy file (NAME.onnx"));
}
