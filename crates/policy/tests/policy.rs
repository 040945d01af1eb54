//! Loading and running exported policies: the committed `models/ppo-features.onnx` and a pixel CNN fixture.
//!
//! Fixtures (`tests/data/`), from the repository root with the package and torch installed:
//! - `pixels-untrained.onnx`: the pixel recipe's CNN (84 × 84 × 4 grayscale, frame_skip 4), untrained (torch
//!   seed 0), exported by `chopperscape.learn.export` (see `python/tests/test_export.py::make_pixel_model`).
//! - `ppo-features.logits.json`: 64 observations met by `models/ppo-features.pt` playing (seeds 5..13), and
//!   torch's logits for them: `policyfile.record_observations(...)` and
//!   `agent.actor(torch.from_numpy(norm(obs)))`.

use chopperscape::{ChopperScape, Config, Env, ObsData, ObsType, Observation};
use chopperscape_policy::{MAX_POLICY_BYTES, Policy, PolicyError, argmax};

const FEATURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/ppo-features.onnx");
const PIXELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/pixels-untrained.onnx");
const LOGITS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/ppo-features.logits.json");

#[test]
fn the_committed_policy_reads_its_metadata() {
    let policy = Policy::load(FEATURES).unwrap();
    let meta = policy.metadata();
    assert_eq!((meta.obs_type, meta.obs_shape.as_slice()), (ObsType::Features, &[46][..]));
    assert_eq!(meta.source_sha256.len(), 64);
    assert_eq!(policy.config().unwrap(), Config::features());
}

#[test]
fn logits_equal_torchs_within_1e_5() {
    let fixture: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(LOGITS).unwrap()).unwrap();
    let rows = |key: &str| -> Vec<Vec<f32>> { serde_json::from_value(fixture[key].clone()).unwrap() };
    let (obs, expected) = (rows("obs"), rows("logits"));
    assert_eq!(obs.len(), 64);
    let mut policy = Policy::load(FEATURES).unwrap();
    for (o, want) in obs.into_iter().zip(expected) {
        let got = policy.logits(&Observation { shape: vec![46], data: ObsData::F32(o) }).unwrap();
        for (g, w) in got.iter().zip(&want) {
            assert!((g - w).abs() <= 1e-5, "{got:?} != {want:?}");
        }
    }
}

#[test]
fn a_features_policy_plays_an_episode_to_its_end() {
    let mut policy = Policy::load(FEATURES).unwrap();
    let config = Config { max_episode_steps: Some(300), ..policy.config().unwrap() };
    policy.check(&config).unwrap();
    let mut env = ChopperScape::new(config).unwrap();
    let (mut obs, _) = env.reset(Some(0));
    let mut steps = 0;
    loop {
        let step = env.step(policy.act(&obs).unwrap() as i64).unwrap();
        steps += 1;
        if step.terminated || step.truncated {
            break;
        }
        obs = step.observation;
    }
    // The trained policy survives the first 300 steps of seed 0.
    assert_eq!(steps, 300);
}

#[test]
fn a_pixel_policy_takes_the_envs_frames() {
    let mut policy = Policy::load(PIXELS).unwrap();
    let config = policy.config().unwrap();
    assert_eq!(
        (config.obs_type, config.obs_size, config.frame_stack, config.frame_skip),
        (ObsType::Grayscale, (84, 84), 4, 4)
    );
    policy.check(&config).unwrap();
    let mut env = ChopperScape::new(config).unwrap();
    let (obs, _) = env.reset(Some(1));
    let logits = policy.logits(&obs).unwrap();
    assert!(logits.iter().all(|l| l.is_finite()));
    assert_eq!(policy.act(&obs).unwrap().index(), argmax(&logits));
}

#[test]
fn an_env_that_gives_other_observations_is_refused_naming_both() {
    let policy = Policy::load(FEATURES).unwrap();
    let err = policy.check(&Config { frame_stack: 2, ..Config::features() }).unwrap_err().to_string();
    assert!(err.contains("float32 [46]") && err.contains("float32 [92]") && err.contains("frame_stack 2"), "{err}");
    let pixels = Policy::load(PIXELS).unwrap();
    let err = pixels.check(&Config::features()).unwrap_err().to_string();
    assert!(err.contains("grayscale uint8 [84, 84, 4]") && err.contains("features float32 [46]"), "{err}");
    let mut features = Policy::load(FEATURES).unwrap();
    let wrong = Observation::zeros(vec![84, 84, 4], chopperscape::Dtype::U8);
    assert!(matches!(features.logits(&wrong), Err(PolicyError::Mismatch { .. })));
}

#[test]
fn damaged_and_foreign_files_are_errors_not_panics() {
    let bytes = std::fs::read(FEATURES).unwrap();
    for cut in [0, 1, 10, 100, 1000, bytes.len() / 2, bytes.len() - 1] {
        assert!(Policy::from_bytes(&bytes[..cut]).is_err(), "{cut} bytes");
    }
    // Every byte flipped in turn over the header and the graph (the weights' bytes are any floats), and
    // pseudo-random garbage: loading either works or says why.
    for i in (0..bytes.len().min(4096)).step_by(31) {
        let mut b = bytes.clone();
        b[i] ^= 0xa5;
        let _ = Policy::from_bytes(&b);
    }
    let mut x = 0x9e37_79b9_7f4a_7c15u64;
    let garbage: Vec<u8> = (0..5000)
        .map(|_| {
            x ^= x << 13;
            x ^= x >> 7;
            x ^= x << 17;
            x as u8
        })
        .collect();
    let err = Policy::from_bytes(&garbage).unwrap_err().to_string();
    assert!(err.contains("not a ChopperScape policy"), "{err}");
    let err = Policy::load("/nonexistent/policy.onnx").unwrap_err().to_string();
    assert!(err.contains("cannot read /nonexistent/policy.onnx"), "{err}");
    let big = vec![0u8; MAX_POLICY_BYTES as usize + 1];
    assert!(matches!(Policy::from_bytes(&big), Err(PolicyError::TooLarge { .. })));
}

/// Only a regular file is read as a policy: a device, a folder or a named pipe is named as what it is, at once (a
/// FIFO with no writer would block the open; `/dev/zero` used to be "0 bytes, more than 64 MiB").
#[cfg(unix)]
#[test]
fn a_device_a_folder_or_a_pipe_is_named_as_what_it_is() {
    let dir = std::env::temp_dir().join(format!("chopperscape-policy-kinds-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let fifo = dir.join("pipe.onnx");
    let made = std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success());
    let mut cases = vec![("/dev/zero".into(), "a character device"), (dir.clone(), "a folder")];
    if made {
        cases.push((fifo, "a named pipe"));
    }
    for (path, kind) in cases {
        let started = std::time::Instant::now();
        let err = Policy::load(&path).unwrap_err().to_string();
        assert!(err.contains(&path.display().to_string()) && err.contains(kind), "{}: {err}", path.display());
        assert!(!err.contains("more than"), "{err}");
        assert!(started.elapsed() < std::time::Duration::from_secs(5), "{}", path.display());
    }
    std::fs::remove_dir_all(&dir).unwrap();
}
