//! What a trained policy costs per step, single-threaded: the greedy action from one observation (tract), and
//! an env step with it, for the recipe's features MLP (`models/ppo-features.onnx`) and the pixel recipe's CNN
//! (84 × 84 × 4 grayscale, `tests/data/pixels-untrained.onnx`, untrained: the cost does not depend on the weights).
//!
//! Run: `cargo bench -p chopperscape-policy --bench act`.

use chopperscape::{ChopperScape, Env, Observation};
use chopperscape_policy::Policy;
use divan::{Bencher, black_box};

fn main() {
    divan::main();
}

const FEATURES: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../../models/ppo-features.onnx");
const PIXELS: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/tests/data/pixels-untrained.onnx");

/// A policy, an env with its options, and an observation met early in seed 0.
fn setup(path: &str) -> (Policy, ChopperScape, Observation) {
    let policy = Policy::load(path).unwrap();
    let mut env = ChopperScape::new(policy.config().unwrap()).unwrap();
    let (obs, _) = env.reset(Some(0));
    (policy, env, obs)
}

fn act(bencher: Bencher, path: &str) {
    let (mut policy, _, obs) = setup(path);
    bencher.bench_local(|| black_box(policy.act(black_box(&obs)).unwrap()));
}

/// One agent step: the action from the observation, then the env's step (reset when the episode ends).
fn step(bencher: Bencher, path: &str) {
    let (mut policy, mut env, mut obs) = setup(path);
    bencher.bench_local(|| {
        let s = env.step(policy.act(&obs).unwrap() as i64).unwrap();
        obs = if s.terminated || s.truncated { env.reset(None).0 } else { s.observation };
    });
}

#[divan::bench]
fn act_features_mlp(bencher: Bencher) {
    act(bencher, FEATURES);
}

#[divan::bench]
fn act_pixels_cnn(bencher: Bencher) {
    act(bencher, PIXELS);
}

#[divan::bench]
fn step_features_mlp(bencher: Bencher) {
    step(bencher, FEATURES);
}

#[divan::bench]
fn step_pixels_cnn(bencher: Bencher) {
    step(bencher, PIXELS);
}
