//! `chopperscape train`: a short run into Python's run folder whose model the other commands play, the refusals
//! (exit 2), Ctrl-C (saved, exit 130) and `--resume`.

mod common;

use std::process::Command;
use std::time::{Duration, Instant};

use common::{bin, cs};

/// A small batch, so that a debug build runs a few updates in seconds.
const SMALL: &[&str] = &["--num-envs", "8", "--num-steps", "64"];

fn rows(dir: &std::path::Path) -> Vec<String> {
    std::fs::read_to_string(dir.join("progress.csv")).unwrap_or_default().lines().skip(1).map(String::from).collect()
}

#[test]
fn a_short_run_writes_the_run_folder_and_its_model_plays() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let done = cs().args(["train", "--seed", "3", "--steps", "3000", "--out"]).arg(&out).args(SMALL).assert().success();
    let line: serde_json::Value = serde_json::from_slice(&done.get_output().stdout).unwrap();
    assert_eq!(line["model"], out.join("model.onnx").to_str().unwrap());
    for f in ["model.onnx", "progress.csv", "recipe.json", "resume.json"] {
        assert!(out.join(f).is_file(), "{f}");
    }
    let csv = std::fs::read_to_string(out.join("progress.csv")).unwrap();
    assert!(csv.starts_with("env_steps,wall_s,episodes,mean_return,std_return,mean_length,learning_rate,"));
    let rows = rows(&out);
    assert_eq!(rows.len(), 6, "3000 decisions in updates of 512: {csv}");
    let recipe: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("recipe.json")).unwrap()).unwrap();
    assert_eq!((recipe["seed"].as_u64(), recipe["gamma"].as_f64()), (Some(3), Some(0.998)));
    assert_eq!(recipe["env_options"]["frame_skip"], 4);
    cs().args(["demo", "--episodes", "1", "--json", "--policy"]).arg(out.join("model.onnx")).assert().success();
    // A second run is refused without --force; with it the first is kept aside.
    cs().args(["train", "--steps", "500", "--out"]).arg(&out).args(SMALL).assert().code(2);
    cs().args(["train", "--steps", "500", "--force", "--out"]).arg(&out).args(SMALL).assert().success();
    assert!(out.join("replaced-1/model.onnx").is_file());
}

#[test]
fn bad_flags_exit_2() {
    let dir = tempfile::tempdir().unwrap();
    for bad in [&["--preset", "pixels"][..], &["--steps", "0"], &["--minutes", "-1"], &["--resume"], &["--bogus"]] {
        cs().arg("train").args(bad).arg("--out").arg(dir.path()).assert().code(2);
    }
}

#[cfg(unix)]
#[test]
fn ctrl_c_saves_and_resume_goes_on() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    let mut child = Command::new(bin())
        .args(["train", "--steps", "1000000", "--out"])
        .arg(&out)
        .args(SMALL)
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::null())
        .spawn()
        .unwrap();
    let start = Instant::now();
    while rows(&out).len() < 2 {
        assert!(start.elapsed() < Duration::from_secs(120), "no progress");
        std::thread::sleep(Duration::from_millis(50));
    }
    // SAFETY: the child is ours and alive.
    unsafe { libc::kill(child.id() as i32, libc::SIGINT) };
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    let state: serde_json::Value = serde_json::from_slice(&std::fs::read(out.join("resume.json")).unwrap()).unwrap();
    let saved = state["env_steps"].as_u64().unwrap();
    assert!(out.join("model.onnx").is_file() && saved > 0);
    let before = rows(&out).len();
    cs().args(["train", "--resume", "--steps"])
        .arg((saved + 1000).to_string())
        .arg("--out")
        .arg(&out)
        .assert()
        .success();
    let after = rows(&out);
    assert!(after.len() > before, "{before} rows, then {}", after.len());
    let steps: Vec<u64> = after.iter().map(|r| r.split(',').next().unwrap().parse().unwrap()).collect();
    assert!(steps.windows(2).all(|w| w[0] < w[1]), "{steps:?}");
}

#[test]
fn a_run_folder_of_an_earlier_version_resumes_with_the_new_column_blank() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("run");
    cs().args(["train", "--steps", "1000", "--out"]).arg(&out).args(SMALL).assert().success();
    // Its CSV as versions before `recon_loss` wrote it: one column fewer.
    let csv = std::fs::read_to_string(out.join("progress.csv")).unwrap();
    let older: Vec<String> = csv.lines().map(|l| l.rsplit_once(',').unwrap().0.to_string()).collect();
    assert!(older[0].ends_with(",aux_loss,teacher_kl"));
    std::fs::write(out.join("progress.csv"), older.join("\n") + "\n").unwrap();
    cs().args(["train", "--resume", "--steps", "2000", "--out"]).arg(&out).assert().success();
    let csv = std::fs::read_to_string(out.join("progress.csv")).unwrap();
    let lines: Vec<&str> = csv.lines().collect();
    assert!(lines[0].ends_with(",aux_loss,teacher_kl,recon_loss"));
    assert_eq!(lines.len(), 5, "2000 decisions in updates of 512, the first two kept: {csv}");
    assert_eq!(lines[1], format!("{},", older[1]));
    // Any other header is still refused.
    std::fs::write(out.join("progress.csv"), "env_steps,wall_s\n").unwrap();
    cs().args(["train", "--resume", "--steps", "3000", "--out"]).arg(&out).assert().code(2);
}
