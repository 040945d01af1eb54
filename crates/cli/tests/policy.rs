//! `--policy FILE.onnx`: a trained policy (from `python -m chopperscape.learn.export`) in `demo` and `record`.
//! (`python/tests/test_export.py` checks its episodes against `python -m chopperscape.learn.evaluate` on the `.pt`.)

use std::path::Path;

use predicates::prelude::*;
use prost::Message;
use serde_json::Value;
use tract_onnx::pb::{AttributeProto, ModelProto, NodeProto, TensorProto};

mod common;
use common::cs;

const FEATURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/ppo-features.onnx");
const PIXELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../policy/tests/data/pixels-untrained.onnx");

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

/// The committed policy's metadata around `nodes` (from `obs`, [1, 46], to `logits`) and `initializer`.
fn hostile(nodes: Vec<NodeProto>, initializer: Vec<TensorProto>) -> Vec<u8> {
    let mut m = ModelProto::decode(&*std::fs::read(FEATURES).unwrap()).unwrap();
    let g = m.graph.as_mut().unwrap();
    g.node = nodes;
    g.initializer = initializer;
    m.encode_to_vec()
}

fn node(op: &str, inputs: &[&str], output: &str, attribute: Vec<AttributeProto>) -> NodeProto {
    NodeProto {
        op_type: op.into(),
        input: inputs.iter().map(|s| s.to_string()).collect(),
        output: vec![output.into()],
        attribute,
        ..Default::default()
    }
}

fn int64s(name: &str, values: &[i64]) -> TensorProto {
    TensorProto {
        name: name.into(),
        dims: vec![values.len() as i64],
        data_type: 7,
        int64_data: values.to_vec(),
        ..Default::default()
    }
}

#[test]
fn hostile_policy_files_exit_2_with_one_line_naming_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let pads = AttributeProto { name: "pads".into(), r#type: 7, ints: vec![i64::MAX, i64::MAX], ..Default::default() };
    let weight = TensorProto {
        name: "w".into(),
        dims: vec![1, 1, 1],
        data_type: 1,
        float_data: vec![1.0],
        ..Default::default()
    };
    let relu_chain: Vec<NodeProto> = (0..4000)
        .map(|i| {
            let input = if i == 0 { "obs".to_string() } else { format!("r{}", i - 1) };
            let output = if i == 3999 { "logits".to_string() } else { format!("r{i}") };
            node("Relu", &[&input], &output, vec![])
        })
        .collect();
    let axis = AttributeProto { name: "axis".into(), r#type: 2, ..Default::default() };
    let files = [
        // A `Conv` padded by 2^63 − 1: `demo` hung.
        (
            "pads.onnx",
            hostile(
                vec![
                    node("Reshape", &["obs", "shape"], "x", vec![]),
                    node("Conv", &["x", "w"], "y", vec![pads]),
                    node("Flatten", &["y"], "logits", vec![]),
                ],
                vec![weight, int64s("shape", &[1, 1, 46])],
            ),
            "has pads = [9223372036854775807, 9223372036854775807]",
        ),
        // 4,000 nodes: tract took half a minute.
        ("chain.onnx", hostile(relu_chain, vec![]), "the graph has 4000 nodes"),
        // tract indexes out of bounds: its panic printed its text and a backtrace.
        (
            "panics.onnx",
            hostile(
                vec![node("Gather", &["c", "i"], "g", vec![axis]), node("Add", &["obs", "g"], "logits", vec![])],
                vec![
                    TensorProto {
                        name: "c".into(),
                        dims: vec![2],
                        data_type: 1,
                        float_data: vec![1.0, 2.0],
                        ..Default::default()
                    },
                    int64s("i", &[1000]),
                ],
            ),
            "the inference engine failed (index out of bounds",
        ),
    ];
    // Constants broadcast onto six axes: 40^6 values (16 GB) that tract computed while loading (an abort).
    let mut nodes = vec![];
    let mut consts = vec![TensorProto {
        name: "c".into(),
        dims: vec![40],
        data_type: 1,
        float_data: vec![1.0; 40],
        ..Default::default()
    }];
    for axis in 0..6 {
        let mut shape = vec![1i64; 6];
        shape[axis] = 40;
        consts.push(int64s(&format!("s{axis}"), &shape));
        nodes.push(node("Reshape", &["c", &format!("s{axis}")], &format!("r{axis}"), vec![]));
    }
    nodes.push(node("Add", &["r0", "r1"], "b1", vec![]));
    for i in 2..6 {
        nodes.push(node("Add", &[&format!("b{}", i - 1), &format!("r{i}")], &format!("b{i}"), vec![]));
    }
    nodes.push(node("Add", &["obs", "b5"], "logits", vec![]));
    // rgb_float 4096 × 4096 stacked 4 deep in the metadata: 1.9 GB allocated before it was refused.
    let mut huge = ModelProto::decode(&*std::fs::read(FEATURES).unwrap()).unwrap();
    for (key, value) in [
        ("obs_type", "rgb_float"),
        ("obs_shape", "[84, 84, 3]"),
        ("env_options", r#"{"obs_size": [4096, 4096], "frame_stack": 4}"#),
    ] {
        huge.metadata_props.iter_mut().find(|e| e.key == key).unwrap().value = value.into();
    }
    let files = files.into_iter().chain([
        ("broadcast.onnx", hostile(nodes, consts), "its constants make values of more than 67108864 elements"),
        ("huge.onnx", huge.encode_to_vec(), "give rgb_float observations of 201326592 elements"),
    ]);
    for (name, bytes, message) in files {
        let path = dir.path().join(name);
        std::fs::write(&path, bytes).unwrap();
        let start = std::time::Instant::now();
        let out = cs()
            .args(["demo", "--policy"])
            .arg(&path)
            .env("RUST_BACKTRACE", "1")
            .timeout(std::time::Duration::from_secs(60))
            .assert()
            .code(2)
            .get_output()
            .clone();
        let stderr = String::from_utf8(out.stderr).unwrap();
        assert_eq!(stderr.lines().count(), 1, "{name}: {stderr}");
        assert!(
            stderr.contains(&format!("--policy {}: ", path.display())) && stderr.contains(message),
            "{name}: {stderr}"
        );
        assert!(!stderr.contains("panicked") && out.stdout.is_empty(), "{name}: {stderr}");
        eprintln!("{name}: refused in {:?}: {stderr}", start.elapsed());
    }
}
